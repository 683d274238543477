#include "simd_groups.hpp"

#include <stdexcept>
#include <string>

namespace rcx::gpu {

SimdGroupStatistics simd_group_statistics(const std::vector<std::uint32_t>& outcomes, int width, int height, int lanes) {
    if (lanes < 1 || lanes > 64 || (lanes & (lanes - 1)) != 0)
        throw std::invalid_argument("simd_group_statistics: lanes must be a power of two in 1..64, not " + std::to_string(lanes));
    if (width < 0 || height < 0 || outcomes.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
        throw std::invalid_argument("simd_group_statistics: " + std::to_string(outcomes.size()) + " outcomes for a " +
                                    std::to_string(width) + " x " + std::to_string(height) + " image");
    SimdGroupStatistics s;
    const int groups_per_workgroup = 64 / lanes;
    for (int wy = 0; wy < height; wy += 8)
        for (int wx = 0; wx < width; wx += 8)
            for (int g = 0; g < groups_per_workgroup; ++g) {
                std::uint32_t met = 0;
                for (int l = g * lanes; l < (g + 1) * lanes; ++l) {
                    const int x = wx + l % 8, y = wy + l / 8;
                    if (x < width && y < height) met |= outcomes[static_cast<std::size_t>(y) * width + x];
                }
                if (met == 0) continue;
                ++s.with_lookups;
                if (met == lookup_hit) ++s.all_hit;
            }
    return s;
}

} // namespace rcx::gpu
