// simd_groups.hpp: how the cache's answers fall on a GPU's SIMD groups. A group of invocations that run in
// lockstep (an NVIDIA warp: 32) takes as long as its slowest lane, so a hit spares the group a trace only
// when none of the group's other leaving rays missed or rested. The tracing dispatch (whitted.comp) runs
// 8 x 8 workgroups, invocation x + 8 y of each, so a group of 32 lanes is 8 x 4 pixels.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace rcx::gpu {

// What a pixel's leaving rays met: whitted.comp or-s these into the pixel's alpha.
inline constexpr std::uint32_t lookup_hit = 1u, lookup_missed = 2u, lookup_rested = 4u;

struct SimdGroupStatistics {
    std::size_t with_lookups = 0; // groups with a ray leaving a cached object (looked up or let through)
    std::size_t all_hit = 0;      // ... whose such rays all hit: they skip every cached object's trace
};

// The groups of `lanes` invocations (a power of two, 1..64) of an 8 x 8-workgroup dispatch over a width x
// height image, from each pixel's bits (row-major). Throws std::invalid_argument for other lanes or sizes.
SimdGroupStatistics simd_group_statistics(const std::vector<std::uint32_t>& outcomes, int width, int height, int lanes);

} // namespace rcx::gpu
