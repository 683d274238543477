// raycache/traced_ray.hpp: what a trace callback gives back to a cache.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <cstdint>
#include <limits>

#include <glm/glm.hpp>

namespace raycache {

// What a secondary-ray trace returns to a cache: its colour, and the distance along the unit ray direction
// to what it hit (infinity or NaN when it escaped to the environment; the CDCT stores the hit there, the
// CCT keeps the nearest per tile to bound parallax). A negative distance (a hit behind the ray's origin) is
// never stored: the colour is used, the cube left alone.
// `work`: what tracing it cost, in units of the caller's choice (rays it traced, say: the ray itself, its
// shadow rays and bounces), as a whole number so that sums do not depend on the order threads add them
// in; 0: not reported. A cube counts the work of the rays that filled its texels, which stands for what
// their hits save; the Embree adapter's resting cubes weigh their hit rates against it (raycache/resting.hpp,
// resting_threshold).
struct TracedRay {
    glm::vec3 color{0.0f};
    float distance = std::numeric_limits<float>::infinity();
    std::uint32_t work = 0;
};

} // namespace raycache
