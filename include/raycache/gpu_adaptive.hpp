// raycache/gpu_adaptive.hpp: adaptive face sizes for GPU cubes, chosen on the host from what a frame's
// lookups counted, and the texels moved into a layout with the new sizes. No graphics API.
//
// Why: as on the CPU (raycache/adaptive_resolution.hpp), a cube whose texels outnumber the rays that reach
// it fills too slowly to be read along a moving camera, and costs memory no ray uses. The GPU's lookups
// count themselves and mark the direction cell they took in the frame buffer (raycache/shared/coverage.h,
// raycache/gpu_frame.hpp), so the host can choose each cube's size by SceneCache's rule (adapted_face_size;
// the cells are marked by direction, where SceneCache's CCT marks by texel, every cell a texel overlaps on
// faces under 16 texels).
//
// The cubes of a technique lie one after another in one texel buffer (raycache/gpu_buffers.hpp), so a cube
// that changes size moves the cubes after it. Between frames, with the device done with the buffers:
//   1. read_gpu_statistics() after the frame, then
//      GpuFaceSizes next = next_gpu_face_sizes<Texel>(adaptive, layout, statistics, sized, max_buffer_bytes);
//   2. if next.changed: new_layout = gpu_buffer_layout<Texel>(the shapes with next.face_sizes); new texel and
//      pending buffers filled with gpu_clear_word, a new doubtful-bit buffer with 0; then
//      move_gpu_cubes<Texel>(layout, old texel words, old doubtful words, new_layout, new texel words, new
//      doubtful words, edge_threshold); bind the new buffers and descriptors (new_layout.cubes) from the
//      next frame on, and size the frame buffer's store list for the new texel count.
// move_gpu_cubes copies a cube that kept its size; fills a smaller one from its old texels (each new texel
// takes the old texel nearest its centre: raycache::resample_into, then the confidence test over them, as
// SceneCache resizes a CPU cube); leaves a larger one empty (its next frame is cold for that object, as a
// growing CPU cube's).
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "raycache/adaptive_resolution.hpp"
#include "raycache/cache_cube.hpp"
#include "raycache/edge_confidence.hpp"
#include "raycache/gpu_buffers.hpp"
#include "raycache/gpu_frame.hpp"

namespace raycache {

// The face sizes a layout's cubes take after a frame, in the layout's order; changed: any differs.
struct GpuFaceSizes {
    std::vector<int> face_sizes;
    bool changed = false;
};

// Each cube's next face size from its frame counters (the statistics of descriptor index cubes[k].index):
// adapted_face_size() of its lookups and the share of direction cells they took. `sized` (one flag per
// cube, all false before the first frame; updated here) says whether a frame with rays has sized the cube
// (a cube that rested in the frame keeps its size and its flag):
// until then it moves to the ideal size at once, and waits at adaptive.min_face_size (or its own size, if
// smaller) while it gets no ray at all. Then, if the cubes would pass `max_buffer_bytes` (the
// device's maxStorageBufferRange), the largest are lowered to fit (fit_gpu_face_sizes); a cube so lowered
// grows again only when the cap rises by the hysteresis. With `still` (one state per cube, default-made
// before the first frame; updated here), a cube whose rays hold still takes finer faces, at
// adaptive.still_rays_per_texel, by SceneCache's rule (next_still_rays, still_face_size: the misses on
// texels holding no value, RAYCACHE_FRAME_EMPTY, say whether its rays come back to the same texels; a
// resized cube's next frame is not judged). Throws std::invalid_argument when `sized` (or `still`) does not
// have one entry per cube, a descriptor's index has no statistics, or a size is not 1..4096.
template <class Texel>
GpuFaceSizes next_gpu_face_sizes(const AdaptiveResolution& adaptive, const GpuBufferLayout& layout,
                                 const GpuFrameStatistics& frame, std::vector<bool>& sized, std::uint64_t max_buffer_bytes,
                                 std::vector<StillRays>* still = nullptr) {
    validate(adaptive);
    if (!frame.coverage_marked)
        throw std::invalid_argument("RayCache: next_gpu_face_sizes needs the frame's direction cells: start the frame with "
                                    "gpu_frame_start_words(layout, true)");
    if (sized.size() != layout.cubes.size())
        throw std::invalid_argument("RayCache: next_gpu_face_sizes needs one `sized` flag per cube (" +
                                    std::to_string(layout.cubes.size()) + "), got " + std::to_string(sized.size()));
    if (still && still->size() != layout.cubes.size())
        throw std::invalid_argument("RayCache: next_gpu_face_sizes needs one StillRays per cube (" +
                                    std::to_string(layout.cubes.size()) + "), got " + std::to_string(still->size()));
    std::vector<int> sizes;
    sizes.reserve(layout.cubes.size());
    for (std::size_t k = 0; k < layout.cubes.size(); ++k) {
        const shared::raycache_gpu_cube& cube = layout.cubes[k];
        if (cube.index >= frame.cubes.size() || cube.index >= frame.coverage.size())
            throw std::invalid_argument("RayCache: GPU cube " + std::to_string(k) + " counts into index " +
                                        std::to_string(cube.index) + ", past the frame's " +
                                        std::to_string(frame.cubes.size()) + " cubes");
        const std::uint64_t rays = frame.cubes[cube.index].lookups;
        // A cube that rested (raycache/gpu_resting.hpp) marked only its probes' cells: the size it had stays.
        if (cube.index < frame.resting.size() && frame.resting[cube.index]) {
            sizes.push_back(cube.face_size);
            if (still) (*still)[k].settled_frames = 0;
            continue;
        }
        // A cube no ray has reached yet waits at the smallest size: unlike a CPU cube, whose tiles cost only
        // once stored into, a GPU cube's texels are all allocated (an object seen only in other objects'
        // reflections may never get a lookup of its own: the GLSL tracers do not recurse).
        int size = !sized[k] && rays == 0 ? std::max(std::min(cube.face_size, adaptive.min_face_size), 1)
                                          : adapted_face_size(cube.face_size, sized[k], rays, frame.coverage[cube.index], adaptive);
        if (still)
            size = face_size_with_still_rule(cube.face_size, size, sized[k], frame.cubes[cube.index], frame.coverage[cube.index],
                                             (*still)[k], adaptive);
        sizes.push_back(size);
        sized[k] = sized[k] || rays > 0;
    }
    GpuFaceSizes next;
    next.face_sizes = fit_gpu_face_sizes(sizes, gpu_words_per_texel<Texel> * sizeof(std::uint32_t), max_buffer_bytes);
    for (std::size_t k = 0; k < layout.cubes.size(); ++k) {
        // The buffer's cap moves with every other cube's size, and a cube that grows starts empty: a cube held
        // below its size by the cap grows only when the cap has risen by the hysteresis (keeping it smaller
        // never breaks the fit).
        const int current = layout.cubes[k].face_size, fitted = next.face_sizes[k];
        if (fitted > current && fitted < sizes[k] &&
            2.0 * std::log2(static_cast<double>(fitted) / current) < adaptive.hysteresis_steps - 1e-9)
            next.face_sizes[k] = current;
        next.changed = next.changed || next.face_sizes[k] != current;
        // A resized cube starts empty or coarser: its next frame's misses say nothing about its rays.
        if (still && next.face_sizes[k] != current) (*still)[k].resized = true;
    }
    return next;
}


// Moves cube k of layout `from` into cube k of layout `to` for every k (the same cubes, in the same order,
// other face sizes): `words` and `doubtful` hold the old texel buffer's and doubtful-bit buffer's contents
// (from.words and from.doubtful_words 32-bit words; doubtful may be null: none marked), `new_words` and
// `new_doubtful` the new ones (to.words and to.doubtful_words words, already cleared: gpu_clear_word, 0;
// new_doubtful may be null). A cube of the same size is copied with its doubtful bits; a smaller one is
// resampled from the old texels and its texels tested for edges (`edge_threshold`, as the mark pass: < 0
// off); a larger one is left empty. With `origins` and `new_origins` (the CCT's origin records,
// from.origin_words and to.origin_words words, the new ones cleared), a cube of the same size keeps its
// tiles' visible origin boxes, a smaller one's tiles get the union of the boxes its texels came from
// (raycache::resample_into), a larger one none. Returns the texels written. Throws std::invalid_argument
// when the layouts do not hold the same number of cubes.
template <class Texel>
std::size_t move_gpu_cubes(const GpuBufferLayout& from, const std::uint32_t* words, const std::uint32_t* doubtful,
                           const GpuBufferLayout& to, std::uint32_t* new_words, std::uint32_t* new_doubtful,
                           float edge_threshold, const std::uint32_t* origins = nullptr, std::uint32_t* new_origins = nullptr) {
    if (from.cubes.size() != to.cubes.size())
        throw std::invalid_argument("RayCache: move_gpu_cubes needs the same cubes in both layouts (" +
                                    std::to_string(from.cubes.size()) + " and " + std::to_string(to.cubes.size()) + ")");
    constexpr std::size_t per_texel = gpu_words_per_texel<Texel>;
    std::size_t written = 0;
    for (std::size_t k = 0; k < from.cubes.size(); ++k) {
        const shared::raycache_gpu_cube& old_cube = from.cubes[k];
        const shared::raycache_gpu_cube& new_cube = to.cubes[k];
        const std::uint32_t count = shared::raycache_gpu_cube_texel_count(new_cube.face_size);
        if (new_cube.face_size == old_cube.face_size) {
            for (std::uint32_t i = 0; i < count; ++i) {
                const std::size_t a = (std::size_t{old_cube.first_texel} + i) * per_texel;
                const std::size_t b = (std::size_t{new_cube.first_texel} + i) * per_texel;
                for (std::size_t w = 0; w < per_texel; ++w) new_words[b + w] = words[a + w];
                if (new_words[b] != gpu_clear_word) ++written;
                if (doubtful && new_doubtful && gpu_doubtful(doubtful, from.doubtful_words, old_cube.first_texel + i))
                    set_gpu_doubtful(new_doubtful, new_cube.first_texel + i);
            }
            if (origins && new_origins) { // the visible words of each record; the rest stay clear
                const std::size_t a = detail::first_origin_word(old_cube, static_cast<std::size_t>(from.origin_words));
                const std::size_t b = detail::first_origin_word(new_cube, static_cast<std::size_t>(to.origin_words));
                for (std::uint32_t t = 0; t < shared::raycache_origin_tile_count(new_cube.face_size); ++t)
                    for (std::uint32_t w = 0; w < RAYCACHE_ORIGIN_PENDING; ++w)
                        new_origins[b + t * RAYCACHE_ORIGIN_RECORD_WORDS + w] = origins[a + t * RAYCACHE_ORIGIN_RECORD_WORDS + w];
            }
            continue;
        }
        if (new_cube.face_size > old_cube.face_size) continue; // grows: starts empty
        CacheCube<Texel> fine(old_cube.face_size), coarse(new_cube.face_size);
        read_gpu_words(fine, old_cube, words, static_cast<std::size_t>(from.words));
        if (origins) read_gpu_origins(fine, old_cube, origins, static_cast<std::size_t>(from.origin_words));
        fine.begin_frame();
        written += resample_into(fine, coarse);
        mark_doubtful_edges(coarse, edge_threshold); // over the resampled texels, which are this frame's stores
        coarse.begin_frame();
        write_gpu_words(coarse, new_cube, new_words, static_cast<std::size_t>(to.words));
        if (origins && new_origins) write_gpu_origins(coarse, new_cube, new_origins, static_cast<std::size_t>(to.origin_words));
        if (new_doubtful)
            coarse.for_each_valid_texel([&](const TexelAddress& t) {
                if (coarse.is_doubtful(t))
                    set_gpu_doubtful(new_doubtful, gpu_element(new_cube, t));
            });
    }
    return written;
}

} // namespace raycache
