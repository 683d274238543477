// raycache/cdct.hpp: the colour-and-depth caching technique (thesis ch. 4): stores keyed by where the ray
// hit, and the relief search (thesis Algorithm 4) that finds a ray's hit in the cube's depth image.
#pragma once

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"

namespace raycache {

// Where a cube sits: the box [centre - half_size, centre + half_size] encloses the cached object.
struct CubeBounds {
    glm::vec3 centre{0.0f};
    float half_size = 1.0f;
};

// Tuning of the relief search; the defaults are one of the thesis's (delta, epsilon) pairs.
struct ReliefParameters {
    float step = 0.2f;        // delta: length of a linear step along the ray, world units
    float epsilon = 0.02f;    // binary refinement stops when the bracket is shorter than this
    int max_steps = 1024;     // linear steps before giving up (a miss)
    float max_depth = 100.0f; // distance at which rays that escaped to the environment are stored
};

// Throws std::invalid_argument, with the offending field, unless every parameter is finite and positive.
inline void validate(const ReliefParameters& p) {
    auto bad = [](const char* name, float value) {
        throw std::invalid_argument(std::string("RayCache: ReliefParameters::") + name +
                                    " must be finite and > 0, got " + std::to_string(value));
    };
    if (!(p.step > 0.0f) || !std::isfinite(p.step)) bad("step", p.step);
    if (!(p.epsilon > 0.0f) || !std::isfinite(p.epsilon)) bad("epsilon", p.epsilon);
    if (!(p.max_depth > 0.0f) || !std::isfinite(p.max_depth)) bad("max_depth", p.max_depth);
    if (p.max_steps < 1) bad("max_steps", static_cast<float>(p.max_steps));
}

// Outcome of a relief search. On a hit, `point` is within `epsilon` (along the ray) past the first
// place where the ray crosses the cached depth image, and `color` is the texel seen there.
struct ReliefResult {
    bool hit = false;
    glm::vec3 color{0.0f};
    glm::vec3 point{0.0f};
    float distance = 0.0f; // along the unit ray direction, from the origin to `point`
    int texels_read = 0;   // cube texels sampled, hit or miss
};

namespace detail {

inline bool is_finite(const glm::vec3& v) noexcept {
    return shared::raycache_is_finite(v.x) && shared::raycache_is_finite(v.y) && shared::raycache_is_finite(v.z);
}

inline bool is_usable(const CubeBounds& b) noexcept {
    return is_finite(b.centre) && b.half_size > 0.0f && shared::raycache_is_finite(b.half_size);
}

// Unit vector along a direction (scaled by its major magnitude first, so its length cannot overflow).
inline glm::vec3 unit(const glm::vec3& direction) noexcept {
    const glm::vec3 a = glm::abs(direction);
    const glm::vec3 scaled = direction / glm::max(a.x, glm::max(a.y, a.z));
    return scaled / glm::length(scaled);
}

// Distance along unit `d` from `o` to where the ray leaves the box (0 if that is behind `o`).
inline float box_exit_distance(const glm::vec3& o, const glm::vec3& d, const CubeBounds& b) noexcept {
    float exit = std::numeric_limits<float>::infinity();
    for (int axis = 0; axis < 3; ++axis) {
        if (d[axis] == 0.0f) continue; // parallel to this slab: it never bounds the exit
        const float face = b.centre[axis] + (d[axis] > 0.0f ? b.half_size : -b.half_size);
        exit = std::min(exit, (face - o[axis]) / d[axis]);
    }
    return std::max(exit, 0.0f);
}

} // namespace detail

// Thesis Algorithm 4 on a perspective depth cube: walk the ray origin + t * unit(direction) from where it
// leaves the cube's box in steps of p.step; at each point Q read the texel in direction Q - centre and
// compare |Q - centre| with its distance; at the first crossing, bisect the last step down to p.epsilon.
// A texel that is empty or written this frame, on the way, makes the search a miss; so do running out
// of p.max_steps, and a bad origin, direction or box. Counts one lookup on the cube (hit or miss).
// Thread-safe as CacheCube::lookup; reads at most 1 + p.max_steps + 64 texels.
inline ReliefResult relief_search(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& origin,
                                  const glm::vec3& direction, const ReliefParameters& p) noexcept {
    ReliefResult result;
    if (!is_direction(direction) || !detail::is_finite(origin) || !detail::is_usable(bounds) || !(p.step > 0.0f) ||
        !(p.epsilon > 0.0f)) {
        cube.record_lookup(false);
        return result;
    }
    const glm::vec3 d = detail::unit(direction);

    // Samples the depth image at distance t along the ray; false when the texel is unusable (a miss).
    DepthSample sample;
    bool crossed = false;
    auto sample_at = [&](float t) {
        const glm::vec3 from_centre = origin + t * d - bounds.centre;
        ++result.texels_read;
        const std::optional<DepthSample> texel = cube.peek(from_centre);
        if (!texel) return false;
        sample = *texel;
        crossed = sample.distance <= glm::length(from_centre);
        return true;
    };
    auto finish = [&](float t, bool hit) {
        result.hit = hit;
        if (hit) {
            result.distance = t;
            result.point = origin + t * d;
            result.color = sample.color;
        }
        cube.record_lookup(hit);
        return result;
    };

    float t = detail::box_exit_distance(origin, d, bounds);
    if (!sample_at(t)) return finish(t, false);
    if (crossed) return finish(t, true); // the cached surface lies inside the box: nothing to refine
    for (int i = 0; i < p.max_steps; ++i) {
        const float previous = t;
        t += p.step;
        if (!sample_at(t)) return finish(t, false);
        if (!crossed) continue;
        // Bisect [previous, t], keeping the crossed end (and its sample) at `hi`.
        float lo = previous, hi = t;
        DepthSample at_hi = sample;
        for (int k = 0; k < 64 && hi - lo > p.epsilon; ++k) {
            const float mid = 0.5f * (lo + hi);
            if (!sample_at(mid)) return finish(mid, false);
            if (crossed) {
                hi = mid;
                at_hi = sample;
            } else {
                lo = mid;
            }
        }
        sample = at_hi;
        return finish(hi, true);
    }
    return finish(t, false);
}

// Stores what a traced ray hit at `hit_point` under the key normalize(hit_point - centre), with distance
// |hit_point - centre| (clamped to p.max_depth). Refused (false) for a bad point or box, or as
// CacheCube::store refuses. Thread-safe as CacheCube::store.
inline bool store_hit(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& hit_point,
                      const glm::vec3& color, const ReliefParameters& p) noexcept {
    if (!detail::is_finite(hit_point) || !detail::is_usable(bounds)) return cube.store(glm::vec3(0.0f), DepthSample{});
    const glm::vec3 from_centre = hit_point - bounds.centre;
    return cube.store(from_centre, DepthSample{color, std::min(glm::length(from_centre), p.max_depth)});
}

// Stores the colour of a ray that escaped to the environment in `direction`, as far away (p.max_depth).
inline bool store_escape(CacheCube<CdctTexel>& cube, const glm::vec3& direction, const glm::vec3& color,
                         const ReliefParameters& p) noexcept {
    return cube.store(direction, DepthSample{color, p.max_depth});
}

// What a secondary-ray trace returns to the CDCT: its colour, and the distance along the unit ray
// direction to what it hit (infinity or NaN when it escaped to the environment).
struct TracedRay {
    glm::vec3 color{0.0f};
    float distance = std::numeric_limits<float>::infinity();
};

// Algorithm 1 with the CDCT: the relief search answers when it can; otherwise trace() runs, its hit is
// stored (store_hit, or store_escape when it escaped) and its colour returned unchanged.
// trace: callable `TracedRay trace()`. `texels_read`, when given, receives the search's texel count.
template <class Trace>
glm::vec3 cdct_cached_trace(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& origin,
                            const glm::vec3& direction, const ReliefParameters& p, Trace&& trace,
                            int* texels_read = nullptr) {
    static_assert(std::is_invocable_r_v<TracedRay, Trace&>, "RayCache cdct_cached_trace: trace must be callable as `TracedRay trace()`");
    const ReliefResult found = relief_search(cube, bounds, origin, direction, p);
    if (texels_read) *texels_read = found.texels_read;
    if (found.hit) return found.color;
    const TracedRay traced = std::forward<Trace>(trace)();
    if (!is_direction(direction)) return traced.color;
    if (std::isfinite(traced.distance))
        store_hit(cube, bounds, origin + traced.distance * detail::unit(direction), traced.color, p);
    else
        store_escape(cube, direction, traced.color, p);
    return traced.color;
}

} // namespace raycache
