/* raycache/shared/gpu_layout.h: how caching cubes live in GPU storage buffers, shared by C++ and GLSL.
 *
 * Texel buffers. Several cubes of one technique may share a buffer: cube k's texels are elements
 * [first_texel, first_texel + 6 N^2) of it, in raycache_texel_linear_index order ((face * N + row) * N
 * + column). Elements are the C++ words: CCT `uint` (CctTexel::Word), CDCT `uvec2` (CdctTexel::Word,
 * x = low half = RGB9E5 colour, y = distance bits), so a CacheCube's words copy into a buffer and back.
 *
 * Frames. Each texel buffer has a pending twin of the same size. During a frame, lookups read the texel
 * buffer only and stores go to the pending buffer (atomicMin: the smallest word wins, as in C++), so a
 * store is never visible in the frame it was made in. Between frames an end-frame pass moves each valid
 * pending word into its texel, unless that texel already holds a value, and empties the pending word.
 *
 * Clearing: fill both buffers with RAYCACHE_GPU_CLEAR_WORD (vkCmdFillBuffer). Every all-ones word is
 * invalid, in the CDCT too (negative distance bits), and is larger than every valid word.
 */
#ifndef RAYCACHE_SHARED_GPU_LAYOUT_H
#define RAYCACHE_SHARED_GPU_LAYOUT_H

#include "raycache/shared/cube_face.h"

#ifdef __cplusplus
#include <cstddef>
namespace raycache {
namespace shared {
#endif

/* The 32-bit word that empties texel and pending buffers. */
#define RAYCACHE_GPU_CLEAR_WORD 0xFFFFFFFFu

/* Where one cube sits in its buffers and in the world; 32 bytes, the same in C++ and in GLSL std430
 * and std140 (an array of these in a storage or uniform buffer reads the same from both languages). */
struct raycache_gpu_cube {
    vec3 centre;      /* CDCT: centre of the box [centre - half_size, centre + half_size]; CCT: unused */
    float half_size;  /* CDCT: half the box's edge, > 0; CCT: unused */
    uint first_texel; /* index of the cube's texel 0 in its texel and pending buffers */
    int face_size;    /* N, texels along a face's edge, 1..4096 */
    uint reserved0;   /* padding to 32 bytes; write 0 */
    uint reserved1;
};

/* A descriptor for a cube of face_size texels per edge whose texels start at element first_texel. */
RAYCACHE_FN raycache_gpu_cube raycache_make_gpu_cube(vec3 centre, float half_size, uint first_texel, int face_size) {
    raycache_gpu_cube cube;
    cube.centre = centre;
    cube.half_size = half_size;
    cube.first_texel = first_texel;
    cube.face_size = face_size;
    cube.reserved0 = 0u;
    cube.reserved1 = 0u;
    return cube;
}

/* Texels in a cube of face_size texels per edge: 6 N^2. */
RAYCACHE_FN uint raycache_gpu_cube_texel_count(int face_size) {
    return 6u * uint(face_size) * uint(face_size);
}

#ifdef __cplusplus
static_assert(sizeof(raycache_gpu_cube) == 32, "raycache_gpu_cube must be 32 bytes, as in GLSL std430/std140");
static_assert(offsetof(raycache_gpu_cube, centre) == 0 && offsetof(raycache_gpu_cube, half_size) == 12 &&
                  offsetof(raycache_gpu_cube, first_texel) == 16 && offsetof(raycache_gpu_cube, face_size) == 20 &&
                  offsetof(raycache_gpu_cube, reserved0) == 24 && offsetof(raycache_gpu_cube, reserved1) == 28,
              "raycache_gpu_cube offsets must match GLSL std430/std140");
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_GPU_LAYOUT_H */
