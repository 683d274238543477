/* raycache/shared/coverage.h: which coarse direction cells a frame's leaving rays took, shared by C++ and
 * GLSL. An adaptive cube's face size follows (rays of a frame) / (texel area they spread over); the area
 * is measured on a coarse grid of 16 x 16 cells a face (1536 cells, one bit each): the covered share of
 * the cells times 6 N^2 (raycache/adaptive_resolution.hpp). The CPU's DirectionCoverage and the GPU's
 * frame buffer (raycache/shared/gpu_layout.h: 48 coverage words a cube) mark the same cell for a direction.
 *
 * Cell (face, column, row) of the 16 x 16 grid is the texel of a 16-texel face the direction falls in
 * (raycache_texel_of), bit (face * 16 + row) * 16 + column: bit (cell & 31) of word (cell >> 5).
 */
#ifndef RAYCACHE_SHARED_COVERAGE_H
#define RAYCACHE_SHARED_COVERAGE_H

#include "raycache/shared/cube_face.h"

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

#define RAYCACHE_COVERAGE_CELLS_PER_EDGE 16
#define RAYCACHE_COVERAGE_CELLS 1536u /* 6 * 16 * 16 */
#define RAYCACHE_COVERAGE_WORDS 48u   /* 32-bit words of one cube's cell bits */
/* Returned instead of a cell for a vector that is not a direction. */
#define RAYCACHE_NO_COVERAGE_CELL 0xFFFFFFFFu

/* The cell `direction` (need not be unit length) falls in, 0..1535; RAYCACHE_NO_COVERAGE_CELL when it is
 * not a direction. */
RAYCACHE_FN uint raycache_coverage_cell(vec3 direction) {
    raycache_texel_address a = raycache_texel_of(direction, RAYCACHE_COVERAGE_CELLS_PER_EDGE);
    if (a.face == RAYCACHE_NO_FACE) return RAYCACHE_NO_COVERAGE_CELL;
    return raycache_texel_linear_index(a, RAYCACHE_COVERAGE_CELLS_PER_EDGE);
}

/* The cell holding the centre of texel (face, column, row) of an N-texel face (N >= 16), found with
 * integers (a centre on a cell's edge counts in the cell after it): a ray already placed in a texel marks
 * its cell without a second face choice. */
RAYCACHE_FN uint raycache_coverage_cell_of_texel(raycache_texel_address t, int face_size) {
    raycache_texel_address c;
    c.face = t.face;
    c.column = (2 * t.column + 1) * (RAYCACHE_COVERAGE_CELLS_PER_EDGE / 2) / face_size;
    c.row = (2 * t.row + 1) * (RAYCACHE_COVERAGE_CELLS_PER_EDGE / 2) / face_size;
    return raycache_texel_linear_index(c, RAYCACHE_COVERAGE_CELLS_PER_EDGE);
}

/* A resting cube (raycache/resting.hpp) looks up one direction in 2^bits: RAYCACHE_PROBE_BITS when it
 * starts resting, and up to RAYCACHE_MAX_PROBE_BITS as its probes go on finding that it does not pay
 * (a cube that keeps resting pays for ever fewer probes). */
#ifndef RAYCACHE_PROBE_BITS
#define RAYCACHE_PROBE_BITS 4u
#endif
#ifndef RAYCACHE_MAX_PROBE_BITS
#define RAYCACHE_MAX_PROBE_BITS 8u
#endif
/* Whether `direction` is a probe direction of a resting cube probing one direction in 2^bits (bits is
 * clamped to RAYCACHE_PROBE_BITS..RAYCACHE_MAX_PROBE_BITS). Direction space is cut into boxes by the
 * sign, exponent and first three mantissa bits of each component (the top 12 bits of its float); a box
 * probes when the top `bits` bits of a multiplicative hash of its three keys are zero, so the probes at
 * bits + 1 are a half of those at bits. The same boxes every frame, without a face choice (a resting
 * cube's rays pay for this test alone). A direction's length matters (scale it and it may fall in
 * another box): pass the rays' unit directions. */
RAYCACHE_FN bool raycache_is_probe_direction_of(vec3 direction, uint bits) {
    uint key = (floatBitsToUint(direction.x) >> 20u) * 2654435761u;
    key = (key ^ (floatBitsToUint(direction.y) >> 20u)) * 2654435761u;
    key = (key ^ (floatBitsToUint(direction.z) >> 20u)) * 2654435761u;
    uint b = min(max(bits, uint(RAYCACHE_PROBE_BITS)), uint(RAYCACHE_MAX_PROBE_BITS));
    return (key >> (32u - b)) == 0u;
}
/* The probes of a cube that has just started resting: one direction in 2^RAYCACHE_PROBE_BITS. */
RAYCACHE_FN bool raycache_is_probe_direction(vec3 direction) {
    return raycache_is_probe_direction_of(direction, uint(RAYCACHE_PROBE_BITS));
}

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_COVERAGE_H */
