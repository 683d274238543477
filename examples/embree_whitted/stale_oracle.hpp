// The stale-texel oracle for dynamic scenes: after objects moved, retraces rays that cached texels answer,
// with the cache off, in the scene before and after the move, and counts the texels for which some ray
// sees another colour. It is how the tests check exact invalidation (no stale texel may survive it) and how
// the dynamic benchmark measures what a move really changed (a lower bound on what any exact invalidation
// must drop: a texel counts only when one of its sampled rays changed).
//   CCT: rays through random directions of the texel from random origins it answers (within the origin
//   test's drift of its tile's origin box, or anywhere in the cube's box).
//   CDCT: rays from random points of the cube's box toward points at the texel's stored distance in random
//   directions of the texel, counted when, before the move, they met a surface within 2% of that distance
//   (or, for a stored escape, nothing).
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

namespace detail {
inline bool differs(const glm::vec3& a, const glm::vec3& b) {
    const glm::vec3 d = glm::abs(a - b);
    return std::max(d.x, std::max(d.y, d.z)) > stale_tolerance;
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
    caches.for_each_cct_cube([&](raycache::embree::ObjectId, const raycache::CubeBounds& bounds, const raycache::CctCube* cube) {
        if (!cube) return;
        const int n = cube->face_size();
        cube->for_each_valid_texel([&](const raycache::TexelAddress& a) {
            if (seen++ % stride) return;
            ++count.checked;
            glm::vec3 lo = bounds.centre - glm::vec3(bounds.half_size), hi = bounds.centre + glm::vec3(bounds.half_size);
            if (const auto box = cube->origin_box(a)) {
                const float drift = drift_fraction * bounds.half_size;
                lo = box->first - glm::vec3(drift), hi = box->second + glm::vec3(drift);
            }
            for (int k = 0; k < rays; ++k) {
                const glm::vec3 o = lo + (hi - lo) * glm::vec3(u(rng), u(rng), u(rng));
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
    caches.for_each_cdct_cache([&](raycache::embree::ObjectId, const raycache::CdctCache* cache) {
        if (!cache) return;
        const raycache::CubeBounds& bounds = cache->bounds();
        const raycache::CdctCube& cube = cache->cube();
        const int n = cube.face_size();
        cube.for_each_valid_texel([&](const raycache::TexelAddress& a) {
            if (seen++ % stride) return;
            const raycache::DepthSample stored = *cube.load(a);
            const bool escape = stored.distance >= cache->parameters().max_depth;
            bool counted = false;
            for (int k = 0; k < rays; ++k) {
                const glm::vec3 o = bounds.centre + bounds.half_size * glm::vec3(2.0f * u(rng) - 1.0f, 2.0f * u(rng) - 1.0f, 2.0f * u(rng) - 1.0f);
                const glm::vec3 point = bounds.centre + stored.distance * detail::random_direction_in(a, n, rng);
                const float length = glm::length(point - o);
                const glm::vec3 d = (point - o) / length;
                const raycache::TracedRay was = before.trace_uncached(o, d, 1);
                const bool hit = std::isfinite(was.distance);
                if (escape ? hit : (!hit || std::abs(was.distance - length) > 0.02f * length)) continue;
                counted = true;
                if (detail::differs(was.color, after.trace_uncached(o, d, 1).color)) {
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
