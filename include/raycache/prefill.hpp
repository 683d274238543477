// raycache/prefill.hpp: filling a cube before rendering, by tracing once through every empty texel.
//
// The CDCT's store key is the direction of what a ray hit, so texels that no hit falls into stay empty,
// and a search that meets one is a miss, frame after frame. Pre-filling traces the cube's own view:
// for each texel, a ray from the cube's centre along the texel's centre direction, which must not see
// the cached object itself (the caller's trace skips it). Starting on the box's surface instead would
// start under the floor an object rests on. For the CCT this is the classic environment-map approximation.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <cmath>
#include <cstddef>
#include <type_traits>
#include <utility>

#include "raycache/cdct.hpp"

namespace raycache {

// Traces and stores every empty texel of one row of one face (a unit of work for a parallel loop over
// faces and rows; rows of one cube may run on different threads at once). Returns the texels stored.
// trace: callable `TracedRay trace(glm::vec3 origin, glm::vec3 unit_direction)`, called with the cube's
// centre as origin; it must pass through the cached object itself. The CDCT stores the hit's distance
// from the centre (escaped rays at p.max_depth; a negative distance, a hit behind the centre, is not
// stored and the texel stays empty); the CCT stores only the colour.
// Stores become visible at the cube's next begin_frame(). face in 0..5, row in 0..N-1 (asserted).
template <class Texel, class Trace>
std::size_t prefill_row(CacheCube<Texel>& cube, const CubeBounds& bounds, const ReliefParameters& p, int face, int row,
                        Trace&& trace) {
    static_assert(std::is_invocable_r_v<TracedRay, Trace&, glm::vec3, glm::vec3>,
                  "RayCache prefill_row: trace must be callable as `TracedRay trace(glm::vec3 origin, glm::vec3 direction)`");
    static_assert(std::is_same_v<Texel, CctTexel> || std::is_same_v<Texel, CdctTexel>, "RayCache prefill_row: CCT or CDCT cubes");
    const int n = cube.face_size();
    RAYCACHE_ASSERT(is_on_cube(TexelAddress{face, 0, row}, n));
    std::size_t stored = 0;
    for (int column = 0; column < n; ++column) {
        const TexelAddress texel{face, column, row};
        if (cube.load(texel)) continue;
        const glm::vec3 d = glm::normalize(texel_direction(texel, n));
        const glm::vec3 origin = bounds.centre;
        const TracedRay traced = trace(origin, d);
        bool written;
        if constexpr (std::is_same_v<Texel, CctTexel>) {
            written = cube.store_at(texel, traced.color);
        } else {
            if (traced.distance < 0.0f) continue; // behind the centre: not what this texel sees
            const float distance = std::isfinite(traced.distance)
                                       ? std::min(glm::length(origin + traced.distance * d - bounds.centre), p.max_depth)
                                       : p.max_depth;
            written = cube.store_at(texel, DepthSample{traced.color, distance});
        }
        stored += written;
    }
    return stored;
}

// prefill_row over every row of every face, on the calling thread.
template <class Texel, class Trace>
std::size_t prefill(CacheCube<Texel>& cube, const CubeBounds& bounds, const ReliefParameters& p, Trace&& trace) {
    std::size_t stored = 0;
    for (int face = 0; face < RAYCACHE_FACE_COUNT; ++face)
        for (int row = 0; row < cube.face_size(); ++row) stored += prefill_row(cube, bounds, p, face, row, trace);
    return stored;
}

} // namespace raycache
