// raycache/gpu_frame.hpp: the host side of RayCache's GPU frame protocol (raycache/shared/gpu_layout.h), with
// no graphics API: the binding numbers, the frame buffer's size and its contents before each frame, the
// end-of-frame pass's dispatch size, the GPU statistics read back after a frame (with each cube's direction
// coverage, for adaptive face sizes: raycache/gpu_adaptive.hpp), and face sizes that fit a device's largest
// storage buffer.
//
// A frame, in Vulkan terms (README "In your own Vulkan shaders" walks through it):
//   1. before it: copy gpu_frame_start_words(frame, mark_coverage, resting_words) into the frame buffer
//      (vkCmdUpdateBuffer or a copy; `resting_words`: raycache/gpu_resting.hpp, or none), then barrier (transfer
//      write -> shader read and write; it also covers the first frame's fill);
//   2. the frame's shaders look up and store (raycache/cct.glsl, cdct.glsl);
//   3. barrier (shader write -> indirect read and shader read), then the end-of-frame pass
//      (raycache/end_frame.glsl) by vkCmdDispatchIndirect at gpu_end_frame_dispatch_offset; with the
//      confidence test (RAYCACHE_CONFIDENCE), a barrier (shader write -> shader read) and the mark pass,
//      dispatched the same way;
//   4. barrier (shader write -> host read, or transfer read for a copy), and once the frame is done read the
//      frame buffer back: read_gpu_statistics(); when its overflow is non-zero, run the sweep
//      (gpu_sweep_groups) before the next frame.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "raycache/cube_face.hpp"
#include "raycache/statistics.hpp"
#include "raycache/shared/gpu_layout.h"

namespace raycache {

// The binding numbers the GLSL include uses (set RAYCACHE_SET), as the shaders see them when the macros
// are left at their defaults (or defined the same way before this header).
struct GpuBindings {
    std::uint32_t cct_texels = RAYCACHE_CCT_BINDING;
    std::uint32_t cct_pending = RAYCACHE_CCT_PENDING_BINDING;
    std::uint32_t cdct_texels = RAYCACHE_CDCT_BINDING;
    std::uint32_t cdct_pending = RAYCACHE_CDCT_PENDING_BINDING;
    std::uint32_t frame = RAYCACHE_FRAME_BINDING;
    // The confidence test's (shaders that define RAYCACHE_CONFIDENCE): doubtful bits, cube tables.
    std::uint32_t cct_doubtful = RAYCACHE_CCT_DOUBTFUL_BINDING;
    std::uint32_t cdct_doubtful = RAYCACHE_CDCT_DOUBTFUL_BINDING;
    std::uint32_t cct_cubes = RAYCACHE_CCT_CUBES_BINDING;
    std::uint32_t cdct_cubes = RAYCACHE_CDCT_CUBES_BINDING;
};
inline constexpr GpuBindings gpu_bindings{};

// The frame buffer: counters for `cube_count` cubes (descriptor indices 0 .. cube_count - 1) and a store list
// of `list_capacity` entries.
struct GpuFrameLayout {
    std::uint32_t cube_count = 0;
    std::uint32_t list_capacity = 0;
    std::uint64_t words = 0; // 32-bit words of the frame buffer
    std::uint64_t bytes = 0; // create it this size (usage: storage, indirect, transfer destination)
    std::uint64_t start_bytes = 0; // the part to rewrite before every frame (header and counters)
};

// Each texel is listed at most once a frame, so a capacity of the texel count (of both techniques' buffers
// together) never overflows; a smaller one saves memory, and a frame that stores more texels overflows
// (read_gpu_statistics tells: run the sweep). Throws std::invalid_argument when the capacity passes
// RAYCACHE_END_FRAME_MAX_ENTRIES (16,776,960: what one dimension of groups covers) or the buffer would pass
// `max_bytes` (the device's maxStorageBufferRange).
inline GpuFrameLayout gpu_frame_layout(std::uint32_t cube_count, std::uint32_t list_capacity,
                                       std::uint64_t max_bytes = ~std::uint64_t{0}) {
    GpuFrameLayout f;
    f.cube_count = cube_count;
    f.list_capacity = list_capacity;
    f.words = std::uint64_t{RAYCACHE_FRAME_HEADER_WORDS} + std::uint64_t{cube_count} * RAYCACHE_FRAME_CUBE_WORDS + list_capacity;
    f.bytes = f.words * 4;
    f.start_bytes = (f.words - list_capacity) * 4;
    if (list_capacity > RAYCACHE_END_FRAME_MAX_ENTRIES || f.bytes > max_bytes)
        throw std::invalid_argument("RayCache: a frame buffer for " + std::to_string(cube_count) + " cubes and " +
                                    std::to_string(list_capacity) + " list entries needs " + std::to_string(f.bytes) +
                                    " bytes, more than " + std::to_string(max_bytes));
    return f;
}

// Throws std::invalid_argument unless `f`'s sizes are the ones gpu_frame_layout() gives its cube count and list
// capacity: the functions below index the frame buffer by those, so a layout filled in by hand with other
// sizes would make them read or write past it.
inline void check_gpu_frame_layout(const GpuFrameLayout& f) {
    const GpuFrameLayout expected = gpu_frame_layout(f.cube_count, f.list_capacity);
    if (f.start_bytes != expected.start_bytes || f.words != expected.words || f.bytes != expected.bytes)
        throw std::invalid_argument("RayCache: a GpuFrameLayout for " + std::to_string(f.cube_count) + " cubes and " +
                                    std::to_string(f.list_capacity) + " list entries must have the sizes gpu_frame_layout() gives (" +
                                    std::to_string(expected.start_bytes) + " start bytes, " + std::to_string(expected.words) +
                                    " words), got " + std::to_string(f.start_bytes) + " and " + std::to_string(f.words));
}

// The largest list capacity that keeps the frame buffer within `max_bytes` for `cube_count` cubes, no larger
// than `texels` (more could never be used) nor RAYCACHE_END_FRAME_MAX_ENTRIES. 0 when not even the counters fit.
inline std::uint32_t gpu_frame_list_capacity(std::uint32_t cube_count, std::uint64_t texels, std::uint64_t max_bytes) {
    const std::uint64_t fixed = std::uint64_t{RAYCACHE_FRAME_HEADER_WORDS} + std::uint64_t{cube_count} * RAYCACHE_FRAME_CUBE_WORDS;
    const std::uint64_t room = max_bytes / 4 > fixed ? max_bytes / 4 - fixed : 0;
    return static_cast<std::uint32_t>(std::min<std::uint64_t>({room, texels, RAYCACHE_END_FRAME_MAX_ENTRIES}));
}

// The frame buffer's first start_bytes before a frame: header (list empty, capacity, cube count, dispatch
// {0, 1, 1}, flags), zeroed counters and each cube's resting word. Upload them before every frame.
// mark_coverage: lookups mark their direction cells, which next_gpu_face_sizes needs
// (raycache/gpu_adaptive.hpp); false for fixed face sizes, whose lookups then skip that work
// (GpuFrameStatistics::coverage reads 0). resting: empty (no cube rests) or one resting word per cube, by
// descriptor index (GpuResting::resting_words(), raycache/gpu_resting.hpp: 0 works, else the cube rests and
// probes one direction in 2^word, clamped to RAYCACHE_PROBE_BITS..RAYCACHE_MAX_PROBE_BITS, 4..8 unless
// defined otherwise, so 1 rests with a first rest's probes); throws
// std::invalid_argument for another count, or a layout check_gpu_frame_layout() refuses.
inline std::vector<std::uint32_t> gpu_frame_start_words(const GpuFrameLayout& f, bool mark_coverage = true,
                                                        const std::vector<std::uint32_t>& resting = {}) {
    check_gpu_frame_layout(f);
    if (!resting.empty() && resting.size() != f.cube_count)
        throw std::invalid_argument("RayCache: gpu_frame_start_words needs one resting word per cube (" +
                                    std::to_string(f.cube_count) + "), got " + std::to_string(resting.size()));
    std::vector<std::uint32_t> words(static_cast<std::size_t>(f.start_bytes / 4), 0u);
    for (std::uint32_t k = 0; k < resting.size(); ++k)
        words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_RESTING)] = resting[k];
    words[RAYCACHE_FRAME_LIST_CAPACITY] = f.list_capacity;
    words[RAYCACHE_FRAME_CUBE_COUNT] = f.cube_count;
    words[RAYCACHE_FRAME_DISPATCH + 1] = 1u;
    words[RAYCACHE_FRAME_DISPATCH + 2] = 1u;
    words[RAYCACHE_FRAME_FLAGS] = mark_coverage ? RAYCACHE_FRAME_MARK_COVERAGE : 0u;
    return words;
}

// Byte offset of the end-of-frame pass's VkDispatchIndirectCommand in the frame buffer.
inline constexpr std::uint64_t gpu_end_frame_dispatch_offset = 4 * RAYCACHE_FRAME_DISPATCH;

// Groups of the end-of-frame pass for `listed` texels (a direct dispatch after reading the count back).
inline std::uint32_t gpu_end_frame_groups(std::uint64_t listed) noexcept {
    return shared::raycache_end_frame_groups(static_cast<std::uint32_t>(std::min<std::uint64_t>(listed, 0xFFFFFF00ull)));
}

// A 2D grid of groups of `group_size` invocations covering `elements` (the sweep after a list overflow:
// invocation (x, y) handles element (y * groups_x + x) * group_size + local index).
struct GpuGroups {
    std::uint32_t x = 0, y = 0;
};
inline GpuGroups gpu_sweep_groups(std::uint64_t elements, std::uint32_t group_size = 64) noexcept {
    const std::uint64_t groups = (elements + group_size - 1) / group_size;
    GpuGroups g;
    g.x = static_cast<std::uint32_t>(std::min<std::uint64_t>(groups, 65535));
    g.y = g.x ? static_cast<std::uint32_t>((groups + g.x - 1) / g.x) : 0;
    return g;
}

// What one frame's frame buffer says: per cube (descriptor index) and in all.
struct GpuFrameStatistics {
    // lookups (every ray that reached the cube), hits, misses (with the rays a resting cube let through, also
    // counted in misses_by[MissReason::resting], as C++ counts them; those on a texel holding no value also in
    // misses_by[MissReason::empty], with the texels stored earlier in the frame, which C++ counts as fresh;
    // only in frames started with mark_coverage),
    // stores (reached the pending word), refused_stores
    std::vector<CubeStatistics> cubes;
    std::vector<double> coverage;      // per cube: the share of the 1536 direction cells its lookups took (0..1)
    std::vector<bool> resting;         // per cube: the frame was started with it resting
    CubeStatistics total;
    std::uint64_t listed = 0;   // texels the end-of-frame pass publishes
    std::uint64_t overflow = 0; // texels stored that found the list full: sweep the buffers before the next frame
    bool coverage_marked = true; // the frame was started with mark_coverage (else `coverage` reads 0 and says nothing)
};

// The share of the 1536 direction cells set in a cube's coverage bits in the frame buffer
// (RAYCACHE_COVERAGE_WORDS words from raycache_frame_coverage_word(cube, 0): shared/coverage.h), 0..1.
inline double gpu_coverage_fraction(const std::uint32_t* words) noexcept {
    int marked = 0;
    for (std::uint32_t i = 0; i < RAYCACHE_COVERAGE_WORDS; ++i)
        for (std::uint32_t bits = words[i]; bits; bits &= bits - 1) ++marked;
    return static_cast<double>(marked) / RAYCACHE_COVERAGE_CELLS;
}

// Reads the counters and the list's state from the frame buffer's first start_bytes (`words`, read back
// after the frame). valid_texels and texel_count are left 0 (the GPU does not count them). Throws
// std::invalid_argument for a layout check_gpu_frame_layout() refuses.
inline GpuFrameStatistics read_gpu_statistics(const std::uint32_t* words, const GpuFrameLayout& f) {
    check_gpu_frame_layout(f);
    GpuFrameStatistics s;
    s.cubes.resize(f.cube_count);
    s.coverage.resize(f.cube_count);
    s.resting.resize(f.cube_count);
    for (std::uint32_t k = 0; k < f.cube_count; ++k) {
        s.coverage[k] = gpu_coverage_fraction(words + shared::raycache_frame_coverage_word(k, 0));
        s.resting[k] = words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_RESTING)] != 0u;
        CubeStatistics& c = s.cubes[k];
        const std::uint64_t rested = words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_RESTED)];
        c.hits = words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_HITS)];
        c.misses = words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_MISSES)] + rested;
        c.misses_by[static_cast<std::size_t>(MissReason::resting)] = rested;
        c.misses_by[static_cast<std::size_t>(MissReason::empty)] = words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_EMPTY)];
        c.lookups = c.hits + c.misses;
        c.stores = words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_STORES)];
        c.refused_stores = words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_REFUSED)];
        s.total.hits += c.hits, s.total.misses += c.misses, s.total.lookups += c.lookups;
        s.total.misses_by[static_cast<std::size_t>(MissReason::resting)] += rested;
        s.total.misses_by[static_cast<std::size_t>(MissReason::empty)] += c.misses_by[static_cast<std::size_t>(MissReason::empty)];
        s.total.stores += c.stores, s.total.refused_stores += c.refused_stores;
    }
    s.listed = std::min(words[RAYCACHE_FRAME_LIST_COUNT], f.list_capacity);
    s.overflow = words[RAYCACHE_FRAME_OVERFLOW];
    s.coverage_marked = (words[RAYCACHE_FRAME_FLAGS] & RAYCACHE_FRAME_MARK_COVERAGE) != 0u;
    return s;
}

// Of a frame's listed entries, the tiles (the CCT's origin test lists tiles beside texels): scans the store
// list of the whole frame buffer read back (`words`, f.words of them). The texels stored are
// GpuFrameStatistics::listed less these. Throws std::invalid_argument for a layout check_gpu_frame_layout()
// refuses.
inline std::uint64_t gpu_listed_tiles(const std::uint32_t* words, const GpuFrameLayout& f) {
    check_gpu_frame_layout(f);
    const std::uint32_t listed = std::min(words[RAYCACHE_FRAME_LIST_COUNT], f.list_capacity);
    const std::uint32_t* list = words + shared::raycache_frame_list_word(f.cube_count, 0);
    std::uint64_t tiles = 0;
    for (std::uint32_t k = 0; k < listed; ++k)
        tiles += (list[k] & (RAYCACHE_FRAME_CDCT_ENTRY | RAYCACHE_FRAME_TILE_ENTRY)) == RAYCACHE_FRAME_TILE_ENTRY;
    return tiles;
}

// Face sizes that fit one storage buffer of `max_bytes`: each cube keeps min(requested, cap) for the largest
// cap (1..4096) whose cubes' texels, `bytes_per_texel` each, fit; cubes below the cap keep their size, so
// small cubes are not lowered for large ones. Throws std::invalid_argument for a requested size outside
// 1..4096, or when even a cap of 1 does not fit.
inline std::vector<int> fit_gpu_face_sizes(const std::vector<int>& requested, std::uint64_t bytes_per_texel,
                                           std::uint64_t max_bytes) {
    auto bytes_at = [&](int cap) {
        std::uint64_t total = 0;
        for (int n : requested) total += shared::raycache_gpu_cube_texel_count(std::min(n, cap)) * bytes_per_texel;
        return total;
    };
    for (int n : requested)
        if (!is_valid_face_size(n))
            throw std::invalid_argument("RayCache: a GPU cube's face size must be 1 to 4096, got " + std::to_string(n));
    if (bytes_at(1) > max_bytes)
        throw std::invalid_argument("RayCache: " + std::to_string(requested.size()) + " cubes do not fit in " +
                                    std::to_string(max_bytes) + " bytes even at one texel a face");
    int lo = 1, hi = RAYCACHE_MAX_FACE_SIZE; // bytes_at(lo) fits; find the largest cap that does
    while (lo < hi) {
        const int mid = lo + (hi - lo + 1) / 2;
        if (bytes_at(mid) <= max_bytes) lo = mid;
        else hi = mid - 1;
    }
    std::vector<int> fitted;
    for (int n : requested) fitted.push_back(std::min(n, lo));
    return fitted;
}

} // namespace raycache
