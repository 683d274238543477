/* raycache/cdct.glsl: the colour and depth caching technique (CDCT, thesis ch. 4) in GLSL, the same
 * texels and the same searches as raycache::CdctCube, raycache::secant_search and raycache::relief_search
 * (linear walk), bit for bit.
 *
 * Buffers (std430, set RAYCACHE_CDCT_SET = RAYCACHE_SET):
 *   binding RAYCACHE_CDCT_BINDING (2)          uvec2 raycache_cdct_texels[]      what searches read
 *   binding RAYCACHE_CDCT_PENDING_BINDING (3)  uint64_t raycache_cdct_pending[]  this frame's stores
 *   binding RAYCACHE_FRAME_BINDING (4)         uint raycache_frame[]             counters, store list (frame.glsl)
 * With RAYCACHE_CONFIDENCE defined (the confidence test; raycache/shared/gpu_layout.h), also:
 *   binding RAYCACHE_CDCT_DOUBTFUL_BINDING (6) uint raycache_cdct_doubtful[]     a bit per texel: doubtful, reads as empty
 *   binding RAYCACHE_CDCT_CUBES_BINDING (8)    raycache_gpu_cube raycache_cdct_cubes[]  the cube table (end_frame.glsl, mark pass)
 * A texel is x = RGB9E5 colour, y = float bits of the distance from the cube's centre (C++'s 64-bit
 * word, x low). Stores take the 64-bit atomicMin, so the nearest surface wins, then the smaller colour
 * word, exactly as in C++: the device needs shaderInt64 and shaderBufferInt64Atomics (lavapipe has
 * both); RAYCACHE_READ_ONLY needs neither. Layout, frames and clearing: raycache/shared/gpu_layout.h.
 * Algorithm 1 in a shader:
 *   raycache_relief_result f = raycache_cdct_search(cube, origin, direction, parameters); // as p.search says
 *   if (!f.hit) { trace; then raycache_cdct_store_traced(cube, origin, direction, colour, distance, parameters)
 *                 (or raycache_cdct_store_hit / raycache_cdct_store_escape) }
 * Parameters: raycache_relief_parameters (raycache/shared/search_parameters.h, C++'s ReliefParameters byte
 * for byte), raycache_default_relief_parameters() for the defaults.
 */
#ifndef RAYCACHE_CDCT_GLSL
#define RAYCACHE_CDCT_GLSL

#include "raycache/cube.glsl"
#include "raycache/shared/cdct_store.h"
#include "raycache/shared/depth_secant.h"
#include "raycache/shared/relief_walk.h"
#include "raycache/shared/search_parameters.h"

#ifndef RAYCACHE_READ_ONLY
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#endif

#ifndef RAYCACHE_CDCT_SET
#define RAYCACHE_CDCT_SET RAYCACHE_SET
#endif

layout(std430, set = RAYCACHE_CDCT_SET, binding = RAYCACHE_CDCT_BINDING) RAYCACHE_TEXEL_ACCESS buffer raycache_cdct_texel_buffer {
    uvec2 raycache_cdct_texels[];
};
#ifndef RAYCACHE_READ_ONLY
layout(std430, set = RAYCACHE_CDCT_SET, binding = RAYCACHE_CDCT_PENDING_BINDING) buffer raycache_cdct_pending_buffer {
    uint64_t raycache_cdct_pending[];
};
#endif
#ifdef RAYCACHE_CONFIDENCE
layout(std430, set = RAYCACHE_CDCT_SET, binding = RAYCACHE_CDCT_DOUBTFUL_BINDING) RAYCACHE_TEXEL_ACCESS buffer raycache_cdct_doubtful_buffer {
    uint raycache_cdct_doubtful[];
};
#endif
/* True when element's texel is marked doubtful (never without RAYCACHE_CONFIDENCE). */
bool raycache_cdct_is_doubtful(uint element) { return RAYCACHE_IS_DOUBTFUL(raycache_cdct_doubtful, element); }

/* An empty CDCT texel, as C++ writes it. */
uvec2 raycache_cdct_invalid_texel() {
    return uvec2(RAYCACHE_CDCT_INVALID_COLOR, RAYCACHE_CDCT_INVALID_DISTANCE);
}

/* True when the cube's box can be searched: finite centre, finite half-size > 0. */
bool raycache_cube_box_is_usable(raycache_gpu_cube cube) {
    return raycache_box_is_usable(cube.centre, cube.half_size);
}

/* The texel that the vector v from the cube's centre points at (invalid when none, or doubtful: so the
 * searches miss on a doubtful texel as on an empty one); `empty`: the texel holds no value. */
uvec2 raycache_cdct_texel_at(raycache_gpu_cube cube, vec3 v, out bool empty) {
    uint i = raycache_cube_texel(cube, v);
    empty = false;
    if (i >= uint(raycache_cdct_texels.length())) return raycache_cdct_invalid_texel();
    uvec2 texel = raycache_cdct_texels[i];
    empty = !raycache_cdct_is_valid(texel); /* holds no value (a doubtful texel holds one) */
    if (raycache_cdct_is_doubtful(i)) return raycache_cdct_invalid_texel();
    return texel;
}
uvec2 raycache_cdct_texel_at(raycache_gpu_cube cube, vec3 v) {
    bool empty;
    return raycache_cdct_texel_at(cube, v, empty);
}

/* Thesis Algorithm 4 on the cube's depth image, as raycache::relief_search without a pyramid
 * (raycache/shared/relief_walk.h walks; this function only reads the texels): walk the ray
 * origin + t * unit(direction) from where it leaves the cube's box, in steps of p.step; at each point Q read
 * the texel in direction Q - centre; a crossing (stored distance <= |Q - centre|) is bisected (at most 64
 * times, keeping the crossed end) down to p.epsilon. A miss: an empty, this-frame or doubtful texel on the way,
 * p.max_steps used up, a step too small to change t (t + p.step == t), a crossing more than p.max_gap behind
 * the surface, a bad origin, direction, box or parameters (p.max_steps above RAYCACHE_MAX_RELIEF_STEPS among
 * them). Reads at most 1 + p.max_steps + 64 texels. */
raycache_relief_result raycache_relief_search(raycache_gpu_cube cube, vec3 origin, vec3 direction,
                                              raycache_relief_parameters p) {
    raycache_relief_walk w = raycache_relief_start(origin, direction, cube.centre, cube.half_size, p, false);
    bool empty = false; /* the last read's texel held no value: a miss then counts as on an empty texel */
    while (w.status == RAYCACHE_RELIEF_READ) {
        uvec2 texel = raycache_cdct_texel_at(cube, raycache_relief_point(w, w.t), empty);
        w = raycache_relief_step(w, raycache_cdct_is_valid(texel), raycache_cdct_distance(texel),
                                 raycache_cdct_color(texel));
    }
    raycache_relief_result result = raycache_relief_walk_result(w);
    raycache_count_lookup_toward(cube, direction, result.hit);
    if (!result.hit && empty) raycache_count_empty(cube);
    return result;
}

/* The CDCT's cheap search, as raycache::secant_search (raycache/shared/depth_secant.h drives it; this
 * function only reads the texels): from where the ray leaves the box, jump to where the ray reaches the
 * distance read, then refine a bracketed crossing by false position; answer only when the point read lies
 * within p.epsilon of its texel's surface (or a bracket shorter than p.epsilon ends at most p.max_gap
 * behind it). Reads the texels lookups read (visible ones: not this frame's stores). A miss: an empty,
 * this-frame or doubtful texel, p.max_reads reads without such an answer, a bad origin, direction or box, or
 * p.epsilon not > 0 (then nothing is read). Reads at most min(p.max_reads, RAYCACHE_SECANT_MAX_READS)
 * texels; p.step and p.max_steps are not used. */
raycache_relief_result raycache_cdct_secant_search(raycache_gpu_cube cube, vec3 origin, vec3 direction,
                                                   raycache_relief_parameters p) {
    raycache_secant_search s = raycache_secant_start(origin, direction, cube.centre, cube.half_size, p.epsilon,
                                                     p.max_gap, p.max_reads);
    bool empty = false; /* the last read's texel held no value: a miss then counts as on an empty texel */
    while (s.status == RAYCACHE_SECANT_READ) {
        uvec2 texel = raycache_cdct_texel_at(cube, raycache_secant_point(s, s.t), empty);
        raycache_secant_advance(s, raycache_cdct_is_valid(texel), raycache_cdct_distance(texel),
                                raycache_cdct_color(texel));
    }
    raycache_relief_result result = raycache_secant_result(s, origin);
    raycache_count_lookup_toward(cube, direction, result.hit);
    if (!result.hit && empty) raycache_count_empty(cube);
    return result;
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
    uvec2 texel = raycache_cdct_store_texel(color, distance);
    if (i >= uint(raycache_cdct_texels.length()) || i >= uint(raycache_cdct_pending.length()) ||
        !raycache_cdct_is_valid(texel) || raycache_cdct_is_valid(raycache_cdct_texels[i]) /* visible: kept */) {
        raycache_frame_count(cube.index, RAYCACHE_FRAME_REFUSED);
        return false;
    }
    raycache_frame_count(cube.index, RAYCACHE_FRAME_STORES);
    uint64_t word = packUint2x32(texel);
    uint64_t old = atomicMin(raycache_cdct_pending[i], word);
    if (old == 0xFFFFFFFFFFFFFFFFul) raycache_frame_list_append(i | RAYCACHE_FRAME_CDCT_ENTRY);
    return old > word;
}

/* Stores what a traced ray hit at hit_point: key hit_point - centre, distance |hit_point - centre|
 * clamped to p.max_depth (raycache::store_hit). Refused for a bad point or box, or as raycache_cdct_store. */
bool raycache_cdct_store_hit(raycache_gpu_cube cube, vec3 hit_point, vec3 color, raycache_relief_parameters p) {
    raycache_cdct_store_key k = raycache_cdct_hit_store(hit_point, cube.centre, cube.half_size, p.max_depth);
    return raycache_cdct_store(cube, k.key, color, k.distance);
}

/* Stores the colour of a ray that escaped to the environment in `direction`, at p.max_depth
 * (raycache::store_escape). */
bool raycache_cdct_store_escape(raycache_gpu_cube cube, vec3 direction, vec3 color, raycache_relief_parameters p) {
    raycache_cdct_store_key k = raycache_cdct_escape_store(direction, p.max_depth);
    return raycache_cdct_store(cube, k.key, color, k.distance);
}

/* Stores what a ray traced from origin along direction brought back, as raycache::cdct_cached_trace does
 * after a miss: `distance` along the unit direction to its hit (store_hit there), infinity or NaN when it
 * escaped (store_escape); nothing for a negative distance or a direction that is not one. */
bool raycache_cdct_store_traced(raycache_gpu_cube cube, vec3 origin, vec3 direction, vec3 color, float distance,
                                raycache_relief_parameters p) {
    raycache_cdct_store_key k =
        raycache_cdct_traced_store(origin, direction, distance, cube.centre, cube.half_size, p.max_depth);
    return k.store && raycache_cdct_store(cube, k.key, color, k.distance);
}
#endif

#ifdef RAYCACHE_END_FRAME
/* End of frame for one element of the buffers: a pending word moves into an empty texel; the pending word
 * is emptied. The end-of-frame pass (raycache/end_frame.glsl) calls it for the listed elements; calling it
 * for every element, 0 .. length - 1, is the sweep needed after a list overflow. */
void raycache_cdct_end_frame(uint element) {
    if (element >= uint(raycache_cdct_texels.length()) || element >= uint(raycache_cdct_pending.length())) return;
    uvec2 pending = unpackUint2x32(raycache_cdct_pending[element]);
    if (raycache_cdct_is_valid(pending) && !raycache_cdct_is_valid(raycache_cdct_texels[element]))
        raycache_cdct_texels[element] = pending;
    raycache_cdct_pending[element] = 0xFFFFFFFFFFFFFFFFul;
}
#endif

#endif /* RAYCACHE_CDCT_GLSL */
