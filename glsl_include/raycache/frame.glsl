/* raycache/frame.glsl: the frame buffer of RayCache's GPU frame protocol (layout: raycache/shared/gpu_layout.h):
 * per-cube counters of lookups and stores, whether the cube rests, the direction cells lookups took, and the list of texels stored this frame, which the
 * end-of-frame pass (raycache/end_frame.glsl) publishes. Included by cube.glsl; declares nothing under
 * RAYCACHE_READ_ONLY (lookups are then not counted).
 *
 *   binding RAYCACHE_FRAME_BINDING (4), set RAYCACHE_FRAME_SET (= RAYCACHE_SET)   uint raycache_frame[]
 */
#ifndef RAYCACHE_FRAME_GLSL
#define RAYCACHE_FRAME_GLSL

#include "raycache/shared/gpu_layout.h"

#ifndef RAYCACHE_FRAME_SET
#define RAYCACHE_FRAME_SET RAYCACHE_SET
#endif

#ifndef RAYCACHE_READ_ONLY
layout(std430, set = RAYCACHE_FRAME_SET, binding = RAYCACHE_FRAME_BINDING) buffer raycache_frame_buffer {
    uint raycache_frame[];
};

/* Adds one to counter `which` of the cube numbered `index` (nothing for a number past the host's cube count). */
void raycache_frame_count(uint index, uint which) {
    if (index >= raycache_frame[RAYCACHE_FRAME_CUBE_COUNT]) return;
    uint word = raycache_frame_counter_word(index, which);
    if (word < uint(raycache_frame.length())) atomicAdd(raycache_frame[word], 1u);
}

/* The resting word the host started this frame with for the cube numbered `index`: 0 when it works, else
 * its probe bits (raycache/shared/gpu_layout.h); 0 for a number past the host's cube count. */
uint raycache_frame_cube_resting_word(uint index) {
    if (index >= raycache_frame[RAYCACHE_FRAME_CUBE_COUNT]) return 0u;
    uint word = raycache_frame_counter_word(index, RAYCACHE_FRAME_RESTING);
    return word < uint(raycache_frame.length()) ? raycache_frame[word] : 0u;
}

/* Whether the host started this frame with the cube numbered `index` resting (false for a number past the
 * host's cube count). */
bool raycache_frame_cube_resting(uint index) {
    return raycache_frame_cube_resting_word(index) != 0u;
}

/* Sets the coverage bit of the direction cell `direction` falls in (raycache/shared/coverage.h) for the
 * cube numbered `index`: what the host's adaptive face sizes go by. Only while the frame's flags hold
 * RAYCACHE_FRAME_MARK_COVERAGE. Reads first, so a cell already marked costs no atomic. */
void raycache_frame_mark_direction(uint index, vec3 direction) {
    if ((raycache_frame[RAYCACHE_FRAME_FLAGS] & RAYCACHE_FRAME_MARK_COVERAGE) == 0u) return;
    if (index >= raycache_frame[RAYCACHE_FRAME_CUBE_COUNT]) return;
    uint cell = raycache_coverage_cell(direction);
    if (cell == RAYCACHE_NO_COVERAGE_CELL) return;
    uint word = raycache_frame_coverage_word(index, cell >> 5u);
    uint bit = 1u << (cell & 31u);
    if (word < uint(raycache_frame.length()) && (raycache_frame[word] & bit) == 0u) atomicOr(raycache_frame[word], bit);
}

/* Appends a stored texel's entry to the store list; called once per texel and frame, by the store that
 * found its pending word empty. Keeps the end-of-frame pass's group count (its indirect dispatch) equal to
 * raycache_end_frame_groups(entries). A full list counts the texel in RAYCACHE_FRAME_OVERFLOW instead:
 * the host must then run the sweep (raycache_cct_end_frame / raycache_cdct_end_frame over every element). */
void raycache_frame_list_append(uint entry) {
    uint k = atomicAdd(raycache_frame[RAYCACHE_FRAME_LIST_COUNT], 1u);
    uint word = raycache_frame_list_word(raycache_frame[RAYCACHE_FRAME_CUBE_COUNT], k);
    if (k >= raycache_frame[RAYCACHE_FRAME_LIST_CAPACITY] || word >= uint(raycache_frame.length())) {
        atomicAdd(raycache_frame[RAYCACHE_FRAME_OVERFLOW], 1u);
        return;
    }
    raycache_frame[word] = entry;
    if (raycache_end_frame_groups(k + 1u) > raycache_end_frame_groups(k)) atomicAdd(raycache_frame[RAYCACHE_FRAME_DISPATCH], 1u);
}
#endif

#endif /* RAYCACHE_FRAME_GLSL */
