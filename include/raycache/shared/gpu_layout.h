/* raycache/shared/gpu_layout.h: how caching cubes live in GPU storage buffers, shared by C++ and GLSL.
 *
 * Texel buffers. Several cubes of one technique may share a buffer: cube k's texels are elements
 * [first_texel, first_texel + 6 N^2) of it, in raycache_texel_linear_index order ((face * N + row) * N
 * + column). Elements are the C++ words: CCT `uint` (CctTexel::Word), CDCT `uvec2` (CdctTexel::Word,
 * x = low half = RGB9E5 colour, y = distance bits), so a CacheCube's words copy into a buffer and back.
 *
 * Frames. Each texel buffer has a pending twin of the same size. During a frame, lookups read the texel
 * buffer only and stores go to the pending buffer (atomicMin: the smallest word wins, as in C++), so a
 * store is never visible in the frame it was made in. The first store into a texel in a frame (the one
 * that finds its pending word empty) appends the texel's element to the frame buffer's store list. Between
 * frames the end-of-frame pass visits only the listed elements: it moves each valid pending word into its
 * texel, unless that texel already holds a value, and empties the pending word. So its cost follows the
 * frame's stores, not the buffers' size.
 *
 * Frame buffer (binding RAYCACHE_FRAME_BINDING, uint words), shared by both techniques:
 *   header (RAYCACHE_FRAME_HEADER_WORDS): list count, list capacity, cube count, overflow, the end-of-frame
 *   pass's VkDispatchIndirectCommand, flags; then RAYCACHE_FRAME_CUBE_WORDS words per cube (counters, resting
 *   word, coverage; indexed by the descriptor's `index`); then the store list (list capacity entries: a texel element, with
 *   RAYCACHE_FRAME_CDCT_ENTRY set for a CDCT texel). The host writes the header and zeroes the counters
 *   before every frame (raycache/gpu_frame.hpp: gpu_frame_start_words). Counters are order-independent:
 *   hits and misses per lookup (a CDCT search is one lookup), `stores` = stores that reached the pending
 *   word (C++'s stores plus its same-frame losers), `refused` = stores refused before it (not a direction,
 *   a value that cannot be stored, a texel already visible or outside the buffers), `rested` = rays the
 *   cube let through without a lookup while resting, and the host's resting word (below); then the cube's
 *   coverage bits (RAYCACHE_COVERAGE_WORDS words: which of 1536 direction cells its lookups took,
 *   raycache/shared/coverage.h), which the host reads to choose adaptive face sizes, marked only while the
 *   header's flags hold RAYCACHE_FRAME_MARK_COVERAGE (a renderer with fixed face sizes leaves it off).
 *
 * Resting cubes (raycache/resting.hpp, as the Embree adapter's): a cube whose lookups answered fewer than a
 * threshold of its rays in a frame rests the next. The host decides between frames from the counters
 * (raycache/gpu_resting.hpp) and writes the cube's resting word before the frame (0: it works; else the
 * probe bits of its RestingState); a shader asks raycache_cube_rests(cube, direction) before the lookup:
 * true (the cube rests and the direction is not one of its probes, raycache_is_probe_direction_of) means
 * trace the ray without lookup or store.
 *
 * Confidence test (optional: shaders that define RAYCACHE_CONFIDENCE; the rule is raycache/shared/edge_rule.h,
 * as in C++'s raycache::mark_doubtful_edges). Each technique has a doubtful-bit buffer (binding
 * RAYCACHE_CCT_DOUBTFUL_BINDING / RAYCACHE_CDCT_DOUBTFUL_BINDING, uint words): bit (element & 31) of word
 * (element >> 5) is set when the texel is doubtful. A doubtful texel keeps its word but reads as empty to
 * lookups and searches (its rays are traced), and a store into it is refused as into any visible texel.
 * A second end-of-frame pass, the mark pass, runs over the same store list after the first one, with a
 * barrier between (it reads the texels that pass wrote). It compares each listed texel's visible colour
 * with its 4 neighbours' on the same face (left, right, up, down; not across a face's edge) and
 * atomicOr's the bits of both when they differ by more than the threshold the shader gives it (< 0 or
 * NaN: off). It reads only texel words, which no invocation of that pass writes, and only ever sets bits,
 * so its marks do not depend on invocation order. It finds a listed texel's cube in the technique's cube
 * table (binding RAYCACHE_CCT_CUBES_BINDING / RAYCACHE_CDCT_CUBES_BINDING: the technique's raycache_gpu_cube
 * descriptors by increasing first_texel, as raycache::gpu_buffer_layout places them).
 *
 * Origin test (optional: shaders that define RAYCACHE_ORIGINS; CCT): a record of 16 words per tile of 16 x 16
 * texels (binding RAYCACHE_CCT_ORIGINS_BINDING, from each descriptor's first_tile on), whose tiles the store
 * list also lists (RAYCACHE_FRAME_TILE_ENTRY); a third end-of-frame pass, the drop pass, empties the tiles
 * a lookup met from too far. Layout and rule: raycache/shared/origin_rule.h.
 *
 * Clearing: fill both buffers with RAYCACHE_GPU_CLEAR_WORD (vkCmdFillBuffer), and the doubtful-bit buffer
 * with 0, and origin records with RAYCACHE_GPU_CLEAR_WORD. Every all-ones word is invalid, in the CDCT too
 * (negative distance bits), and is larger than every valid word.
 */
#ifndef RAYCACHE_SHARED_GPU_LAYOUT_H
#define RAYCACHE_SHARED_GPU_LAYOUT_H

#include "raycache/shared/coverage.h"
#include "raycache/shared/cube_face.h"

#ifdef __cplusplus
#include <cstddef>
namespace raycache {
namespace shared {
#endif

/* The 32-bit word that empties texel and pending buffers. */
#define RAYCACHE_GPU_CLEAR_WORD 0xFFFFFFFFu

/* Descriptor set and binding numbers of RayCache's buffers; define any of them before the first include
 * (GLSL, and C++ where the host must agree) to move it. */
#ifndef RAYCACHE_SET
#define RAYCACHE_SET 0
#endif
#ifndef RAYCACHE_CCT_BINDING
#define RAYCACHE_CCT_BINDING 0
#endif
#ifndef RAYCACHE_CCT_PENDING_BINDING
#define RAYCACHE_CCT_PENDING_BINDING 1
#endif
#ifndef RAYCACHE_CDCT_BINDING
#define RAYCACHE_CDCT_BINDING 2
#endif
#ifndef RAYCACHE_CDCT_PENDING_BINDING
#define RAYCACHE_CDCT_PENDING_BINDING 3
#endif
#ifndef RAYCACHE_FRAME_BINDING
#define RAYCACHE_FRAME_BINDING 4
#endif
/* The confidence test's buffers (only in shaders that define RAYCACHE_CONFIDENCE): doubtful bits (lookups,
 * searches and both end-of-frame passes) and cube tables (the mark pass only). */
#ifndef RAYCACHE_CCT_DOUBTFUL_BINDING
#define RAYCACHE_CCT_DOUBTFUL_BINDING 5
#endif
#ifndef RAYCACHE_CDCT_DOUBTFUL_BINDING
#define RAYCACHE_CDCT_DOUBTFUL_BINDING 6
#endif
#ifndef RAYCACHE_CCT_CUBES_BINDING
#define RAYCACHE_CCT_CUBES_BINDING 7
#endif
#ifndef RAYCACHE_CDCT_CUBES_BINDING
#define RAYCACHE_CDCT_CUBES_BINDING 8
#endif
/* The CCT's origin test (only in shaders that define RAYCACHE_ORIGINS): a record per tile of texels
 * (raycache/shared/origin_rule.h); the end-of-frame passes also read the CCT's cube table. */
#ifndef RAYCACHE_CCT_ORIGINS_BINDING
#define RAYCACHE_CCT_ORIGINS_BINDING 9
#endif

/* Frame buffer: header words. */
#define RAYCACHE_FRAME_LIST_COUNT 0u    /* texels appended this frame (may pass the capacity: see OVERFLOW) */
#define RAYCACHE_FRAME_LIST_CAPACITY 1u /* entries the list holds (written by the host) */
#define RAYCACHE_FRAME_CUBE_COUNT 2u    /* cubes with counters (written by the host) */
#define RAYCACHE_FRAME_OVERFLOW 3u      /* texels stored that found the list full: sweep the buffers this frame */
#define RAYCACHE_FRAME_DISPATCH 4u      /* 3 words: groups of the end-of-frame pass, 1, 1 (vkCmdDispatchIndirect) */
#define RAYCACHE_FRAME_FLAGS 7u         /* RAYCACHE_FRAME_MARK_COVERAGE or 0 (written by the host) */
#define RAYCACHE_FRAME_HEADER_WORDS 8u
/* Frame flag: lookups mark their direction cells (adaptive face sizes read them); without it they read
 * only the flags word, skipping the face choice, the coverage word and its atomic. */
#define RAYCACHE_FRAME_MARK_COVERAGE 1u
/* Counters of one cube, after the header. */
#define RAYCACHE_FRAME_HITS 0u
#define RAYCACHE_FRAME_MISSES 1u   /* lookups that missed (the rays a resting cube let through are not among them) */
#define RAYCACHE_FRAME_STORES 2u
#define RAYCACHE_FRAME_REFUSED 3u
#define RAYCACHE_FRAME_RESTED 4u   /* rays the resting cube let through untouched (raycache_cube_rests) */
#define RAYCACHE_FRAME_RESTING 5u  /* written by the host: 0 when the cube works this frame, else it rests
                                      and probes one direction in 2^word (clamped to RAYCACHE_PROBE_BITS..
                                      RAYCACHE_MAX_PROBE_BITS: raycache_is_probe_direction_of) */
#define RAYCACHE_FRAME_EMPTY 6u    /* lookups that missed on a texel holding no value (among MISSES; counted in
                                      frames that mark coverage): whether the cube's rays come back to texels
                                      already filled (raycache/gpu_adaptive.hpp) */
#define RAYCACHE_FRAME_COVERAGE 7u /* RAYCACHE_COVERAGE_WORDS words: the direction cells its lookups took */
#define RAYCACHE_FRAME_CUBE_WORDS (RAYCACHE_FRAME_COVERAGE + RAYCACHE_COVERAGE_WORDS)
/* A store-list entry for a CDCT texel (else CCT); the rest of the entry is the texel's element. */
#define RAYCACHE_FRAME_CDCT_ENTRY 0x80000000u
/* A store-list entry for a CCT tile's origin record (RAYCACHE_ORIGINS: stored from, or met by a lookup from
 * too far); the rest of the entry is the record's index. CCT elements stay below this bit. */
#define RAYCACHE_FRAME_TILE_ENTRY 0x40000000u
/* The end-of-frame pass: invocations per group, at most this many groups (one dimension), so a store list
 * of at most this many entries (a longer frame overflows: sweep). */
#define RAYCACHE_END_FRAME_GROUP_SIZE 256u
#define RAYCACHE_END_FRAME_MAX_GROUPS 65535u
#define RAYCACHE_END_FRAME_MAX_ENTRIES (RAYCACHE_END_FRAME_GROUP_SIZE * RAYCACHE_END_FRAME_MAX_GROUPS)

/* Where one cube sits in its buffers and in the world; 32 bytes, the same in C++ and in GLSL std430
 * and std140 (an array of these in a storage or uniform buffer reads the same from both languages). */
struct raycache_gpu_cube {
    vec3 centre;      /* CDCT: centre of the box [centre - half_size, centre + half_size]; CCT: unused */
    float half_size;  /* CDCT: half the box's edge, > 0; CCT: unused */
    uint first_texel; /* index of the cube's texel 0 in its texel and pending buffers */
    int face_size;    /* N, texels along a face's edge, 1..4096 */
    uint index;       /* the cube's counters in the frame buffer (cubes of both techniques number apart) */
    uint first_tile;  /* CCT with RAYCACHE_ORIGINS: index of the cube's tile 0 in the origin records
                         (raycache/shared/origin_rule.h); otherwise unused, write 0 */
};

/* A descriptor for a cube of face_size texels per edge whose texels start at element first_texel. */
RAYCACHE_FN raycache_gpu_cube raycache_make_gpu_cube(vec3 centre, float half_size, uint first_texel, int face_size) {
    raycache_gpu_cube cube;
    cube.centre = centre;
    cube.half_size = half_size;
    cube.first_texel = first_texel;
    cube.face_size = face_size;
    cube.index = 0u;
    cube.first_tile = 0u;
    return cube;
}

/* Texels in a cube of face_size texels per edge: 6 N^2. */
RAYCACHE_FN uint raycache_gpu_cube_texel_count(int face_size) {
    return 6u * uint(face_size) * uint(face_size);
}

/* Word of the frame buffer holding counter `which` (RAYCACHE_FRAME_HITS...) of cube `index`. */
RAYCACHE_FN uint raycache_frame_counter_word(uint index, uint which) {
    return RAYCACHE_FRAME_HEADER_WORDS + index * RAYCACHE_FRAME_CUBE_WORDS + which;
}

/* Word of the frame buffer holding coverage word w (0..RAYCACHE_COVERAGE_WORDS - 1) of cube `index`. */
RAYCACHE_FN uint raycache_frame_coverage_word(uint index, uint w) {
    return raycache_frame_counter_word(index, RAYCACHE_FRAME_COVERAGE + w);
}

/* Word of the frame buffer holding store-list entry k, with cube_count cubes' counters before the list. */
RAYCACHE_FN uint raycache_frame_list_word(uint cube_count, uint k) {
    return RAYCACHE_FRAME_HEADER_WORDS + cube_count * RAYCACHE_FRAME_CUBE_WORDS + k;
}

/* Groups of the end-of-frame pass for `entries` listed texels: one per RAYCACHE_END_FRAME_GROUP_SIZE, at
 * most RAYCACHE_END_FRAME_MAX_GROUPS. A store that appends entry k adds a group exactly when this grows. */
RAYCACHE_FN uint raycache_end_frame_groups(uint entries) {
    return min((entries + RAYCACHE_END_FRAME_GROUP_SIZE - 1u) / RAYCACHE_END_FRAME_GROUP_SIZE, RAYCACHE_END_FRAME_MAX_GROUPS);
}

/* The doubtful-bit buffer's word holding element's bit, and the bit within it. */
RAYCACHE_FN uint raycache_doubtful_word(uint element) {
    return element >> 5u;
}
RAYCACHE_FN uint raycache_doubtful_bit(uint element) {
    return 1u << (element & 31u);
}

#ifdef __cplusplus
static_assert(sizeof(raycache_gpu_cube) == 32, "raycache_gpu_cube must be 32 bytes, as in GLSL std430/std140");
static_assert(offsetof(raycache_gpu_cube, centre) == 0 && offsetof(raycache_gpu_cube, half_size) == 12 &&
                  offsetof(raycache_gpu_cube, first_texel) == 16 && offsetof(raycache_gpu_cube, face_size) == 20 &&
                  offsetof(raycache_gpu_cube, index) == 24 && offsetof(raycache_gpu_cube, first_tile) == 28,
              "raycache_gpu_cube offsets must match GLSL std430/std140");
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_GPU_LAYOUT_H */
