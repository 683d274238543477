/* raycache/shared/origin_rule.h: the CCT's origin test, shared by C++ (raycache::CacheCube's tiles) and GLSL
 * (raycache/cct.glsl with RAYCACHE_ORIGINS), so that both answer, refuse and drop the same texels.
 *
 * The CCT keys a texel by direction alone. A tile of 16 x 16 texels of a face keeps the box of the origins
 * its stores left from and the nearest surface they hit. A lookup from an origin more than the allowed drift
 * outside that box misses, and the tile is dropped between frames (it refills from the current rays); a
 * store that would stretch the box wider than the allowed drift on some axis is refused. The allowed drift
 * is min(drift, parallax x nearest): a surface at distance d seen from an origin moved by s shifts by about
 * s / d radians.
 *
 * GPU records (RAYCACHE_ORIGINS; buffer binding RAYCACHE_CCT_ORIGINS_BINDING, uint words): one record of
 * RAYCACHE_ORIGIN_RECORD_WORDS words per tile, the cube's tiles from its descriptor's first_tile on, in
 * raycache_origin_tile_index order. Every word holds RAYCACHE_GPU_CLEAR_WORD when the tile has no origins
 * (fill the buffer with it, with the texel buffers): boxes are kept as ordered keys of their lower corners
 * and complemented keys of their upper ones, so that both grow by atomicMin and the clear word is empty.
 */
#ifndef RAYCACHE_SHARED_ORIGIN_RULE_H
#define RAYCACHE_SHARED_ORIGIN_RULE_H

#include "raycache/shared/cube_face.h"
#include "raycache/shared/gpu_layout.h"
#include "raycache/shared/language.h"

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

/* Texels along a tile's edge, in C++ (CacheCube::tile_edge) and in GPU records. */
#define RAYCACHE_ORIGIN_TILE_EDGE 16u

/* A GPU record's words: the visible box (what lookups and stores read), this frame's stores (made visible
 * by the end-of-frame pass), and the marks. */
#define RAYCACHE_ORIGIN_LO 0u       /* 3 words: raycache_ordered_key of the box's lower corner */
#define RAYCACHE_ORIGIN_HI 3u       /* 3 words: ~raycache_ordered_key of its upper corner */
#define RAYCACHE_ORIGIN_NEAREST 6u  /* raycache_ordered_key of the nearest hit distance (clear: infinity) */
#define RAYCACHE_ORIGIN_PENDING 7u  /* 7 words: LO, HI, NEAREST of this frame's stores, at this offset */
#define RAYCACHE_ORIGIN_STALE 14u   /* 0: a lookup met an origin outside the box; drop the tile */
#define RAYCACHE_ORIGIN_LISTED 15u  /* 0: the tile is in this frame's store list */
#define RAYCACHE_ORIGIN_RECORD_WORDS 16u

/* A float's bits mapped so that unsigned order is the float's order (for atomic min and max on floats);
 * -0 maps as +0 (not by adding 0.0, which a shader compiler may fold away). */
RAYCACHE_FN uint raycache_ordered_key(float f) {
    uint bits = floatBitsToUint(f);
    if (bits == 0x80000000u) bits = 0u;
    return (bits & 0x80000000u) != 0u ? ~bits : (bits | 0x80000000u);
}
/* The float of an ordered key: a key with its top bit set loses it, any other is inverted (by one xor,
 * without a select: invalidation decodes thousands of keys a move). */
RAYCACHE_FN float raycache_key_float(uint key) {
    return uintBitsToFloat(key ^ (((key >> 31u) - 1u) | 0x80000000u));
}

/* The drift a tile allows whose nearest hit lies at `nearest`: min(drift, parallax x nearest); drift alone
 * when either factor of the product is not finite (infinite parallax: no bound by distance). */
RAYCACHE_FN float raycache_allowed_drift(float drift, float parallax, float nearest) {
    if (!(parallax < RAYCACHE_INFINITY) || !(nearest < RAYCACHE_INFINITY)) return drift;
    return min(drift, parallax * nearest);
}

/* Whether origin o lies within `allowed` of the box [lo, hi] on every axis. */
RAYCACHE_FN bool raycache_origin_covered(vec3 o, vec3 lo, vec3 hi, float allowed) {
    return o.x >= lo.x - allowed && o.x <= hi.x + allowed && o.y >= lo.y - allowed && o.y <= hi.y + allowed &&
           o.z >= lo.z - allowed && o.z <= hi.z + allowed;
}

/* Whether the box [lo, hi] grown by o stays at most `allowed` wide on every axis. */
RAYCACHE_FN bool raycache_origin_box_stays_within(vec3 lo, vec3 hi, vec3 o, float allowed) {
    return max(hi.x, o.x) - min(lo.x, o.x) <= allowed && max(hi.y, o.y) - min(lo.y, o.y) <= allowed &&
           max(hi.z, o.z) - min(lo.z, o.z) <= allowed;
}

/* Tiles along a face's edge for faces of face_size texels, and in a whole cube. */
RAYCACHE_FN uint raycache_origin_tiles_per_edge(int face_size) {
    return (uint(face_size) + RAYCACHE_ORIGIN_TILE_EDGE - 1u) / RAYCACHE_ORIGIN_TILE_EDGE;
}
RAYCACHE_FN uint raycache_origin_tile_count(int face_size) {
    uint t = raycache_origin_tiles_per_edge(face_size);
    return 6u * t * t;
}

/* The cube's tile holding texel a (0 .. raycache_origin_tile_count - 1): (face x t + row / 16) x t + column / 16. */
RAYCACHE_FN uint raycache_origin_tile_index(raycache_texel_address a, int face_size) {
    uint t = raycache_origin_tiles_per_edge(face_size);
    return (uint(a.face) * t + uint(a.row) / RAYCACHE_ORIGIN_TILE_EDGE) * t + uint(a.column) / RAYCACHE_ORIGIN_TILE_EDGE;
}

/* A record's word for one coordinate of a box's lower corner, and of its upper corner (complemented, so
 * that atomicMin widens both and the clear word is an empty box); the coordinate a corner's words hold. */
RAYCACHE_FN uint raycache_origin_corner_word(float x, bool upper) {
    return upper ? ~raycache_ordered_key(x) : raycache_ordered_key(x);
}
RAYCACHE_FN vec3 raycache_origin_corner(uint x, uint y, uint z, bool upper) {
    return upper ? vec3(raycache_key_float(~x), raycache_key_float(~y), raycache_key_float(~z))
                 : vec3(raycache_key_float(x), raycache_key_float(y), raycache_key_float(z));
}
/* Whether a record has a box (its first lower-corner word is not the clear word). */
RAYCACHE_FN bool raycache_origin_has_box(uint first_lo_word) {
    return first_lo_word != RAYCACHE_GPU_CLEAR_WORD;
}

/* The nearest hit distance a record's word holds (the clear word: infinity). */
RAYCACHE_FN float raycache_origin_nearest(uint word) {
    return word == RAYCACHE_GPU_CLEAR_WORD ? RAYCACHE_INFINITY : raycache_key_float(word);
}

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_ORIGIN_RULE_H */
