// raycache/filtered_lookup.hpp: filtered (bilinear) lookups in a caching cube, seamless across face edges
// and corners, over any storage: you say how to read one texel, this header says which texels to read and
// how to weigh them (C++ face of shared/cube_filter.h, which GLSL includes too: glsl_include/raycache/filter.glsl).
//
//   std::optional<glm::vec3> c = raycache::filtered_value(direction, cube.face_size(),
//       [&](const raycache::TexelAddress& t) { return cube.load(t); });   // std::nullopt: empty texel
//
// The footprint is the Vulkan specification's LINEAR cube-map filtering: the 2 x 2 texels around the
// direction's position, a tap past a face's edge read from the adjacent face, and at a cube corner (where
// only three texels exist) the missing tap's weight shared equally by the other three. Empty texels are
// left out and the others' weights renormalised, so an empty neighbour does not darken the result.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <array>
#include <optional>
#include <type_traits>
#include <utility>

#include <glm/glm.hpp>

#include "raycache/assert.hpp"
#include "raycache/cube_face.hpp"
#include "raycache/shared/cube_filter.h"

namespace raycache {

// One texel of a filtered lookup and its weight (> 0).
struct FilterTap {
    TexelAddress texel;
    float weight = 0.0f;
};

// The texels a filtered lookup reads: taps[0 .. count), at most 4, weights summing to 1 up to rounding;
// count == 0 for a vector that is not a direction.
struct FilterFootprint {
    int count = 0;
    std::array<FilterTap, RAYCACHE_FILTER_MAX_TAPS> taps{};

    const FilterTap* begin() const noexcept { return taps.data(); }
    const FilterTap* end() const noexcept { return taps.data() + count; }
};

// The bilinear footprint of `direction` (need not be unit length) on a cube with `face_size` texels along
// each edge (valid, asserted); bit for bit what GLSL's raycache_filter_taps_of gives.
inline FilterFootprint filter_footprint(const glm::vec3& direction, int face_size) noexcept {
    RAYCACHE_ASSERT(is_valid_face_size(face_size));
    const shared::raycache_filter_taps t = shared::raycache_filter_taps_of(direction, face_size);
    FilterFootprint footprint;
    footprint.count = t.count;
    for (int k = 0; k < t.count; ++k)
        footprint.taps[static_cast<std::size_t>(k)] = {{t.texel[k].face, t.texel[k].column, t.texel[k].row}, t.weight[k]};
    return footprint;
}

// The filtered colour for `direction`: the weighted mean of the footprint's texels that `fetch` finds,
// with their weights renormalised. fetch(const TexelAddress&) returns std::optional<glm::vec3> (std::nullopt
// for an empty texel) and is called once per tap, in footprint order. std::nullopt when `direction` is not
// a direction (fetch is not called), when every tap is empty, or when the taps found weigh less than
// `min_weight` (0, the default: any non-empty tap answers; e.g. 0.5: at least half the footprint must be
// filled, so that a cache whose misses fill the nearest texel fills holes instead of blurring over them).
// Bit for bit GLSL's raycache_filtered_value with the same texels.
template <class Fetch>
std::optional<glm::vec3> filtered_value(const glm::vec3& direction, int face_size, Fetch&& fetch,
                                        float min_weight = 0.0f) {
    static_assert(std::is_convertible_v<std::invoke_result_t<Fetch&, const TexelAddress&>, std::optional<glm::vec3>>,
                  "fetch(const TexelAddress&) must return std::optional<glm::vec3>");
    shared::raycache_filter_sum sum = shared::raycache_filter_sum_zero();
    for (const FilterTap& tap : filter_footprint(direction, face_size)) {
        const std::optional<glm::vec3> color = fetch(tap.texel);
        if (color) sum = shared::raycache_filter_sum_add(sum, *color, tap.weight);
    }
    if (!shared::raycache_filter_sum_found(sum, min_weight)) return std::nullopt;
    return shared::raycache_filter_sum_mean(sum);
}

} // namespace raycache
