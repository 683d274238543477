// raycache/cube_placement.hpp: where a caching cube sits around an object.
//
// The rule: the cube is centred on the middle of the object's axis-aligned bounding box, and its half-size
// is the box's largest half-extent, so it is the smallest cube centred there that encloses the object (a
// sphere's cube is centred on the sphere, half-size = its radius). It lives here, and not in each tracer,
// because what a cube caches depends on where it sits: its texels are directions from its centre, its CDCT
// depths are measured from its box. A CPU tracer (the Embree adapter, raycache/embree/scene_cache.hpp) and
// a GPU one (GpuCubeShape, raycache/gpu_buffers.hpp) placing one object's cube by the same rule cache the
// same rays (the two hand-written copies this replaces had drifted apart: one refused empty boxes, one not).
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <glm/glm.hpp>

#include "raycache/cdct.hpp"

namespace raycache {

// The cube around the box [lower, upper]: centre (lower + upper) / 2, half-size the largest of
// (upper - lower) / 2. Throws std::invalid_argument naming `what` when a corner is not finite, lower
// exceeds upper on an axis, or the box is a single point (a cube of half-size 0 caches nothing).
inline CubeBounds cube_around_box(const glm::vec3& lower, const glm::vec3& upper, const std::string& what = "an object") {
    const glm::vec3 half = 0.5f * (upper - lower);
    const CubeBounds cube{0.5f * (lower + upper), std::fmax(half.x, std::fmax(half.y, half.z))};
    // NaN fails the >= tests; an infinite corner makes the centre or the half-size not finite.
    if (!(half.x >= 0.0f && half.y >= 0.0f && half.z >= 0.0f) || !detail::is_usable(cube))
        throw std::invalid_argument("RayCache: " + what + " has empty or infinite bounds");
    return cube;
}

// The cube around a sphere: its centre, half-size = its radius (what cube_around_box gives for the
// sphere's box, without the rounding of going through the corners). Throws std::invalid_argument naming
// `what` unless the centre is finite and the radius finite and > 0.
inline CubeBounds cube_around_sphere(const glm::vec3& centre, float radius, const std::string& what = "a sphere") {
    const CubeBounds cube{centre, radius};
    if (!detail::is_usable(cube)) throw std::invalid_argument("RayCache: " + what + " has empty or infinite bounds");
    return cube;
}

// The cube around a set of points (a mesh's vertices): cube_around_box of their bounding box. `points` is
// any range of glm::vec3 (a std::vector, an array). Throws std::invalid_argument naming `what` when there
// are no points, one is not finite, or all are the same point.
template <class Points>
CubeBounds cube_around_points(const Points& points, const std::string& what = "a set of points") {
    glm::vec3 lower(INFINITY), upper(-INFINITY);
    for (const glm::vec3& p : points) {
        if (!shared::raycache_is_finite3(p)) // glm::min and glm::max would pass over a NaN
            throw std::invalid_argument("RayCache: " + what + " has a point that is not finite");
        lower = glm::min(lower, p);
        upper = glm::max(upper, p);
    }
    return cube_around_box(lower, upper, what); // no points: lower > upper, refused there
}

} // namespace raycache
