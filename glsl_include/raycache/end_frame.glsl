/* raycache/end_frame.glsl: the end-of-frame pass of RayCache's GPU frame protocol, for both techniques: it
 * publishes the texels listed in the frame buffer's store list (raycache/frame.glsl) and nothing else, so
 * its cost follows the frame's stores, not the buffers' size. A whole compute shader is five lines:
 *
 *   #version 450
 *   #extension GL_GOOGLE_include_directive : require
 *   #define RAYCACHE_END_FRAME
 *   #define RAYCACHE_CDCT                      // only when CDCT cubes are in use (needs 64-bit atomics)
 *   #include "raycache/end_frame.glsl"
 *   layout(local_size_x = RAYCACHE_END_FRAME_GROUP_SIZE) in;
 *   void main() { raycache_end_frame_pass(); }
 *
 * Dispatch it with vkCmdDispatchIndirect on the frame buffer at byte offset 4 * RAYCACHE_FRAME_DISPATCH (the
 * stores keep that count), or directly with raycache::gpu_end_frame_groups(listed) groups; with the texel,
 * pending and frame buffers bound as in the frame, after a barrier that makes the frame's shader writes
 * visible to the indirect read and to this pass.
 *
 * The confidence test (RAYCACHE_CONFIDENCE defined here and in the frame's shaders; raycache/shared/gpu_layout.h)
 * adds a second pass over the same list, the mark pass, with the doubtful-bit buffers and cube tables bound
 * too: record a barrier (shader write -> shader read) after the pass above, then dispatch this one the same
 * way (the list and its group count are unchanged). The threshold comes from the shader, e.g.
 *
 *   layout(push_constant) uniform Edge { float threshold; };
 *   void main() { raycache_end_frame_mark_pass(threshold); }
 *
 * The origin test (RAYCACHE_ORIGINS, CCT; raycache/shared/origin_rule.h) lists tiles in the same list: the
 * publish pass makes their stores' origins visible, and a third pass, the drop pass, empties the tiles that
 * a lookup met from too far, with the CCT's cube table and origin records bound: after the mark pass (or
 * after the publish pass without the confidence test) record a barrier and dispatch
 *
 *   void main() { raycache_end_frame_drop_pass(); }
 *
 * the same way. Its sweep: raycache_cct_end_frame_tile for every tile with the publish sweep, and
 * raycache_cct_drop_tile for every tile after the mark sweep.
 *
 * After a list overflow, the sweep (every element through raycache_cct_end_frame / raycache_cdct_end_frame),
 * a barrier, and raycache_mark_edges for every element of both techniques: that compares every filled texel
 * with its neighbours, not only this frame's, which marks what the listed pass and C++ mark as long as the
 * threshold is the same from frame to frame (the older pairs were compared when stored, and marks only get
 * set); its cost follows the buffers' size, as the sweep's does.
 */
#ifndef RAYCACHE_END_FRAME_GLSL
#define RAYCACHE_END_FRAME_GLSL

#include "raycache/cct.glsl"
#ifdef RAYCACHE_CDCT
#include "raycache/cdct.glsl"
#endif
#if defined(RAYCACHE_END_FRAME) && (defined(RAYCACHE_CONFIDENCE) || defined(RAYCACHE_ORIGINS))
#include "raycache/shared/edge_rule.h"
/* The cube tables (raycache/shared/gpu_layout.h): each technique's cubes by increasing first_texel (and so
 * by increasing first_tile). */
layout(std430, set = RAYCACHE_CCT_SET, binding = RAYCACHE_CCT_CUBES_BINDING) readonly buffer raycache_cct_cube_table {
    raycache_gpu_cube raycache_cct_cubes[];
};
#if defined(RAYCACHE_CDCT) && defined(RAYCACHE_CONFIDENCE)
layout(std430, set = RAYCACHE_CDCT_SET, binding = RAYCACHE_CDCT_CUBES_BINDING) readonly buffer raycache_cdct_cube_table {
    raycache_gpu_cube raycache_cdct_cubes[];
};
#endif
#endif

#ifdef RAYCACHE_END_FRAME
/* Publishes one store-list entry (a CDCT entry is ignored unless RAYCACHE_CDCT is defined, a tile entry
 * unless RAYCACHE_ORIGINS is). */
void raycache_end_frame_entry(uint entry) {
    uint element = entry & ~RAYCACHE_FRAME_CDCT_ENTRY;
    if ((entry & RAYCACHE_FRAME_CDCT_ENTRY) == 0u) {
        if ((entry & RAYCACHE_FRAME_TILE_ENTRY) == 0u) raycache_cct_end_frame(element);
#ifdef RAYCACHE_ORIGINS
        else raycache_cct_end_frame_tile(entry & ~RAYCACHE_FRAME_TILE_ENTRY);
#endif
    } else {
#ifdef RAYCACHE_CDCT
        raycache_cdct_end_frame(element);
#endif
    }
}

/* Store-list entry k for invocation k of a pass over the list; false when there is none. */
bool raycache_end_frame_listed_entry(out uint entry) {
    entry = 0u;
    uint listed = min(raycache_frame[RAYCACHE_FRAME_LIST_COUNT], raycache_frame[RAYCACHE_FRAME_LIST_CAPACITY]);
    uint k = gl_GlobalInvocationID.x;
    if (k >= listed) return false;
    uint word = raycache_frame_list_word(raycache_frame[RAYCACHE_FRAME_CUBE_COUNT], k);
    if (word >= uint(raycache_frame.length())) return false;
    entry = raycache_frame[word];
    return true;
}

/* The pass's body, for a 1D dispatch of raycache_end_frame_groups(listed) groups: invocation k publishes
 * entry k. No loop: on lavapipe a grid-stride loop here made the pass about 50 times slower, so the list
 * holds at most RAYCACHE_END_FRAME_MAX_ENTRIES (the host's capacity is capped there). */
void raycache_end_frame_pass() {
    uint entry;
    if (raycache_end_frame_listed_entry(entry)) raycache_end_frame_entry(entry);
}

#ifdef RAYCACHE_ORIGINS
/* The CCT cube whose tiles hold origin record `tile` (false when none): a binary search of the cube table
 * for the last cube whose first_tile is at or before it. */
bool raycache_cct_cube_holding_tile(uint tile, out raycache_gpu_cube cube) {
    uint lo = 0u, hi = uint(raycache_cct_cubes.length());
    cube = raycache_make_gpu_cube(vec3(0.0), 0.0, 0u, 0);
    if (hi == 0u) return false;
    while (hi - lo > 1u) {
        uint mid = lo + (hi - lo) / 2u;
        if (raycache_cct_cubes[mid].first_tile <= tile) lo = mid;
        else hi = mid;
    }
    cube = raycache_cct_cubes[lo];
    return raycache_cube_has_texels(cube) && tile >= cube.first_tile &&
           tile - cube.first_tile < raycache_origin_tile_count(cube.face_size);
}

/* The drop pass for one tile: when a lookup marked it stale this frame, its texels are emptied (their
 * doubtful bits too) and its record cleared, as C++ drops a stale tile in begin_frame(). Runs after the
 * publish pass and the mark pass (which still compare the tile's texels, as C++'s confidence test does
 * before begin_frame()). Calling it for every tile is the sweep's drop pass. */
void raycache_cct_drop_tile(uint tile) {
    uint r = tile * RAYCACHE_ORIGIN_RECORD_WORDS;
    if (tile >= RAYCACHE_FRAME_TILE_ENTRY || r + RAYCACHE_ORIGIN_RECORD_WORDS > uint(raycache_cct_origins.length()) ||
        raycache_cct_origins[r + RAYCACHE_ORIGIN_STALE] != 0u)
        return;
    raycache_gpu_cube cube;
    if (raycache_cct_cube_holding_tile(tile, cube)) {
        uint n = uint(cube.face_size), t = raycache_origin_tiles_per_edge(cube.face_size), local = tile - cube.first_tile;
        uint face = local / (t * t);
        uint row0 = (local / t) % t * RAYCACHE_ORIGIN_TILE_EDGE, column0 = local % t * RAYCACHE_ORIGIN_TILE_EDGE;
        uint count = min(column0 + RAYCACHE_ORIGIN_TILE_EDGE, n) - column0; // the tile's texels in a row
        for (uint row = row0; row < min(row0 + RAYCACHE_ORIGIN_TILE_EDGE, n); ++row) {
            uint first = cube.first_texel + (face * n + row) * n + column0, last = first + count - 1u;
            for (uint e = first; e <= last; ++e)
                if (e < uint(raycache_cct_texels.length())) raycache_cct_texels[e] = RAYCACHE_GPU_CLEAR_WORD;
#ifdef RAYCACHE_CONFIDENCE
            /* The row's doubtful bits (one or two words), cleared by mask without reading them first: no
             * load waits in the loop (with a read a texel, this pass took 0.4 ms a frame on an NVIDIA H200).
             * Other tiles' bits share the words, hence atomicAnd. */
            for (uint w = raycache_doubtful_word(first); w <= raycache_doubtful_word(last); ++w) {
                uint lo = max(first, w * 32u) - w * 32u, hi = min(last, w * 32u + 31u) - w * 32u;
                uint bits = hi - lo == 31u ? 0xFFFFFFFFu : ((1u << (hi - lo + 1u)) - 1u) << lo;
                if (w < uint(raycache_cct_doubtful.length())) atomicAnd(raycache_cct_doubtful[w], ~bits);
            }
#endif
        }
    }
    for (uint w = 0u; w < RAYCACHE_ORIGIN_RECORD_WORDS; ++w) raycache_cct_origins[r + w] = RAYCACHE_GPU_CLEAR_WORD;
}
#endif

/* The drop pass's body (RAYCACHE_ORIGINS), dispatched as raycache_end_frame_pass after the publish pass and
 * the mark pass (barriers between): invocation k drops the tile of entry k if a lookup marked it stale.
 * Does nothing without RAYCACHE_ORIGINS. */
void raycache_end_frame_drop_pass() {
#ifdef RAYCACHE_ORIGINS
    uint entry;
    if (raycache_end_frame_listed_entry(entry) &&
        (entry & (RAYCACHE_FRAME_CDCT_ENTRY | RAYCACHE_FRAME_TILE_ENTRY)) == RAYCACHE_FRAME_TILE_ENTRY)
        raycache_cct_drop_tile(entry & ~RAYCACHE_FRAME_TILE_ENTRY);
#endif
}

#ifdef RAYCACHE_CONFIDENCE
/* Cube k of the technique's cube table (the CDCT's: cdct), and the table's length (0 for a technique this
 * shader does not include). */
uint raycache_cube_table_length(bool cdct) {
    if (cdct) {
#ifdef RAYCACHE_CDCT
        return uint(raycache_cdct_cubes.length());
#else
        return 0u;
#endif
    }
    return uint(raycache_cct_cubes.length());
}
raycache_gpu_cube raycache_cube_table_entry(bool cdct, uint k) {
#ifdef RAYCACHE_CDCT
    if (cdct) return raycache_cdct_cubes[k];
#endif
    return raycache_cct_cubes[k];
}

/* The cube of the technique's table whose texels hold `element` (false when none). The table lists the
 * cubes by increasing first_texel: a binary search for the last one starting at or before `element`. */
bool raycache_cube_holding(bool cdct, uint element, out raycache_gpu_cube cube) {
    uint lo = 0u, hi = raycache_cube_table_length(cdct);
    if (hi == 0u) return false;
    while (hi - lo > 1u) {
        uint mid = lo + (hi - lo) / 2u;
        if (raycache_cube_table_entry(cdct, mid).first_texel <= element) lo = mid;
        else hi = mid;
    }
    cube = raycache_cube_table_entry(cdct, lo);
    return raycache_cube_has_texels(cube) && element >= cube.first_texel &&
           element - cube.first_texel < raycache_gpu_cube_texel_count(cube.face_size);
}

/* The colour of element's visible texel (false when it is empty or past the buffer). */
bool raycache_visible_colour(bool cdct, uint element, out vec3 colour) {
    colour = vec3(0.0);
    if (cdct) {
#ifdef RAYCACHE_CDCT
        if (element >= uint(raycache_cdct_texels.length())) return false;
        uvec2 texel = raycache_cdct_texels[element];
        colour = raycache_cdct_color(texel);
        return raycache_cdct_is_valid(texel);
#else
        return false;
#endif
    }
    if (element >= uint(raycache_cct_texels.length())) return false;
    uint word = raycache_cct_texels[element];
    colour = raycache_unpack_rgb9e5(word);
    return raycache_cct_is_valid(word);
}

/* Sets element's doubtful bit (atomicOr: marks from any number of invocations add up). */
void raycache_mark_doubtful(bool cdct, uint element) {
    uint w = raycache_doubtful_word(element);
    if (cdct) {
#ifdef RAYCACHE_CDCT
        if (w < uint(raycache_cdct_doubtful.length())) atomicOr(raycache_cdct_doubtful[w], raycache_doubtful_bit(element));
#endif
        return;
    }
    if (w < uint(raycache_cct_doubtful.length())) atomicOr(raycache_cct_doubtful[w], raycache_doubtful_bit(element));
}

/* The confidence test for one texel of a technique's buffers (the CDCT's: cdct), as C++'s
 * raycache::mark_doubtful_edges for one written texel: when it holds a value, it and each filled neighbour
 * on its face (left, right, up, down) whose colours differ by more than `threshold` are marked doubtful.
 * Reads texel words only, so any number of invocations may run it at once, in any order. */
void raycache_mark_edges(bool cdct, uint element, float threshold) {
    raycache_gpu_cube cube;
    vec3 own;
    if (!raycache_edge_test_enabled(threshold) || !raycache_cube_holding(cdct, element, cube) ||
        !raycache_visible_colour(cdct, element, own))
        return;
    uint n = uint(cube.face_size), local = element - cube.first_texel;
    uint column = local % n, row = (local / n) % n;
    uint neighbours[4];
    neighbours[0] = column > 0u ? element - 1u : RAYCACHE_NO_TEXEL;
    neighbours[1] = column + 1u < n ? element + 1u : RAYCACHE_NO_TEXEL;
    neighbours[2] = row > 0u ? element - n : RAYCACHE_NO_TEXEL;
    neighbours[3] = row + 1u < n ? element + n : RAYCACHE_NO_TEXEL;
    for (int k = 0; k < 4; ++k) {
        vec3 other;
        if (neighbours[k] == RAYCACHE_NO_TEXEL || !raycache_visible_colour(cdct, neighbours[k], other) ||
            !raycache_colours_differ(own, other, threshold))
            continue;
        raycache_mark_doubtful(cdct, element);
        raycache_mark_doubtful(cdct, neighbours[k]);
    }
}

/* The mark pass's body, dispatched as raycache_end_frame_pass after it (and a barrier): invocation k runs
 * the confidence test for entry k. threshold < 0 or NaN: nothing is marked. */
void raycache_end_frame_mark_pass(float threshold) {
    uint entry;
    if (raycache_edge_test_enabled(threshold) && raycache_end_frame_listed_entry(entry) &&
        (entry & (RAYCACHE_FRAME_CDCT_ENTRY | RAYCACHE_FRAME_TILE_ENTRY)) != RAYCACHE_FRAME_TILE_ENTRY)
        raycache_mark_edges((entry & RAYCACHE_FRAME_CDCT_ENTRY) != 0u, entry & ~RAYCACHE_FRAME_CDCT_ENTRY, threshold);
}
#endif
#endif

#endif /* RAYCACHE_END_FRAME_GLSL */
