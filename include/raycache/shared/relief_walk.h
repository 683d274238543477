/* raycache/shared/relief_walk.h: the CDCT's relief search (thesis Algorithm 4), written once for C++ and GLSL.
 *
 * The ray origin + t d (d unit) is walked from where it leaves the cube's box: at each point Q the texel in
 * direction Q - centre is read and |Q - centre| compared with its stored distance; the first point at or
 * past the stored surface is a crossing, which is bisected (at most RAYCACHE_RELIEF_MAX_HALVINGS times,
 * keeping the crossed end) until the bracket is no longer than epsilon. A crossing already at the box exit
 * means the surface lies inside the box: a hit there, nothing to refine. A miss: an empty or not yet
 * visible texel read on the way, max_steps steps without a crossing, a step too small to move the ray on
 * (t + step == t), a refined crossing more than max_gap behind its texel's surface, or bad input (a
 * direction that is not one, a non-finite origin, a box that cannot be searched, step or epsilon not > 0,
 * max_steps above RAYCACHE_MAX_RELIEF_STEPS: then nothing is read). Reads at most
 * 1 + min(max_steps, RAYCACHE_MAX_RELIEF_STEPS) + RAYCACHE_RELIEF_MAX_HALVINGS texels.
 *
 * The language supplies the texel read (visible texels only). Both drive the same state:
 *     w = raycache_relief_start(origin, direction, centre, half_size, parameters, false);
 *     while (w.status == RAYCACHE_RELIEF_READ) {
 *         read the texel of direction raycache_relief_point(w, w.t) -> (valid, distance, colour);
 *         w = raycache_relief_step(w, valid, distance, colour);
 *     }
 *     raycache_relief_walk_result(w): hit, colour, point, distance, texels read.
 * (raycache::relief_search in C++, raycache_relief_search in GLSL.) A walk of the caller's own between the
 * box exit and the crossing (C++'s over a depth pyramid) starts with caller_walks = true: after a clear box
 * exit the state stops at RAYCACHE_RELIEF_CALLER_WALK, the caller walks on, counting its reads in w.reads,
 * and hands a crossing it found to raycache_relief_bracket(); the same loop then refines it.
 * Products are rounded on their own (never fused into an FMA), so both languages, and C++ built with or
 * without FMA contraction, give the same bits.
 */
#ifndef RAYCACHE_SHARED_RELIEF_WALK_H
#define RAYCACHE_SHARED_RELIEF_WALK_H

#include "raycache/shared/search_parameters.h"

/* status */
#define RAYCACHE_RELIEF_READ 0        /* read the texel at w.t next */
#define RAYCACHE_RELIEF_HIT 1
#define RAYCACHE_RELIEF_MISS 2
#define RAYCACHE_RELIEF_CALLER_WALK 3 /* nothing at the box exit; the caller walks on (caller_walks only) */
/* phase: which read w.t is */
#define RAYCACHE_RELIEF_AT_EXIT 0     /* the box exit */
#define RAYCACHE_RELIEF_LINEAR 1      /* a linear step */
#define RAYCACHE_RELIEF_BISECT 2      /* a bisection of [lo, hi] */

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

struct raycache_relief_walk {
    vec3 origin;
    vec3 d;           /* unit ray direction */
    vec3 centre;      /* the cube's centre */
    float step;
    float epsilon;
    float max_gap;
    int max_steps;
    bool caller_walks;
    int status;       /* RAYCACHE_RELIEF_READ, _HIT, _MISS, _CALLER_WALK */
    int phase;        /* RAYCACHE_RELIEF_AT_EXIT, _LINEAR, _BISECT */
    float t;          /* the point to read next, or the answer's */
    float lo;         /* the last point known before the surface */
    float hi;         /* bisection: the first point known at or past it, and its texel's distance and colour */
    float hi_distance;
    vec3 hi_color;
    vec3 color;       /* the answer's colour (on a hit) */
    int steps;        /* linear steps taken */
    int halvings;     /* bisection reads taken */
    int reads;        /* texels read so far (and pyramid nodes, counted by the caller's walk) */
};

/* The ray's point at t, seen from the cube's centre: (origin + t d) - centre. */
RAYCACHE_FN vec3 raycache_relief_point(raycache_relief_walk w, float t) {
    return raycache_ray_from_centre(w.origin, w.d, t, w.centre);
}

/* True when the ray's point at t lies at or past a surface stored at `distance` from the centre. */
RAYCACHE_FN bool raycache_relief_crosses(raycache_relief_walk w, float t, float distance) {
    return distance <= raycache_length(raycache_relief_point(w, t));
}

/* A walk along origin + t unit(direction) through the cube of box centre +- half_size, reading first where
 * the ray leaves the box; already a miss, with no read, for bad input (see above). */
RAYCACHE_FN raycache_relief_walk raycache_relief_start(vec3 origin, vec3 direction, vec3 centre, float half_size,
                                                       raycache_relief_parameters p, bool caller_walks) {
    bool usable = raycache_is_direction(direction) && raycache_is_finite3(origin) &&
                  raycache_box_is_usable(centre, half_size) && p.step > 0.0f && p.epsilon > 0.0f &&
                  p.max_steps <= RAYCACHE_MAX_RELIEF_STEPS;
    raycache_relief_walk w;
    w.origin = origin;
    w.d = usable ? raycache_unit(direction) : vec3(0.0f, 0.0f, 1.0f);
    w.centre = centre;
    w.step = p.step;
    w.epsilon = p.epsilon;
    w.max_gap = p.max_gap;
    w.max_steps = p.max_steps;
    w.caller_walks = caller_walks;
    w.status = usable ? RAYCACHE_RELIEF_READ : RAYCACHE_RELIEF_MISS;
    w.phase = RAYCACHE_RELIEF_AT_EXIT;
    w.t = usable ? raycache_box_exit_distance(origin, w.d, centre, half_size) : 0.0f;
    w.lo = w.t;
    w.hi = w.t;
    w.hi_distance = 0.0f;
    w.hi_color = vec3(0.0f);
    w.color = vec3(0.0f);
    w.steps = 0;
    w.halvings = 0;
    w.reads = 0;
    return w;
}

/* The next linear step from w.t, or a miss when max_steps are used up or the step no longer moves t. */
RAYCACHE_FN raycache_relief_walk raycache_relief_advance(raycache_relief_walk w) {
    if (w.steps >= w.max_steps) {
        w.status = RAYCACHE_RELIEF_MISS;
        return w;
    }
    w.steps = w.steps + 1;
    w.lo = w.t;
    RAYCACHE_PRECISE float next = w.t + w.step;
    if (!(next > w.t)) {
        w.status = RAYCACHE_RELIEF_MISS;
        return w;
    }
    w.t = next;
    w.status = RAYCACHE_RELIEF_READ;
    return w;
}

/* The bracket [lo, hi] halved once more, or, when it is short enough, the outcome: a hit at hi unless hi
 * lies more than max_gap past its texel's surface. */
RAYCACHE_FN raycache_relief_walk raycache_relief_halve(raycache_relief_walk w) {
    if (w.halvings < RAYCACHE_RELIEF_MAX_HALVINGS && w.hi - w.lo > w.epsilon) {
        RAYCACHE_PRECISE float mid = 0.5f * (w.lo + w.hi);
        w.t = mid;
        w.status = RAYCACHE_RELIEF_READ;
        return w;
    }
    RAYCACHE_PRECISE float gap = raycache_length(raycache_relief_point(w, w.hi)) - w.hi_distance;
    w.status = (gap > w.max_gap) ? RAYCACHE_RELIEF_MISS : RAYCACHE_RELIEF_HIT;
    w.t = w.hi;
    w.color = w.hi_color;
    return w;
}

/* Refines a crossing between lo (before the surface) and hi (at or past it, where a texel at `distance`
 * seeing `color` was read). */
RAYCACHE_FN raycache_relief_walk raycache_relief_bracket(raycache_relief_walk w, float lo, float hi, float distance,
                                                         vec3 color) {
    w.phase = RAYCACHE_RELIEF_BISECT;
    w.lo = lo;
    w.hi = hi;
    w.hi_distance = distance;
    w.hi_color = color;
    w.halvings = 0;
    return raycache_relief_halve(w);
}

/* Takes the texel read at raycache_relief_point(w, w.t): valid (false: empty, a miss), its stored distance
 * from the centre and its colour. Returns the next state: another read at w.t, or the outcome. */
RAYCACHE_FN raycache_relief_walk raycache_relief_step(raycache_relief_walk w, bool valid, float distance, vec3 color) {
    w.reads = w.reads + 1;
    if (!valid) {
        w.status = RAYCACHE_RELIEF_MISS;
        return w;
    }
    bool crossed = raycache_relief_crosses(w, w.t, distance);
    if (w.phase == RAYCACHE_RELIEF_AT_EXIT) {
        if (crossed) { /* the cached surface lies inside the box */
            w.status = RAYCACHE_RELIEF_HIT;
            w.color = color;
            return w;
        }
        if (w.caller_walks) {
            w.status = RAYCACHE_RELIEF_CALLER_WALK;
            return w;
        }
        w.phase = RAYCACHE_RELIEF_LINEAR;
        return raycache_relief_advance(w);
    }
    if (w.phase == RAYCACHE_RELIEF_LINEAR) {
        if (crossed) return raycache_relief_bracket(w, w.lo, w.t, distance, color);
        return raycache_relief_advance(w);
    }
    w.halvings = w.halvings + 1;
    if (crossed) {
        w.hi = w.t;
        w.hi_distance = distance;
        w.hi_color = color;
    } else {
        w.lo = w.t;
    }
    return raycache_relief_halve(w);
}

/* The walk's outcome as a search result. */
RAYCACHE_FN raycache_relief_result raycache_relief_walk_result(raycache_relief_walk w) {
    return raycache_search_result(w.status == RAYCACHE_RELIEF_HIT, w.origin, w.d, w.t, w.color, w.reads);
}

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_RELIEF_WALK_H */
