/* raycache/cube.glsl: what the CCT and the CDCT share in GLSL: the options, the texel a direction falls
 * in within a cube's buffers, and small float helpers evaluated in the C++ headers' order.
 *
 * The face table, tie rule and texel rounding come from raycache/shared/cube_face.h and the cube
 * descriptor from raycache/shared/gpu_layout.h, the same files the C++ library compiles.
 *
 * Options (define before the first RayCache include):
 *   RAYCACHE_SET         descriptor set of RayCache's buffers (default 0)
 *   RAYCACHE_READ_ONLY   lookups only: no pending or frame buffer, no store functions, no counters
 *                        (no atomics needed)
 *   RAYCACHE_END_FRAME   texel buffers writable, and the end-frame functions defined (for the pass
 *                        that runs between frames); otherwise texel buffers are readonly
 *   RAYCACHE_CONFIDENCE  the confidence test: doubtful-bit buffers, doubtful texels read as empty
 *                        (raycache/shared/gpu_layout.h; the mark pass: raycache/end_frame.glsl)
 *   RAYCACHE_ORIGINS     the CCT's origin test: origin records per tile, raycache_cct_lookup_from and
 *                        raycache_cct_store_from (raycache/shared/origin_rule.h; the drop pass:
 *                        raycache/end_frame.glsl)
 * Stores from a fragment shader need the device feature fragmentStoresAndAtomics.
 */
#ifndef RAYCACHE_CUBE_GLSL
#define RAYCACHE_CUBE_GLSL

#include "raycache/shared/cube_face.h"
#include "raycache/shared/texel_encoding.h"
#include "raycache/shared/gpu_layout.h"
#include "raycache/shared/ray_box.h"

#include "raycache/frame.glsl" /* RAYCACHE_SET defaults to 0 in raycache/shared/gpu_layout.h */

#if defined(RAYCACHE_READ_ONLY) && defined(RAYCACHE_END_FRAME)
#error "RayCache: RAYCACHE_READ_ONLY and RAYCACHE_END_FRAME exclude each other"
#endif

/* Access qualifier of the texel buffers: written only by the end-frame pass. */
#ifdef RAYCACHE_END_FRAME
#define RAYCACHE_TEXEL_ACCESS
#else
#define RAYCACHE_TEXEL_ACCESS readonly
#endif

/* Whether element's bit is set in a doubtful-bit buffer `bits` (uint bits[]; raycache/shared/gpu_layout.h):
 * whether its texel is doubtful. Always false without RAYCACHE_CONFIDENCE (no such buffer then). */
#ifdef RAYCACHE_CONFIDENCE
#define RAYCACHE_IS_DOUBTFUL(bits, element)                              \
    (raycache_doubtful_word(element) < uint(bits.length()) &&            \
     (bits[raycache_doubtful_word(element)] & raycache_doubtful_bit(element)) != 0u)
#else
#define RAYCACHE_IS_DOUBTFUL(bits, element) false
#endif

/* Returned instead of a buffer element when a vector has no texel. */
#define RAYCACHE_NO_TEXEL 0xFFFFFFFFu

/* True when the cube's face size is 1..4096 (anything else has no texels). */
bool raycache_cube_has_texels(raycache_gpu_cube cube) {
    return cube.face_size >= RAYCACHE_MIN_FACE_SIZE && cube.face_size <= RAYCACHE_MAX_FACE_SIZE;
}

/* The texel of the cube that s falls in (need not be unit length); face RAYCACHE_NO_FACE when s is not a
 * direction or the cube has no texels. */
raycache_texel_address raycache_cube_texel_address(raycache_gpu_cube cube, vec3 s) {
    if (raycache_cube_has_texels(cube)) return raycache_texel_of(s, cube.face_size);
    raycache_texel_address none;
    none.face = RAYCACHE_NO_FACE;
    none.column = 0;
    none.row = 0;
    return none;
}

/* Element of the cube's texel (and pending) buffer holding texel a; RAYCACHE_NO_TEXEL for no texel. */
uint raycache_cube_element(raycache_gpu_cube cube, raycache_texel_address a) {
    if (a.face == RAYCACHE_NO_FACE) return RAYCACHE_NO_TEXEL;
    return cube.first_texel + raycache_texel_linear_index(a, cube.face_size);
}

/* Element of the cube's texel (and pending) buffer holding the texel that s falls in; s need not be
 * unit length. RAYCACHE_NO_TEXEL when s is not a direction or the cube has no texels. Callers check
 * the element against the buffer's length before reading. */
uint raycache_cube_texel(raycache_gpu_cube cube, vec3 s) {
    return raycache_cube_element(cube, raycache_cube_texel_address(cube, s));
}

/* Whether a ray leaving the cube's object in unit `direction` passes the cube by this frame: the host started
 * the frame with the cube resting (raycache/gpu_resting.hpp) and the direction is not one of the probes
 * that keep measuring it (raycache_is_probe_direction_of with the bits of its resting word,
 * raycache/shared/coverage.h). Then trace the ray and
 * neither look it up nor store its colour; it is counted in the cube's `rested` counter. Ask before the
 * lookup, as C++'s SceneCache does:
 *   if (raycache_cube_rests(cube, d)) colour = trace(r);
 *   else { lookup; on a miss trace and store }
 * Always false under RAYCACHE_READ_ONLY (no frame buffer) and for a cube without texels. */
bool raycache_cube_rests(raycache_gpu_cube cube, vec3 direction) {
#ifdef RAYCACHE_READ_ONLY
    return false;
#else
    if (!raycache_cube_has_texels(cube)) return false;
    uint probe_bits = raycache_frame_cube_resting_word(cube.index);
    if (probe_bits == 0u || raycache_is_probe_direction_of(direction, probe_bits)) return false;
    raycache_frame_count(cube.index, RAYCACHE_FRAME_RESTED);
    return true;
#endif
}

/* Counts a lookup of `cube` as a hit or a miss in the frame buffer (nothing under RAYCACHE_READ_ONLY). */
void raycache_count_lookup(raycache_gpu_cube cube, bool hit) {
#ifndef RAYCACHE_READ_ONLY
    raycache_frame_count(cube.index, hit ? RAYCACHE_FRAME_HITS : RAYCACHE_FRAME_MISSES);
#endif
}

/* Counts a miss of `cube` on a texel that holds no value (a texel stored earlier in the same frame is among
 * them: lookups read published texels alone), from which the host tells whether the cube's rays come back to
 * texels already filled (raycache/gpu_adaptive.hpp: finer faces for still cameras). Only while the frame's
 * flags hold RAYCACHE_FRAME_MARK_COVERAGE (adaptive sizes, its one reader), so fixed-size frames pay no
 * second atomic on a miss; nothing under RAYCACHE_READ_ONLY. */
void raycache_count_empty(raycache_gpu_cube cube) {
#ifndef RAYCACHE_READ_ONLY
    if ((raycache_frame[RAYCACHE_FRAME_FLAGS] & RAYCACHE_FRAME_MARK_COVERAGE) != 0u) raycache_frame_count(cube.index, RAYCACHE_FRAME_EMPTY);
#endif
}

/* raycache_count_lookup for a ray going in `direction`, also marking its direction cell (when the frame's
 * flags ask for it), from which the host chooses adaptive face sizes (raycache/gpu_adaptive.hpp). The CCT's
 * lookup and the CDCT's searches call it. */
void raycache_count_lookup_toward(raycache_gpu_cube cube, vec3 direction, bool hit) {
    raycache_count_lookup(cube, hit);
#ifndef RAYCACHE_READ_ONLY
    raycache_frame_mark_direction(cube.index, direction);
#endif
}

#endif /* RAYCACHE_CUBE_GLSL */
