/* raycache/cdct.glsl: the colour and depth caching technique (CDCT, thesis ch. 4) in GLSL, the same
 * texels and the same searches as raycache::CdctCube, raycache::secant_search and raycache::relief_search
 * (linear walk), bit for bit.
 *
 * Buffers (std430, set RAYCACHE_CDCT_SET = RAYCACHE_SET):
 *   binding RAYCACHE_CDCT_BINDING (2)          uvec2 raycache_cdct_texels[]      what searches read
 *   binding RAYCACHE_CDCT_PENDING_BINDING (3)  uint64_t raycache_cdct_pending[]  this frame's stores
 * A texel is x = RGB9E5 colour, y = float bits of the distance from the cube's centre (C++'s 64-bit
 * word, x low). Stores take the 64-bit atomicMin, so the nearest surface wins, then the smaller colour
 * word, exactly as in C++: the device needs shaderInt64 and shaderBufferInt64Atomics (lavapipe has
 * both); RAYCACHE_READ_ONLY needs neither. Layout, frames and clearing: raycache/shared/gpu_layout.h.
 * Algorithm 1 in a shader:
 *   raycache_relief_result f = raycache_cdct_search(cube, origin, direction, parameters); // as p.search says
 *   if (!f.hit) { trace; then raycache_cdct_store_hit(cube, hit point, colour, parameters),
 *                 or raycache_cdct_store_escape(cube, direction, colour, parameters) }
 */
#ifndef RAYCACHE_CDCT_GLSL
#define RAYCACHE_CDCT_GLSL

#include "raycache/cube.glsl"
#include "raycache/shared/depth_secant.h"

#ifndef RAYCACHE_READ_ONLY
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#endif

#ifndef RAYCACHE_CDCT_SET
#define RAYCACHE_CDCT_SET RAYCACHE_SET
#endif
#ifndef RAYCACHE_CDCT_BINDING
#define RAYCACHE_CDCT_BINDING 2
#endif
#ifndef RAYCACHE_CDCT_PENDING_BINDING
#define RAYCACHE_CDCT_PENDING_BINDING 3
#endif

layout(std430, set = RAYCACHE_CDCT_SET, binding = RAYCACHE_CDCT_BINDING) RAYCACHE_TEXEL_ACCESS buffer raycache_cdct_texel_buffer {
    uvec2 raycache_cdct_texels[];
};
#ifndef RAYCACHE_READ_ONLY
layout(std430, set = RAYCACHE_CDCT_SET, binding = RAYCACHE_CDCT_PENDING_BINDING) buffer raycache_cdct_pending_buffer {
    uint64_t raycache_cdct_pending[];
};
#endif

/* Tuning of the CDCT's searches, raycache::ReliefParameters field for field (so a std430 copy of the
 * C++ struct reads as this one). */
struct raycache_relief_parameters {
    float step;      /* relief: delta, length of a linear step along the ray, world units, > 0 */
    float epsilon;   /* relief: bisection stops when the bracket is shorter than this; secant: accept
                        |f| <= epsilon or a bracket this short; > 0 */
    int max_steps;   /* relief: linear steps before giving up (a miss), at most RAYCACHE_MAX_RELIEF_STEPS */
    float max_depth; /* distance at which rays that escaped to the environment are stored */
    float max_gap;   /* a crossing more than this beyond the cached surface is a miss (infinity: never) */
    int search;      /* what raycache_cdct_search makes: RAYCACHE_DEPTH_SEARCH_SECANT or _RELIEF */
    int max_reads;   /* secant: reads before giving up (a miss), 1..RAYCACHE_SECANT_MAX_READS (clamped) */
};

/* The C++ defaults: step 0.2, epsilon 0.02, 1024 steps, depth 100, no gap limit, the secant search with
 * 8 reads. */
raycache_relief_parameters raycache_default_relief_parameters() {
    return raycache_relief_parameters(0.2, 0.02, 1024, 100.0, RAYCACHE_INFINITY, RAYCACHE_DEPTH_SEARCH_SECANT, 8);
}

/* Outcome of a search, raycache::ReliefResult field for field. On a miss only texels_read is set. */
struct raycache_relief_result {
    bool hit;
    vec3 color;      /* the texel seen at the crossing */
    vec3 point;      /* origin + distance * unit(direction) */
    float distance;  /* along the unit ray direction, within epsilon past the first crossing */
    int texels_read; /* texels sampled, hit or miss */
};

/* An empty CDCT texel, as C++ writes it. */
uvec2 raycache_cdct_invalid_texel() {
    return uvec2(RAYCACHE_CDCT_INVALID_COLOR, RAYCACHE_CDCT_INVALID_DISTANCE);
}

/* True when the cube's box can be searched: finite centre, finite half-size > 0. */
bool raycache_cube_box_is_usable(raycache_gpu_cube cube) {
    return raycache_box_is_usable(cube.centre, cube.half_size);
}

/* The texel that the vector v from the cube's centre points at (empty when none). */
uvec2 raycache_cdct_texel_at(raycache_gpu_cube cube, vec3 v) {
    uint i = raycache_cube_texel(cube, v);
    if (i >= uint(raycache_cdct_texels.length())) return raycache_cdct_invalid_texel();
    return raycache_cdct_texels[i];
}

/* Thesis Algorithm 4 on the cube's depth image, as raycache::relief_search without a pyramid: walk the
 * ray origin + t * unit(direction) from where it leaves the cube's box, in steps of p.step; at each point
 * Q read the texel in direction Q - centre; a crossing (stored distance <= |Q - centre|) is bisected
 * (at most 64 times, keeping the crossed end) down to p.epsilon. A miss: an empty or this-frame texel on
 * the way, p.max_steps used up, a step too small to change t (t + p.step == t), a crossing more than
 * p.max_gap behind the surface, a bad origin, direction, box or parameters (p.max_steps above
 * RAYCACHE_MAX_RELIEF_STEPS among them). Reads at most 1 + p.max_steps + 64 texels. */
raycache_relief_result raycache_relief_search(raycache_gpu_cube cube, vec3 origin, vec3 direction,
                                              raycache_relief_parameters p) {
    raycache_relief_result r;
    r.hit = false;
    r.color = vec3(0.0);
    r.point = vec3(0.0);
    r.distance = 0.0;
    r.texels_read = 0;
    if (!raycache_is_direction(direction) || !raycache_is_finite3(origin) || !raycache_cube_box_is_usable(cube) ||
        !(p.step > 0.0) || !(p.epsilon > 0.0) || p.max_steps > RAYCACHE_MAX_RELIEF_STEPS)
        return r;
    vec3 d = raycache_unit(direction);

    /* The box exit: a crossing there means the cached surface lies inside the box (nothing to refine). */
    precise float t = raycache_box_exit_distance(origin, d, cube.centre, cube.half_size);
    vec3 v = raycache_ray_from_centre(origin, d, t, cube.centre);
    uvec2 texel = raycache_cdct_texel_at(cube, v);
    r.texels_read = 1;
    if (!raycache_cdct_is_valid(texel)) return r;
    bool crossed = raycache_cdct_distance(texel) <= raycache_length(v);

    /* Linear walk to the first crossing, bracketed by [lo, hi]. */
    precise float lo = t;
    precise float hi = t;
    if (!crossed) {
        for (int i = 0; i < p.max_steps && !crossed; ++i) {
            lo = t;
            t = t + p.step;
            if (!(t > lo)) return r; /* the step no longer moves the ray */
            v = raycache_ray_from_centre(origin, d, t, cube.centre);
            texel = raycache_cdct_texel_at(cube, v);
            r.texels_read += 1;
            if (!raycache_cdct_is_valid(texel)) return r;
            crossed = raycache_cdct_distance(texel) <= raycache_length(v);
        }
        if (!crossed) return r;
        hi = t;

        /* Bisection, keeping the crossed end and its texel at hi. */
        uvec2 at_hi = texel;
        for (int k = 0; k < 64 && hi - lo > p.epsilon; ++k) {
            precise float mid = 0.5 * (lo + hi);
            v = raycache_ray_from_centre(origin, d, mid, cube.centre);
            texel = raycache_cdct_texel_at(cube, v);
            r.texels_read += 1;
            if (!raycache_cdct_is_valid(texel)) return r;
            if (raycache_cdct_distance(texel) <= raycache_length(v)) {
                hi = mid;
                at_hi = texel;
            } else {
                lo = mid;
            }
        }
        precise float gap = raycache_length(raycache_ray_from_centre(origin, d, hi, cube.centre)) -
                            raycache_cdct_distance(at_hi);
        if (gap > p.max_gap) return r;
        texel = at_hi;
    }
    r.hit = true;
    r.distance = hi;
    r.point = raycache_ray_point(origin, d, hi);
    r.color = raycache_cdct_color(texel);
    return r;
}

/* The CDCT's cheap search, as raycache::secant_search (raycache/shared/depth_secant.h drives it; this
 * function only reads the texels): from where the ray leaves the box, jump to where the ray reaches the
 * distance read, then refine a bracketed crossing by false position; answer only when the point read lies
 * within p.epsilon of its texel's surface (or a bracket shorter than p.epsilon ends at most p.max_gap
 * behind it). Reads the texels lookups read (visible ones: not this frame's stores). A miss: an empty or
 * this-frame texel, p.max_reads reads without such an answer, a bad origin, direction or box, or
 * p.epsilon not > 0 (then nothing is read). Reads at most min(p.max_reads, RAYCACHE_SECANT_MAX_READS)
 * texels; p.step and p.max_steps are not used. */
raycache_relief_result raycache_cdct_secant_search(raycache_gpu_cube cube, vec3 origin, vec3 direction,
                                                   raycache_relief_parameters p) {
    raycache_secant_search s = raycache_secant_start(origin, direction, cube.centre, cube.half_size, p.epsilon,
                                                     p.max_gap, p.max_reads);
    while (s.status == RAYCACHE_SECANT_READ) {
        uvec2 texel = raycache_cdct_texel_at(cube, raycache_secant_point(s, s.t));
        s = raycache_secant_step(s, raycache_cdct_is_valid(texel), raycache_cdct_distance(texel),
                                 raycache_cdct_color(texel));
    }
    raycache_relief_result r;
    r.hit = s.status == RAYCACHE_SECANT_HIT;
    r.color = r.hit ? s.color : vec3(0.0);
    r.point = r.hit ? raycache_ray_point(origin, s.d, s.t) : vec3(0.0);
    r.distance = r.hit ? s.t : 0.0;
    r.texels_read = s.reads;
    return r;
}

/* The search p.search names, as raycache::depth_search without a pyramid: RAYCACHE_DEPTH_SEARCH_SECANT
 * the secant search, anything else the relief walk. */
raycache_relief_result raycache_cdct_search(raycache_gpu_cube cube, vec3 origin, vec3 direction,
                                            raycache_relief_parameters p) {
    if (p.search == RAYCACHE_DEPTH_SEARCH_SECANT) return raycache_cdct_secant_search(cube, origin, direction, p);
    return raycache_relief_search(cube, origin, direction, p);
}

#ifndef RAYCACHE_READ_ONLY
/* Caches `color` seen at `distance` from the centre in the texel of `key` (CdctCube::store). Refused
 * (false) when key is not a direction, the distance is negative, NaN or infinite, or the texel already
 * holds a value. Among same-frame stores into one texel the smallest 64-bit word wins: the nearest
 * distance, then the smaller colour word. Visible from the next frame. */
bool raycache_cdct_store(raycache_gpu_cube cube, vec3 key, vec3 color, float distance) {
    uint i = raycache_cube_texel(cube, key);
    if (i >= uint(raycache_cdct_texels.length()) || i >= uint(raycache_cdct_pending.length())) return false;
    uint distance_bits = floatBitsToUint(distance); /* tested on the bits: no float compare to fold away */
    if (distance_bits == 0x80000000u) distance_bits = 0u; /* -0 becomes +0 */
    if ((distance_bits & 0x80000000u) != 0u || !raycache_is_finite(distance)) return false;
    if (raycache_cdct_is_valid(raycache_cdct_texels[i])) return false; /* visible: kept */
    uint64_t word = packUint2x32(uvec2(raycache_pack_rgb9e5(color), distance_bits));
    return atomicMin(raycache_cdct_pending[i], word) > word;
}

/* Stores what a traced ray hit at hit_point: key hit_point - centre, distance |hit_point - centre|
 * clamped to p.max_depth (raycache::store_hit). Refused for a bad point or box, or as raycache_cdct_store. */
bool raycache_cdct_store_hit(raycache_gpu_cube cube, vec3 hit_point, vec3 color, raycache_relief_parameters p) {
    if (!raycache_is_finite3(hit_point) || !raycache_cube_box_is_usable(cube)) return false;
    precise vec3 from_centre = hit_point - cube.centre;
    float length = raycache_length(from_centre);
    return raycache_cdct_store(cube, from_centre, color, (p.max_depth < length) ? p.max_depth : length);
}

/* Stores the colour of a ray that escaped to the environment in `direction`, at p.max_depth
 * (raycache::store_escape). */
bool raycache_cdct_store_escape(raycache_gpu_cube cube, vec3 direction, vec3 color, raycache_relief_parameters p) {
    return raycache_cdct_store(cube, direction, color, p.max_depth);
}
#endif

#ifdef RAYCACHE_END_FRAME
/* End of frame for one element of the buffers (call for every element, 0 .. length - 1, in a pass
 * between frames): a pending word moves into an empty texel; the pending word is emptied. */
void raycache_cdct_end_frame(uint element) {
    if (element >= uint(raycache_cdct_texels.length()) || element >= uint(raycache_cdct_pending.length())) return;
    uvec2 pending = unpackUint2x32(raycache_cdct_pending[element]);
    if (raycache_cdct_is_valid(pending) && !raycache_cdct_is_valid(raycache_cdct_texels[element]))
        raycache_cdct_texels[element] = pending;
    raycache_cdct_pending[element] = 0xFFFFFFFFFFFFFFFFul;
}
#endif

#endif /* RAYCACHE_CDCT_GLSL */
