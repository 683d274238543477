/* raycache/cct.glsl: the colour caching technique (CCT, thesis ch. 3) in GLSL, the same texels as
 * raycache::CctCube: one RGB9E5 word per texel, keyed by the direction of the ray leaving the object.
 *
 * Buffers (std430, set RAYCACHE_CCT_SET = RAYCACHE_SET):
 *   binding RAYCACHE_CCT_BINDING (0)          uint raycache_cct_texels[]   what lookups read
 *   binding RAYCACHE_CCT_PENDING_BINDING (1)  uint raycache_cct_pending[]  this frame's stores (atomicMin)
 *   binding RAYCACHE_FRAME_BINDING (4)        uint raycache_frame[]        counters, store list (frame.glsl)
 * With RAYCACHE_CONFIDENCE defined (the confidence test), also:
 *   binding RAYCACHE_CCT_DOUBTFUL_BINDING (5) uint raycache_cct_doubtful[]  a bit per texel: doubtful, reads as empty
 *   binding RAYCACHE_CCT_CUBES_BINDING (7)    raycache_gpu_cube raycache_cct_cubes[]  the cube table (end_frame.glsl, mark pass)
 * With RAYCACHE_ORIGINS defined (the origin test, C++'s lookup and store with an OriginTolerance), also:
 *   binding RAYCACHE_CCT_ORIGINS_BINDING (9)  uint raycache_cct_origins[]   a record per tile of 16 x 16 texels
 *   binding RAYCACHE_CCT_CUBES_BINDING (7)    the cube table (end-of-frame passes only)
 * Layout, frames, the confidence test and clearing: raycache/shared/gpu_layout.h; the origin test and its
 * records: raycache/shared/origin_rule.h. Algorithm 1 in a shader:
 *   raycache_cct_result c = raycache_cct_lookup(cube, r);
 *   if (!c.hit) { c.color = trace(r); raycache_cct_store(cube, r, c.color); }
 * and with the origin test, for a ray leaving from point o whose traced hit lay t along r (infinity: none):
 *   raycache_cct_result c = raycache_cct_lookup_from(cube, r, o, tolerance);
 *   if (!c.hit) { c.color = trace(r); raycache_cct_store_from(cube, r, c.color, o, t, tolerance); }
 */
#ifndef RAYCACHE_CCT_GLSL
#define RAYCACHE_CCT_GLSL

#include "raycache/cube.glsl"

#ifndef RAYCACHE_CCT_SET
#define RAYCACHE_CCT_SET RAYCACHE_SET
#endif

layout(std430, set = RAYCACHE_CCT_SET, binding = RAYCACHE_CCT_BINDING) RAYCACHE_TEXEL_ACCESS buffer raycache_cct_texel_buffer {
    uint raycache_cct_texels[];
};
#ifndef RAYCACHE_READ_ONLY
layout(std430, set = RAYCACHE_CCT_SET, binding = RAYCACHE_CCT_PENDING_BINDING) buffer raycache_cct_pending_buffer {
    uint raycache_cct_pending[];
};
#endif
#ifdef RAYCACHE_CONFIDENCE
layout(std430, set = RAYCACHE_CCT_SET, binding = RAYCACHE_CCT_DOUBTFUL_BINDING) RAYCACHE_TEXEL_ACCESS buffer raycache_cct_doubtful_buffer {
    uint raycache_cct_doubtful[];
};
#endif
#ifdef RAYCACHE_ORIGINS
#include "raycache/shared/origin_rule.h"
#ifdef RAYCACHE_READ_ONLY
#define RAYCACHE_ORIGIN_ACCESS readonly
#else
#define RAYCACHE_ORIGIN_ACCESS
#endif
layout(std430, set = RAYCACHE_CCT_SET, binding = RAYCACHE_CCT_ORIGINS_BINDING) RAYCACHE_ORIGIN_ACCESS buffer raycache_cct_origin_buffer {
    uint raycache_cct_origins[];
};
#endif
/* True when element's texel is marked doubtful (never without RAYCACHE_CONFIDENCE). */
bool raycache_cct_is_doubtful(uint element) { return RAYCACHE_IS_DOUBTFUL(raycache_cct_doubtful, element); }

/* What a lookup found: hit, and then the cached colour (RGB9E5-rounded). */
struct raycache_cct_result {
    bool hit;
    vec3 color;
};

/* The colour element i's texel holds for lookups (a miss when it is empty or doubtful, or i is past the buffer);
 * `empty`: the texel holds no value (a doubtful texel holds one). */
raycache_cct_result raycache_cct_peek_element(uint i, out bool empty) {
    raycache_cct_result result;
    result.hit = false;
    result.color = vec3(0.0);
    empty = false;
    if (i >= uint(raycache_cct_texels.length())) return result;
    uint word = raycache_cct_texels[i];
    empty = !raycache_cct_is_valid(word);
    if (empty || raycache_cct_is_doubtful(i)) return result;
    result.hit = true;
    result.color = raycache_unpack_rgb9e5(word);
    return result;
}
raycache_cct_result raycache_cct_peek_element(uint i) {
    bool empty;
    return raycache_cct_peek_element(i, empty);
}

/* The colour cached for `direction` (need not be unit length) in `cube`, without counting. A miss when the
 * texel is empty, was stored this frame, is doubtful, or `direction` is not a direction (zero, NaN, infinite). */
raycache_cct_result raycache_cct_peek(raycache_gpu_cube cube, vec3 direction) {
    return raycache_cct_peek_element(raycache_cube_texel(cube, direction));
}

/* raycache_cct_peek, counted as a hit or a miss of the cube in the frame buffer (and its direction cell marked). */
raycache_cct_result raycache_cct_lookup(raycache_gpu_cube cube, vec3 direction) {
    bool empty;
    raycache_cct_result result = raycache_cct_peek_element(raycache_cube_texel(cube, direction), empty);
    raycache_count_lookup_toward(cube, direction, result.hit);
    if (empty) raycache_count_empty(cube);
    return result;
}

#ifdef RAYCACHE_ORIGINS
/* How far a ray's origin may lie outside the origins a tile was stored from and still be answered (C++'s
 * raycache::OriginTolerance): `drift` world units, and no more than `parallax` times the distance to the
 * nearest surface the tile's rays hit (infinity: no such bound). */
struct raycache_origin_tolerance {
    float drift;
    float parallax;
};

/* First word of the origin record of the tile holding texel a of `cube` (a texel of it), or
 * RAYCACHE_NO_TEXEL when the record lies past the buffer. */
uint raycache_cct_origin_record(raycache_gpu_cube cube, raycache_texel_address a) {
    uint r = (cube.first_tile + raycache_origin_tile_index(a, cube.face_size)) * RAYCACHE_ORIGIN_RECORD_WORDS;
    return r + RAYCACHE_ORIGIN_RECORD_WORDS <= uint(raycache_cct_origins.length()) ? r : RAYCACHE_NO_TEXEL;
}

/* The visible origin box of the record at r (false when it has none). */
bool raycache_cct_origin_box(uint r, out vec3 lo, out vec3 hi) {
    lo = vec3(0.0);
    hi = vec3(0.0);
    if (!raycache_origin_has_box(raycache_cct_origins[r + RAYCACHE_ORIGIN_LO])) return false;
    lo = raycache_origin_corner(raycache_cct_origins[r + RAYCACHE_ORIGIN_LO], raycache_cct_origins[r + RAYCACHE_ORIGIN_LO + 1u],
                                raycache_cct_origins[r + RAYCACHE_ORIGIN_LO + 2u], false);
    hi = raycache_origin_corner(raycache_cct_origins[r + RAYCACHE_ORIGIN_HI], raycache_cct_origins[r + RAYCACHE_ORIGIN_HI + 1u],
                                raycache_cct_origins[r + RAYCACHE_ORIGIN_HI + 2u], true);
    return true;
}

#ifndef RAYCACHE_READ_ONLY
/* Lists the record at r in the store list once a frame (the end-of-frame passes publish or drop its tile). */
void raycache_cct_list_tile(uint r) {
    if (raycache_cct_origins[r + RAYCACHE_ORIGIN_LISTED] != 0u && atomicExchange(raycache_cct_origins[r + RAYCACHE_ORIGIN_LISTED], 0u) != 0u)
        raycache_frame_list_append(RAYCACHE_FRAME_TILE_ENTRY | (r / RAYCACHE_ORIGIN_RECORD_WORDS));
}
#endif

/* raycache_cct_lookup for a ray leaving from `origin`: also a miss when `origin` lies more than the allowed
 * drift (raycache/shared/origin_rule.h) outside the box of the origins the texel's tile was stored from (a
 * tile without a box answers any origin); the tile is then dropped at the end of the frame (not under
 * RAYCACHE_READ_ONLY) and refills from the current rays. As C++'s CacheCube::lookup(direction, origin, tolerance). */
raycache_cct_result raycache_cct_lookup_from(raycache_gpu_cube cube, vec3 direction, vec3 origin, raycache_origin_tolerance tolerance) {
    raycache_texel_address a = raycache_cube_texel_address(cube, direction);
    bool empty; /* holds no value: counted as such below, whatever the origin test says */
    raycache_cct_result result = raycache_cct_peek_element(raycache_cube_element(cube, a), empty);
    if (result.hit) {
        uint r = raycache_cct_origin_record(cube, a);
        vec3 lo, hi;
        if (r == RAYCACHE_NO_TEXEL) {
            result.hit = false;
        } else if (raycache_cct_origin_box(r, lo, hi)) {
            float nearest = raycache_origin_nearest(raycache_cct_origins[r + RAYCACHE_ORIGIN_NEAREST]);
            if (!raycache_origin_covered(origin, lo, hi, raycache_allowed_drift(tolerance.drift, tolerance.parallax, nearest))) {
                result.hit = false;
#ifndef RAYCACHE_READ_ONLY
                if (raycache_cct_origins[r + RAYCACHE_ORIGIN_STALE] != 0u) {
                    atomicMin(raycache_cct_origins[r + RAYCACHE_ORIGIN_STALE], 0u);
                    raycache_cct_list_tile(r);
                }
#endif
            }
        }
        if (!result.hit) result.color = vec3(0.0);
    }
    raycache_count_lookup_toward(cube, direction, result.hit);
    if (empty) raycache_count_empty(cube);
    return result;
}
#endif

#ifndef RAYCACHE_READ_ONLY
/* Whether a store of `word` into element i gets past the first refusals: i within both buffers, its
 * texel empty (a visible value is kept), the word valid. */
bool raycache_cct_may_store(uint i, uint word) {
    return i < uint(raycache_cct_texels.length()) && i < uint(raycache_cct_pending.length()) &&
           !raycache_cct_is_valid(raycache_cct_texels[i]) && raycache_cct_is_valid(word);
}

/* The rivalry of a store that got past raycache_cct_may_store: counted, the smallest word wins. */
bool raycache_cct_store_element(raycache_gpu_cube cube, uint i, uint word) {
    raycache_frame_count(cube.index, RAYCACHE_FRAME_STORES);
    uint old = atomicMin(raycache_cct_pending[i], word);
    if (old == RAYCACHE_GPU_CLEAR_WORD) raycache_frame_list_append(i);
    return old > word;
}

/* Caches `color` for `direction`; visible from the next frame (after the end-of-frame pass). Refused
 * (false, counted as refused) when `direction` is not a direction or the texel already holds a value;
 * among same-frame stores into one texel the smallest RGB9E5 word wins, whatever the order (true: smallest
 * so far). The texel's first store of the frame lists it for the end-of-frame pass. */
bool raycache_cct_store(raycache_gpu_cube cube, vec3 direction, vec3 color) {
    uint i = raycache_cube_texel(cube, direction);
    uint word = raycache_pack_rgb9e5(color);
    if (!raycache_cct_may_store(i, word)) {
        raycache_frame_count(cube.index, RAYCACHE_FRAME_REFUSED);
        return false;
    }
    return raycache_cct_store_element(cube, i, word);
}

#ifdef RAYCACHE_ORIGINS
/* raycache_cct_store for a ray that left from `origin` and hit at `hit_distance` along the unit direction
 * (infinity: it escaped): also refused when `origin` is not finite, hit_distance is not >= 0, or the tile's
 * visible origin box, grown by `origin`, would be wider than the allowed drift; otherwise the origin and
 * distance join the tile's box for the next frames. As C++'s CacheCube::store(direction, value, origin,
 * hit_distance, tolerance). */
bool raycache_cct_store_from(raycache_gpu_cube cube, vec3 direction, vec3 color, vec3 origin, float hit_distance,
                             raycache_origin_tolerance tolerance) {
    raycache_texel_address a = raycache_cube_texel_address(cube, direction);
    uint i = raycache_cube_element(cube, a);
    uint word = raycache_pack_rgb9e5(color);
    if (!raycache_cct_may_store(i, word) || !raycache_is_finite3(origin) || !(hit_distance >= 0.0)) {
        raycache_frame_count(cube.index, RAYCACHE_FRAME_REFUSED);
        return false;
    }
    uint r = raycache_cct_origin_record(cube, a);
    vec3 lo, hi;
    if (r == RAYCACHE_NO_TEXEL ||
        (raycache_cct_origin_box(r, lo, hi) &&
         !raycache_origin_box_stays_within(lo, hi, origin, raycache_allowed_drift(tolerance.drift, tolerance.parallax,
             min(raycache_origin_nearest(raycache_cct_origins[r + RAYCACHE_ORIGIN_NEAREST]), hit_distance))))) {
        raycache_frame_count(cube.index, RAYCACHE_FRAME_REFUSED);
        return false;
    }
    for (uint k = 0u; k < 3u; ++k) {
        atomicMin(raycache_cct_origins[r + RAYCACHE_ORIGIN_PENDING + RAYCACHE_ORIGIN_LO + k], raycache_origin_corner_word(origin[k], false));
        atomicMin(raycache_cct_origins[r + RAYCACHE_ORIGIN_PENDING + RAYCACHE_ORIGIN_HI + k], raycache_origin_corner_word(origin[k], true));
    }
    if (hit_distance < RAYCACHE_INFINITY) // an escaped ray leaves the nearest distance as it is (clear: infinity)
        atomicMin(raycache_cct_origins[r + RAYCACHE_ORIGIN_PENDING + RAYCACHE_ORIGIN_NEAREST], raycache_ordered_key(hit_distance));
    raycache_cct_list_tile(r);
    return raycache_cct_store_element(cube, i, word);
}
#endif
#endif

#ifdef RAYCACHE_END_FRAME
/* End of frame for one element of the buffers: a pending word moves into an empty texel; the pending word
 * is emptied. The end-of-frame pass (raycache/end_frame.glsl) calls it for the listed elements; calling it
 * for every element, 0 .. length - 1, is the sweep needed after a list overflow. */
void raycache_cct_end_frame(uint element) {
    if (element >= uint(raycache_cct_texels.length()) || element >= uint(raycache_cct_pending.length())) return;
    uint pending = raycache_cct_pending[element];
    if (raycache_cct_is_valid(pending) && !raycache_cct_is_valid(raycache_cct_texels[element]))
        raycache_cct_texels[element] = pending;
    raycache_cct_pending[element] = RAYCACHE_GPU_CLEAR_WORD;
}

#ifdef RAYCACHE_ORIGINS
/* End of frame for one tile's origin record (a tile entry of the store list, or every tile in the sweep):
 * unless a lookup marked the tile stale (the drop pass empties it then), this frame's origins and nearest
 * distance join the visible ones and the pending words are emptied. */
void raycache_cct_end_frame_tile(uint tile) {
    uint r = tile * RAYCACHE_ORIGIN_RECORD_WORDS;
    if (tile >= RAYCACHE_FRAME_TILE_ENTRY || r + RAYCACHE_ORIGIN_RECORD_WORDS > uint(raycache_cct_origins.length()) ||
        raycache_cct_origins[r + RAYCACHE_ORIGIN_STALE] == 0u)
        return;
    for (uint w = 0u; w < RAYCACHE_ORIGIN_PENDING; ++w) {
        raycache_cct_origins[r + w] = min(raycache_cct_origins[r + w], raycache_cct_origins[r + RAYCACHE_ORIGIN_PENDING + w]);
        raycache_cct_origins[r + RAYCACHE_ORIGIN_PENDING + w] = RAYCACHE_GPU_CLEAR_WORD;
    }
    raycache_cct_origins[r + RAYCACHE_ORIGIN_LISTED] = RAYCACHE_GPU_CLEAR_WORD;
}
#endif
#endif

#endif /* RAYCACHE_CCT_GLSL */
