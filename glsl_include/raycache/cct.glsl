/* raycache/cct.glsl: the colour caching technique (CCT, thesis ch. 3) in GLSL, the same texels as
 * raycache::CctCube: one RGB9E5 word per texel, keyed by the direction of the ray leaving the object.
 *
 * Buffers (std430, set RAYCACHE_CCT_SET = RAYCACHE_SET):
 *   binding RAYCACHE_CCT_BINDING (0)          uint raycache_cct_texels[]   what lookups read
 *   binding RAYCACHE_CCT_PENDING_BINDING (1)  uint raycache_cct_pending[]  this frame's stores (atomicMin)
 * Layout, frames and clearing: raycache/shared/gpu_layout.h. Algorithm 1 in a shader:
 *   raycache_cct_result c = raycache_cct_lookup(cube, r);
 *   if (!c.hit) { c.color = trace(r); raycache_cct_store(cube, r, c.color); }
 */
#ifndef RAYCACHE_CCT_GLSL
#define RAYCACHE_CCT_GLSL

#include "raycache/cube.glsl"

#ifndef RAYCACHE_CCT_SET
#define RAYCACHE_CCT_SET RAYCACHE_SET
#endif
#ifndef RAYCACHE_CCT_BINDING
#define RAYCACHE_CCT_BINDING 0
#endif
#ifndef RAYCACHE_CCT_PENDING_BINDING
#define RAYCACHE_CCT_PENDING_BINDING 1
#endif

layout(std430, set = RAYCACHE_CCT_SET, binding = RAYCACHE_CCT_BINDING) RAYCACHE_TEXEL_ACCESS buffer raycache_cct_texel_buffer {
    uint raycache_cct_texels[];
};
#ifndef RAYCACHE_READ_ONLY
layout(std430, set = RAYCACHE_CCT_SET, binding = RAYCACHE_CCT_PENDING_BINDING) buffer raycache_cct_pending_buffer {
    uint raycache_cct_pending[];
};
#endif

/* What a lookup found: hit, and then the cached colour (RGB9E5-rounded). */
struct raycache_cct_result {
    bool hit;
    vec3 color;
};

/* The colour cached for `direction` (need not be unit length) in `cube`. A miss when the texel is
 * empty, was stored this frame, or `direction` is not a direction (zero, NaN, infinite). */
raycache_cct_result raycache_cct_lookup(raycache_gpu_cube cube, vec3 direction) {
    raycache_cct_result result;
    result.hit = false;
    result.color = vec3(0.0);
    uint i = raycache_cube_texel(cube, direction);
    if (i >= uint(raycache_cct_texels.length())) return result;
    uint word = raycache_cct_texels[i];
    if (!raycache_cct_is_valid(word)) return result;
    result.hit = true;
    result.color = raycache_unpack_rgb9e5(word);
    return result;
}

#ifndef RAYCACHE_READ_ONLY
/* Caches `color` for `direction`; visible from the next frame (after the end-frame pass). Refused
 * (false) when `direction` is not a direction or the texel already holds a value; among same-frame
 * stores into one texel the smallest RGB9E5 word wins, whatever the order (true: smallest so far). */
bool raycache_cct_store(raycache_gpu_cube cube, vec3 direction, vec3 color) {
    uint i = raycache_cube_texel(cube, direction);
    if (i >= uint(raycache_cct_texels.length()) || i >= uint(raycache_cct_pending.length())) return false;
    if (raycache_cct_is_valid(raycache_cct_texels[i])) return false; /* visible: kept */
    uint word = raycache_pack_rgb9e5(color);
    if (!raycache_cct_is_valid(word)) return false;
    return atomicMin(raycache_cct_pending[i], word) > word;
}
#endif

#ifdef RAYCACHE_END_FRAME
/* End of frame for one element of the buffers (call for every element, 0 .. length - 1, in a pass
 * between frames): a pending word moves into an empty texel; the pending word is emptied. */
void raycache_cct_end_frame(uint element) {
    if (element >= uint(raycache_cct_texels.length()) || element >= uint(raycache_cct_pending.length())) return;
    uint pending = raycache_cct_pending[element];
    if (raycache_cct_is_valid(pending) && !raycache_cct_is_valid(raycache_cct_texels[element]))
        raycache_cct_texels[element] = pending;
    raycache_cct_pending[element] = RAYCACHE_GPU_CLEAR_WORD;
}
#endif

#endif /* RAYCACHE_CCT_GLSL */
