/* raycache/shared/depth_secant.h: the CDCT's cheap search, written once for C++ and GLSL. It finds where a
 * ray meets the surface stored in a depth cube with a handful of texel reads, instead of walking the ray
 * in steps (the thesis's Algorithm 4 reads tens to hundreds of texels, more than the ray it replaces).
 *
 * Along the ray p(t) = start + t d (start = origin - cube centre, d unit), f(t) = |p(t)| - D(p(t)), where
 * D(v) is the distance stored in the texel of direction v: f < 0 before the stored surface, f >= 0 at or
 * past it. From the box exit, each step jumps to where the ray reaches the sphere of the distance just read
 * (exact for a surface at constant distance from the centre: the distance impostor iteration of
 * Szirmay-Kalos et al., Eurographics 2005); once a read lands past the surface the crossing is bracketed
 * and the next points come by false position (Illinois variant). An answer is given only when it is
 * consistent: |f| <= epsilon at the point read, or a bracket narrower than epsilon whose far end lies at
 * most max_gap past its texel's surface. An empty texel, a step that cannot move on, or max_reads reads
 * without such an answer make the search a miss: a doubtful answer is traced, not guessed.
 *
 * The language supplies the texel read (visible texels only). Both drive the same state:
 *     s = raycache_secant_start(origin, direction, centre, half_size, epsilon, max_gap, max_reads);
 *     while (s.status == RAYCACHE_SECANT_READ) {
 *         read the texel of direction raycache_secant_point(s, s.t) -> (valid, distance, colour);
 *         raycache_secant_advance(s, valid, distance, colour);   // s updated in place
 *     }
 *     raycache_secant_result(s, origin): s.status == RAYCACHE_SECANT_HIT when the ray meets the cached
 *     surface at s.t, at the point raycache_ray_point(origin, s.d, s.t), seeing s.color; s.reads texels
 *     were read, hit or miss.
 * (raycache::secant_search in C++, raycache_cdct_secant_search in GLSL.) Products are rounded on their own
 * (never fused into an FMA), so both languages, and C++ built with or without FMA contraction, give the
 * same bits.
 */
#ifndef RAYCACHE_SHARED_DEPTH_SECANT_H
#define RAYCACHE_SHARED_DEPTH_SECANT_H

#include "raycache/shared/search_parameters.h"

#define RAYCACHE_SECANT_READ 0
#define RAYCACHE_SECANT_HIT 1
#define RAYCACHE_SECANT_MISS 2

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

struct raycache_secant_search {
    vec3 start;       /* ray origin - cube centre */
    vec3 d;           /* unit ray direction */
    float epsilon;    /* accept |f| <= epsilon, or a bracket this short */
    float max_gap;    /* a bracket's far end further than this past its surface: a discontinuity, a miss */
    int max_reads;
    int reads;        /* texels read so far */
    int status;       /* RAYCACHE_SECANT_READ (read at t next), _HIT, _MISS */
    float t;          /* the point to read next, or the answer's */
    vec3 color;       /* the answer's colour (on a hit) */
    float lo_t;       /* the last point before the surface, and its f (< 0) */
    float lo_f;
    float hi_t;       /* the first point known past the surface, its f (>= 0; halved by Illinois steps, for the */
    float hi_f;       /* false position only) and colour */
    float hi_gap;     /* that point's f as read: how far past its texel's surface it lies (the max_gap test) */
    vec3 hi_color;
    bool bracketed;   /* hi_* is set */
    int last_side;    /* which end the last read replaced: -1 lo, +1 hi, 0 none (Illinois) */
};

/* a . b with every product rounded on its own. */
RAYCACHE_FN float raycache_dot_no_fma(vec3 a, vec3 b) {
    RAYCACHE_PRECISE float sum = (raycache_no_fma(a.x * b.x) + raycache_no_fma(a.y * b.y)) + raycache_no_fma(a.z * b.z);
    return sum;
}

/* The ray's point at t, from the cube's centre: start + t d. */
RAYCACHE_FN vec3 raycache_secant_point(RAYCACHE_IN(raycache_secant_search) s, float t) {
    RAYCACHE_PRECISE vec3 p = s.start + vec3(raycache_no_fma(t * s.d.x), raycache_no_fma(t * s.d.y), raycache_no_fma(t * s.d.z));
    return p;
}

/* The larger t at which |start + t d| = radius (the ray leaving the sphere of that radius around the
 * centre); 0 when the ray never reaches it going forwards. */
RAYCACHE_FN float raycache_sphere_exit(vec3 start, vec3 d, float radius) {
    float b = raycache_dot_no_fma(start, d);
    RAYCACHE_PRECISE float c = raycache_dot_no_fma(start, start) - raycache_no_fma(radius * radius);
    RAYCACHE_PRECISE float disc = raycache_no_fma(b * b) - c;
    RAYCACHE_PRECISE float t = raycache_sqrt(max(disc, 0.0f)) - b;
    return max(t, 0.0f);
}

/* A search starting at t_start (where the ray leaves the cube's box): the first read is at t_start. */
RAYCACHE_FN raycache_secant_search raycache_secant_begin(vec3 start, vec3 d, float t_start, float epsilon, float max_gap,
                                                         int max_reads) {
    raycache_secant_search s;
    s.start = start;
    s.d = d;
    s.epsilon = epsilon;
    s.max_gap = max_gap;
    s.max_reads = clamp(max_reads, 1, RAYCACHE_SECANT_MAX_READS);
    s.reads = 0;
    s.status = RAYCACHE_SECANT_READ;
    s.t = t_start;
    s.color = vec3(0.0f, 0.0f, 0.0f);
    s.lo_t = t_start;
    s.lo_f = 0.0f;
    s.hi_t = t_start;
    s.hi_f = 0.0f;
    s.hi_gap = 0.0f;
    s.hi_color = vec3(0.0f, 0.0f, 0.0f);
    s.bracketed = false;
    s.last_side = 0;
    return s;
}

/* A search along origin + t unit(direction) through the cube of box centre +- half_size, starting where
 * the ray leaves the box; already a miss, with no read, for a direction that is not one (zero, NaN,
 * infinite), a non-finite origin, a box that cannot be searched or epsilon not > 0. */
RAYCACHE_FN raycache_secant_search raycache_secant_start(vec3 origin, vec3 direction, vec3 centre, float half_size,
                                                         float epsilon, float max_gap, int max_reads) {
    bool usable = raycache_is_direction(direction) && raycache_is_finite3(origin) &&
                  raycache_box_is_usable(centre, half_size) && epsilon > 0.0f;
    vec3 d = usable ? raycache_unit(direction) : vec3(0.0f, 0.0f, 1.0f);
    float t_start = usable ? raycache_box_exit_distance(origin, d, centre, half_size) : 0.0f;
    RAYCACHE_PRECISE vec3 start = origin - centre;
    raycache_secant_search s = raycache_secant_begin(start, d, t_start, epsilon, max_gap, max_reads);
    if (!usable) s.status = RAYCACHE_SECANT_MISS;
    return s;
}

/* Takes the texel read at raycache_secant_point(s, s.t): valid (false: empty, a miss), its stored
 * distance from the centre and its colour. Advances `s` in place to the next state: another read at s.t, or the outcome. */
RAYCACHE_FN void raycache_secant_advance(RAYCACHE_INOUT(raycache_secant_search) s, bool valid, float distance, vec3 color) {
    s.reads = s.reads + 1;
    if (!valid) {
        s.status = RAYCACHE_SECANT_MISS;
        return;
    }
    RAYCACHE_PRECISE float f = raycache_length(raycache_secant_point(s, s.t)) - distance;
    if (abs(f) <= s.epsilon || (s.reads == 1 && f > 0.0f)) {
        /* On the surface; or, at the box exit already past it: the surface lies inside the box. */
        s.status = RAYCACHE_SECANT_HIT;
        s.color = color;
        return;
    }
    if (f < 0.0f) {
        if (s.last_side < 0 && s.bracketed) s.hi_f = raycache_no_fma(0.5f * s.hi_f); /* Illinois: the same end again */
        s.lo_t = s.t;
        s.lo_f = f;
        s.last_side = -1;
    } else {
        if (s.last_side > 0) s.lo_f = raycache_no_fma(0.5f * s.lo_f);
        s.hi_t = s.t;
        s.hi_f = f;
        s.hi_gap = f;
        s.hi_color = color;
        s.bracketed = true;
        s.last_side = 1;
    }
    if (s.bracketed && s.hi_t - s.lo_t <= s.epsilon) {
        /* The crossing lies within epsilon: take the far end unless it is far behind its surface (the ray
         * passed behind an edge, where the cube saw nothing). */
        s.status = (s.hi_gap <= s.max_gap) ? RAYCACHE_SECANT_HIT : RAYCACHE_SECANT_MISS;
        s.t = s.hi_t;
        s.color = s.hi_color;
        return;
    }
    if (s.reads >= s.max_reads) {
        s.status = RAYCACHE_SECANT_MISS;
        return;
    }
    float next;
    if (s.bracketed) {
        /* False position between lo (f < 0) and hi (f >= 0). */
        RAYCACHE_PRECISE float span = s.hi_t - s.lo_t;
        RAYCACHE_PRECISE float f_span = s.hi_f - s.lo_f;
        float fraction = raycache_divide(-s.lo_f, f_span);
        RAYCACHE_PRECISE float step = raycache_no_fma(span * fraction);
        next = s.lo_t + step;
    } else {
        /* Not past the surface yet: to where the ray reaches the distance just read. */
        next = raycache_sphere_exit(s.start, s.d, distance);
    }
    if (!(next > s.lo_t) || (s.bracketed && !(next < s.hi_t))) {
        /* No room to move on (rounding): the bracket, if any, is as short as floats allow. */
        s.status = (s.bracketed && s.hi_gap <= s.max_gap) ? RAYCACHE_SECANT_HIT : RAYCACHE_SECANT_MISS;
        s.t = s.hi_t;
        s.color = s.hi_color;
        return;
    }
    s.t = next;
}

/* The search's outcome as a search result (origin: the ray's origin given to raycache_secant_start). */
RAYCACHE_FN raycache_relief_result raycache_secant_result(RAYCACHE_IN(raycache_secant_search) s, vec3 origin) {
    return raycache_search_result(s.status == RAYCACHE_SECANT_HIT, origin, s.d, s.t, s.color, s.reads);
}

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_DEPTH_SECANT_H */
