// raycache/gpu_resting.hpp: resting cubes (raycache/resting.hpp) for the GPU frame protocol, decided on the
// host between frames. No graphics API.
//
// The rule is C++'s, unchanged: after each frame, a cube whose looked-up rays found fewer than min_hit_rate
// hits rests the next frame, and a resting cube works again when its probes find that many
// (next_resting_state; probes pooled over frames, thinned while they find it not paying, and longer rests
// after wrong wakes). The GPU counts what the rule needs (hits and misses of the lookups it made, and the
// rays a resting cube let through: GpuFrameStatistics), the host writes each cube's resting word before the
// frame (gpu_frame_start_words(layout, mark_coverage, resting.resting_words()): 0, or the probe bits of a
// resting cube), and the shaders ask
// raycache_cube_rests(cube, direction) before a lookup (raycache/cube.glsl). A frame, in the order of
// raycache/gpu_frame.hpp:
//   1. start the frame buffer with gpu_frame_start_words(frame_layout, mark_coverage, resting.resting_words());
//   2. the frame; read_gpu_statistics() after it;
//   3. resting.after_frame(statistics); then, with adaptive face sizes, next_gpu_face_sizes (a cube that
//      rested keeps its size, as a CPU cube does) and, when cubes moved, resting.resized(old, new layout).
// What the host must tell it beyond the counters: which cubes start a frame empty (a frame a cube starts
// empty decides nothing, as in C++): all of them at first; resized() marks cubes that grew (they start
// empty, raycache::move_gpu_cubes); restart() a cube cleared or loaded from a cache file (it works again,
// as SceneCache's after clear() or a load). The GPU counts no valid texels, so a cube is taken to hold
// texels from its first frame with stores on: one whose every tile the origin test's drop pass emptied
// still counts as holding texels, where C++ (which counts them) would let its next frame decide nothing.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "raycache/gpu_buffers.hpp"
#include "raycache/gpu_frame.hpp"
#include "raycache/resting.hpp"

namespace raycache {

class GpuResting {
public:
    // Cubes numbered 0 .. cube_count - 1 (their descriptors' `index`, the frame buffer's counters), all
    // working and empty. min_hit_rate: 0 never rests a cube (default_min_hit_rate(cdct): C++'s defaults).
    // Throws std::invalid_argument when it is negative or NaN.
    GpuResting(std::size_t cube_count, float min_hit_rate)
        : min_hit_rate_(min_hit_rate), states_(cube_count), holds_texels_(cube_count, false) {
        if (!(min_hit_rate >= 0.0f))
            throw std::invalid_argument("RayCache: GpuResting's min_hit_rate must be >= 0 (0: cubes never rest), got " +
                                        std::to_string(min_hit_rate));
    }

    // Each cube's state for the next frame from the frame just read back (statistics by descriptor index).
    // Throws std::invalid_argument when the frame counted another number of cubes.
    void after_frame(const GpuFrameStatistics& frame) {
        if (frame.cubes.size() != states_.size())
            throw std::invalid_argument("RayCache: GpuResting has " + std::to_string(states_.size()) + " cubes, the frame counted " +
                                        std::to_string(frame.cubes.size()));
        for (std::size_t k = 0; k < states_.size(); ++k) {
            states_[k] = next_resting_state(states_[k], frame.cubes[k], min_hit_rate_, !holds_texels_[k]);
            // A store that reached the pending word is published at the frame's end (its texel was empty;
            // the drop pass may empty its tile again: see the top of this file).
            holds_texels_[k] = holds_texels_[k] || frame.cubes[k].stores > 0;
        }
    }

    // Cubes moved from layout `from` to layout `to` (the same cubes, other face sizes): those that grew start
    // empty (raycache::move_gpu_cubes leaves them so). Throws std::invalid_argument when the layouts differ
    // in their cubes or number one past this object's cubes.
    void resized(const GpuBufferLayout& from, const GpuBufferLayout& to) {
        if (from.cubes.size() != to.cubes.size())
            throw std::invalid_argument("RayCache: GpuResting::resized needs the same cubes in both layouts");
        for (std::size_t k = 0; k < from.cubes.size(); ++k) {
            const std::uint32_t index = to.cubes[k].index;
            if (index >= states_.size() || from.cubes[k].index != index)
                throw std::invalid_argument("RayCache: GpuResting::resized: cube " + std::to_string(k) + " numbers " +
                                            std::to_string(index) + " in the new layout, " + std::to_string(from.cubes[k].index) +
                                            " in the old, of " + std::to_string(states_.size()));
            if (to.cubes[k].face_size > from.cubes[k].face_size) holds_texels_[index] = false;
        }
    }

    // Cube `index` was cleared (holds_texels false) or loaded from a cache file (true when the file gave it
    // texels): it works the next frame, which decides nothing when it starts empty. Throws
    // std::out_of_range for an index past the cubes.
    void restart(std::size_t index, bool holds_texels) {
        states_.at(index) = RestingState{};
        holds_texels_[index] = holds_texels;
    }

    // Per cube, by index: its resting word for the next frame (gpu_frame_start_words): 0 when it works, else
    // its probe bits (it probes one direction in 2^bits, raycache_is_probe_direction_of).
    std::vector<std::uint32_t> resting_words() const {
        std::vector<std::uint32_t> r(states_.size());
        for (std::size_t k = 0; k < states_.size(); ++k) r[k] = states_[k].resting ? std::max(states_[k].probe_bits, 1u) : 0u;
        return r;
    }
    // Per cube, by index: whether it rests the next frame.
    std::vector<bool> resting() const {
        std::vector<bool> r(states_.size());
        for (std::size_t k = 0; k < states_.size(); ++k) r[k] = states_[k].resting;
        return r;
    }
    std::size_t resting_count() const noexcept {
        std::size_t n = 0;
        for (const RestingState& s : states_) n += s.resting ? 1 : 0;
        return n;
    }
    const RestingState& state(std::size_t index) const { return states_.at(index); }
    float min_hit_rate() const noexcept { return min_hit_rate_; }

private:
    float min_hit_rate_;
    std::vector<RestingState> states_;
    std::vector<bool> holds_texels_; // whether the cube starts the next frame with texels
};

} // namespace raycache
