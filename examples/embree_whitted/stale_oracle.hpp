// The stale-texel oracle for dynamic scenes: after objects moved, retraces rays that cached texels answer,
// with the cache off, in the scene before and after the move, and counts the texels for which some ray
// sees another colour. It is how the tests check exact invalidation (no stale texel may survive it) and how
// the dynamic benchmark measures what a move really changed (a lower bound on what any exact invalidation
// must drop: a texel counts only when one of its sampled rays changed).
//   CCT: rays through random directions of the texel from random origins it answers (within the origin
//   test's drift of its tile's origin box, or anywhere in the cube's box; and within the distance from the
//   centre the cube answers rays from, SceneCache::answered_origin_radius).
//   CDCT: rays from random points of the cube's box it answers rays from (half of them on the surface of
//   that ball, where the object's rays leave) toward points at the texel's stored distance in random
//   directions of the texel, counted when, before the move, they met a surface within 2% of that distance
//   (or, for a stored escape, nothing); stale when the move changed where such a ray hits, or its colour
//   by more than cdct_shading_tolerance.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <random>

#include <glm/glm.hpp>

#include "raycache/embree/scene_cache.hpp"
#include "raycache/shared/cube_face.h"
#include "tracer.hpp"

namespace rcx::embree {

// What the oracle found over one SceneCache.
struct StaleCount {
    std::size_t stale = 0;   // texels some retraced ray of which changed colour by more than the tolerance
    std::size_t checked = 0; // texels looked at (CDCT: those with a ray that met the stored surface before)
    double fraction() const noexcept { return checked ? static_cast<double>(stale) / static_cast<double>(checked) : 0.0; }
};

// A colour change larger than this in a channel makes a texel stale (stale texels differ by 0.01 and more).
constexpr float stale_tolerance = 1e-4f;
// CDCT: a ray from another point of the object's surface than the stored ray meets the stored surface at
// another point, whose own bounces and shadow rays no stored path took, so a move may shade it a little
// differently (0.0004 to 0.002 seen on dynamic-8): such a change up to this much is not counted, while any
// change of what the ray itself hits (its distance, so its first segment) is.
constexpr float cdct_shading_tolerance = 0.005f;

namespace detail {
inline bool differs(const glm::vec3& a, const glm::vec3& b, float tolerance = stale_tolerance) {
    const glm::vec3 d = glm::abs(a - b);
    return std::max(d.x, std::max(d.y, d.z)) > tolerance;
}
// A random point of the cube's box from which its cube answers rays (within `radius` of the centre;
// infinity: the whole box). For a limited radius, every other point lies on the ball's surface, where the
// object's own rays leave from (rays from deeper inside a solid object meet it first and test little).
inline glm::vec3 random_answered_origin(const raycache::CubeBounds& b, float radius, bool on_surface, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    if (!std::isfinite(radius))
        return b.centre + b.half_size * glm::vec3(2.0f * u(rng) - 1.0f, 2.0f * u(rng) - 1.0f, 2.0f * u(rng) - 1.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    const float reach = std::min(radius, 1.7320508f * b.half_size);
    for (;;) {
        const glm::vec3 axis(g(rng), g(rng), g(rng));
        if (!(glm::length(axis) > 1e-6f)) continue;
        const glm::vec3 p = (on_surface ? reach : reach * std::cbrt(u(rng))) * glm::normalize(axis);
        if (std::max(std::abs(p.x), std::max(std::abs(p.y), std::abs(p.z))) <= b.half_size) return b.centre + p;
    }
}
inline glm::vec3 random_direction_in(const raycache::TexelAddress& a, int n, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const float sc = 2.0f * ((static_cast<float>(a.column) + u(rng)) / static_cast<float>(n)) - 1.0f;
    const float tc = 2.0f * ((static_cast<float>(a.row) + u(rng)) / static_cast<float>(n)) - 1.0f;
    return glm::normalize(raycache::shared::raycache_face_point(a.face, 1.0f, sc, tc));
}
} // namespace detail

// The oracle over the CCT cubes of `caches`, every `stride`-th valid texel (1: all), `rays` rays a texel.
inline StaleCount stale_cct_texels(const raycache::embree::SceneCache& caches, const Tracer& before, const Tracer& after,
                                   std::size_t stride = 1, int rays = 6) {
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const float drift_fraction = raycache::embree::SceneCacheSettings{}.origin_drift;
    StaleCount count;
    std::size_t seen = 0;
    caches.for_each_cct_cube([&](raycache::embree::ObjectId id, const raycache::CubeBounds& bounds, const raycache::CctCube* cube) {
        if (!cube) return;
        const float answered = *caches.answered_origin_radius(id);
        const int n = cube->face_size();
        cube->for_each_valid_texel([&](const raycache::TexelAddress& a) {
            if (seen++ % stride) return;
            ++count.checked;
            glm::vec3 lo = bounds.centre - glm::vec3(bounds.half_size), hi = bounds.centre + glm::vec3(bounds.half_size);
            if (const auto box = cube->origin_box(a)) {
                const float drift = drift_fraction * bounds.half_size;
                lo = box->first - glm::vec3(drift), hi = box->second + glm::vec3(drift);
            }
            for (int k = 0, tries = 0; k < rays && tries < 64 * rays; ++tries) {
                const glm::vec3 o = lo + (hi - lo) * glm::vec3(u(rng), u(rng), u(rng));
                if (glm::length(o - bounds.centre) > answered) continue; // the cube answers no ray from there
                ++k;
                const glm::vec3 d = detail::random_direction_in(a, n, rng);
                if (detail::differs(before.trace_uncached(o, d, 1).color, after.trace_uncached(o, d, 1).color)) {
                    ++count.stale;
                    return;
                }
            }
        });
    });
    return count;
}

// The oracle over the CDCT caches of `caches`, every `stride`-th valid texel, up to `rays` rays a texel.
inline StaleCount stale_cdct_texels(const raycache::embree::SceneCache& caches, const Tracer& before, const Tracer& after,
                                    std::size_t stride = 1, int rays = 32) {
    std::mt19937 rng(29);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    StaleCount count;
    std::size_t seen = 0;
    caches.for_each_cdct_cache([&](raycache::embree::ObjectId id, const raycache::CdctCache* cache) {
        if (!cache) return;
        const raycache::CubeBounds& bounds = cache->bounds();
        const float answered = *caches.answered_origin_radius(id);
        const raycache::CdctCube& cube = cache->cube();
        const int n = cube.face_size();
        cube.for_each_valid_texel([&](const raycache::TexelAddress& a) {
            if (seen++ % stride) return;
            const raycache::DepthSample stored = *cube.load(a);
            const bool escape = stored.distance >= cache->parameters().max_depth;
            bool counted = false;
            for (int k = 0; k < rays; ++k) {
                const glm::vec3 o = detail::random_answered_origin(bounds, answered, k % 2 == 0, rng);
                const glm::vec3 point = bounds.centre + stored.distance * detail::random_direction_in(a, n, rng);
                const float length = glm::length(point - o);
                const glm::vec3 d = (point - o) / length;
                const raycache::TracedRay was = before.trace_uncached(o, d, 1);
                const bool hit = std::isfinite(was.distance);
                if (escape ? hit : (!hit || std::abs(was.distance - length) > 0.02f * length)) continue;
                counted = true;
                const raycache::TracedRay now = after.trace_uncached(o, d, 1);
                const bool moved_hit = !(std::abs(now.distance - was.distance) <= 1e-4f * std::max(1.0f, was.distance)) &&
                                       !(std::isinf(now.distance) && std::isinf(was.distance));
                if (moved_hit || detail::differs(was.color, now.color, cdct_shading_tolerance)) {
                    ++count.stale;
                    break;
                }
            }
            count.checked += counted;
        });
    });
    return count;
}

} // namespace rcx::embree
