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
 * Layout, frames, the confidence test and clearing: raycache/shared/gpu_layout.h. Algorithm 1 in a shader:
 *   raycache_cct_result c = raycache_cct_lookup(cube, r);
 *   if (!c.hit) { c.color = trace(r); raycache_cct_store(cube, r, c.color); }
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
/* True when element's texel is marked doubtful (never without RAYCACHE_CONFIDENCE). */
bool raycache_cct_is_doubtful(uint element) { return RAYCACHE_IS_DOUBTFUL(raycache_cct_doubtful, element); }

/* What a lookup found: hit, and then the cached colour (RGB9E5-rounded). */
struct raycache_cct_result {
    bool hit;
    vec3 color;
};

/* The colour cached for `direction` (need not be unit length) in `cube`, without counting. A miss when the
 * texel is empty, was stored this frame, is doubtful, or `direction` is not a direction (zero, NaN, infinite). */
raycache_cct_result raycache_cct_peek(raycache_gpu_cube cube, vec3 direction) {
    raycache_cct_result result;
    result.hit = false;
    result.color = vec3(0.0);
    uint i = raycache_cube_texel(cube, direction);
    if (i >= uint(raycache_cct_texels.length())) return result;
    uint word = raycache_cct_texels[i];
    if (!raycache_cct_is_valid(word) || raycache_cct_is_doubtful(i)) return result;
    result.hit = true;
    result.color = raycache_unpack_rgb9e5(word);
    return result;
}

/* raycache_cct_peek, counted as a hit or a miss of the cube in the frame buffer (and its direction cell marked). */
raycache_cct_result raycache_cct_lookup(raycache_gpu_cube cube, vec3 direction) {
    raycache_cct_result result = raycache_cct_peek(cube, direction);
    raycache_count_lookup_toward(cube, direction, result.hit);
    return result;
}

#ifndef RAYCACHE_READ_ONLY
/* Caches `color` for `direction`; visible from the next frame (after the end-of-frame pass). Refused
 * (false, counted as refused) when `direction` is not a direction or the texel already holds a value;
 * among same-frame stores into one texel the smallest RGB9E5 word wins, whatever the order (true: smallest
 * so far). The texel's first store of the frame lists it for the end-of-frame pass. */
bool raycache_cct_store(raycache_gpu_cube cube, vec3 direction, vec3 color) {
    uint i = raycache_cube_texel(cube, direction);
    uint word = raycache_pack_rgb9e5(color);
    if (i >= uint(raycache_cct_texels.length()) || i >= uint(raycache_cct_pending.length()) ||
        raycache_cct_is_valid(raycache_cct_texels[i]) /* visible: kept */ || !raycache_cct_is_valid(word)) {
        raycache_frame_count(cube.index, RAYCACHE_FRAME_REFUSED);
        return false;
    }
    raycache_frame_count(cube.index, RAYCACHE_FRAME_STORES);
    uint old = atomicMin(raycache_cct_pending[i], word);
    if (old == RAYCACHE_GPU_CLEAR_WORD) raycache_frame_list_append(i);
    return old > word;
}
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
#endif

#endif /* RAYCACHE_CCT_GLSL */
