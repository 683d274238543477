// raycache/cdct.hpp: the colour-and-depth caching technique (thesis ch. 4): stores keyed by where the ray
// hit, and the relief search (thesis Algorithm 4) that finds a ray's hit in the cube's depth image.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"
#include "raycache/depth_pyramid.hpp"
#include "raycache/path_record.hpp"
#include "raycache/pyramid_walk.hpp"
#include "raycache/shared/cdct_store.h"
#include "raycache/shared/depth_secant.h"
#include "raycache/shared/relief_walk.h"
#include "raycache/shared/search_parameters.h"
#include "raycache/traced_ray.hpp"

namespace raycache {

// Where a cube sits: the box [centre - half_size, centre + half_size] encloses the cached object.
struct CubeBounds {
    glm::vec3 centre{0.0f};
    float half_size = 1.0f;
};

// Throws std::invalid_argument, with the offending field, unless every parameter is finite and positive
// and max_steps is 1..RAYCACHE_MAX_RELIEF_STEPS.
inline void validate(const ReliefParameters& p) {
    auto bad = [](const char* name, float value) {
        throw std::invalid_argument(std::string("RayCache: ReliefParameters::") + name +
                                    " must be finite and > 0, got " + std::to_string(value));
    };
    if (!(p.step > 0.0f) || !std::isfinite(p.step)) bad("step", p.step);
    if (!(p.epsilon > 0.0f) || !std::isfinite(p.epsilon)) bad("epsilon", p.epsilon);
    if (!(p.max_depth > 0.0f) || !std::isfinite(p.max_depth)) bad("max_depth", p.max_depth);
    if (p.max_steps < 1 || p.max_steps > RAYCACHE_MAX_RELIEF_STEPS)
        throw std::invalid_argument("RayCache: ReliefParameters::max_steps must be 1 to " +
                                    std::to_string(RAYCACHE_MAX_RELIEF_STEPS) + ", got " + std::to_string(p.max_steps));
    if (!(p.max_gap > 0.0f)) bad("max_gap", p.max_gap);
    if (p.max_reads < 1 || p.max_reads > RAYCACHE_SECANT_MAX_READS)
        throw std::invalid_argument("RayCache: ReliefParameters::max_reads must be 1 to " +
                                    std::to_string(RAYCACHE_SECANT_MAX_READS) + ", got " + std::to_string(p.max_reads));
}

namespace detail {

// True when the box can be searched (shared/ray_box.h, as the GLSL search decides).
inline bool is_usable(const CubeBounds& b) noexcept { return shared::raycache_box_is_usable(b.centre, b.half_size); }

// Reads the texels a relief walk asks for (visible ones, through CacheCube::peek) until it ends or hands
// the walk to its caller. A read that finds nothing ends the walk as a miss, its texel's state in `why`.
inline shared::raycache_relief_walk read_relief_walk(const CdctCube& cube, shared::raycache_relief_walk w,
                                                     MissReason& why) noexcept {
    while (w.status == RAYCACHE_RELIEF_READ) {
        const std::optional<DepthSample> texel = cube.peek(shared::raycache_relief_point(w, w.t), &why);
        w = texel ? shared::raycache_relief_step(w, true, texel->distance, texel->color)
                  : shared::raycache_relief_step(w, false, 0.0f, glm::vec3(0.0f));
    }
    return w;
}

} // namespace detail

// Thesis Algorithm 4 on a perspective depth cube (shared/relief_walk.h: the same steps as GLSL's
// raycache_relief_search; over a pyramid, pyramid_walk.hpp's): walk the ray origin + t * unit(direction) from where it
// leaves the cube's box; at each point Q read the texel in direction Q - centre and compare |Q - centre|
// with its distance; at the first crossing, bisect down to p.epsilon. Without a pyramid the walk takes
// steps of p.step (the thesis); with one (kept up to date for this cube) it skips blocks of texels that
// lie beyond the ray. An empty or not-yet-visible texel read on the way makes the search a miss; so do
// running out of p.max_steps, a linear step too small to move the ray on, a crossing more than p.max_gap
// behind the surface, a bad origin, direction or box, and parameters no search can run with (step or
// epsilon not > 0, max_steps above RAYCACHE_MAX_RELIEF_STEPS: no texel read). Reads at most
// 1 + min(p.max_steps, RAYCACHE_MAX_RELIEF_STEPS) + 64 texels or pyramid nodes. Counts one lookup on the
// cube: a miss under the state of the texel whose read ended it, outside for a point without a face or
// nothing read, else search; texels_read counts pyramid nodes too. Thread-safe as CacheCube::lookup.
inline ReliefResult relief_search(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& origin,
                                  const glm::vec3& direction, const ReliefParameters& p,
                                  const DepthPyramid* pyramid = nullptr) noexcept {
    const auto use = cube.in_frame();
    const bool over_pyramid = pyramid && pyramid->face_size() == cube.face_size();
    shared::raycache_relief_walk w =
        shared::raycache_relief_start(origin, direction, bounds.centre, bounds.half_size, p, over_pyramid);
    RAYCACHE_ASSERT(w.status == RAYCACHE_RELIEF_MISS || !pyramid || over_pyramid);
    MissReason why = MissReason::search; // a miss on a read that found nothing: that texel's state
    w = detail::read_relief_walk(cube, w, why);
    if (w.status == RAYCACHE_RELIEF_CALLER_WALK) w = detail::read_relief_walk(cube, detail::pyramid_walk(cube, *pyramid, w, why), why);
    const ReliefResult result = shared::raycache_relief_walk_result(w);
    if (result.hit) cube.record_hit();
    else cube.record_miss(w.reads == 0 ? MissReason::outside : why);
    return result;
}

// The CDCT's cheap search (shared/depth_secant.h, the same steps as GLSL's): from where the ray leaves the
// box, jump to where the ray reaches the distance read, then refine a bracketed crossing by false position;
// answer only when the point read lies within p.epsilon of its texel's surface (or a bracket shorter than
// p.epsilon ends at most p.max_gap behind it). A miss for an empty or not-yet-visible texel, after
// p.max_reads reads without such an answer, and for bad input (no texel read). A texel marked doubtful
// (raycache/edge_confidence.hpp) reads as empty: its colour, and often its distance, lie at an edge. Reads at most
// min(p.max_reads, RAYCACHE_SECANT_MAX_READS) texels. Counts one lookup: a miss under the state of the texel
// whose read ended it (MissReason empty, fresh or doubtful), else search; outside for bad input.
// Thread-safe as CacheCube::lookup.
inline ReliefResult secant_search(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& origin,
                                  const glm::vec3& direction, const ReliefParameters& p) noexcept {
    const auto use = cube.in_frame();
    shared::raycache_secant_search s = shared::raycache_secant_start(origin, direction, bounds.centre, bounds.half_size,
                                                                     p.epsilon, p.max_gap, p.max_reads);
    // A read that finds nothing ends the search: the cause is that texel's (peek sets it only then).
    MissReason why = MissReason::search;
    while (s.status == RAYCACHE_SECANT_READ) {
        const std::optional<DepthSample> texel = cube.peek(shared::raycache_secant_point(s, s.t), &why);
        if (texel) shared::raycache_secant_advance(s, true, texel->distance, texel->color);
        else shared::raycache_secant_advance(s, false, 0.0f, glm::vec3(0.0f));
    }
    const ReliefResult result = shared::raycache_secant_result(s, origin);
    if (result.hit) cube.record_hit();
    else cube.record_miss(s.reads == 0 ? MissReason::outside : why);
    return result;
}

// The search p.search names: secant_search, or relief_search (over `pyramid` when given).
inline ReliefResult depth_search(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& origin,
                                 const glm::vec3& direction, const ReliefParameters& p,
                                 const DepthPyramid* pyramid = nullptr) noexcept {
    return p.search == DepthSearch::secant ? secant_search(cube, bounds, origin, direction, p)
                                           : relief_search(cube, bounds, origin, direction, p, pyramid);
}

// Stores what a traced ray hit at `hit_point` under the key normalize(hit_point - centre), with distance
// |hit_point - centre| (clamped to p.max_depth). Refused (false) for a bad point or box, or as
// CacheCube::store refuses. Thread-safe as CacheCube::store.
inline bool store_hit(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& hit_point,
                      const glm::vec3& color, const ReliefParameters& p) noexcept {
    const shared::raycache_cdct_store_key k = shared::raycache_cdct_hit_store(hit_point, bounds.centre, bounds.half_size, p.max_depth);
    return cube.store(k.key, DepthSample{color, k.distance});
}

// Stores the colour of a ray that escaped to the environment in `direction`, as far away (p.max_depth).
inline bool store_escape(CacheCube<CdctTexel>& cube, const glm::vec3& direction, const glm::vec3& color,
                         const ReliefParameters& p) noexcept {
    const shared::raycache_cdct_store_key k = shared::raycache_cdct_escape_store(direction, p.max_depth);
    return cube.store(k.key, DepthSample{color, k.distance});
}

// Stores what a ray traced from `origin` along `direction` brought back (shared/cdct_store.h): its hit
// (store_hit at origin + distance * unit(direction)), or, for an infinite or NaN distance, an escape
// (store_escape). Nothing for a negative distance or a direction that is not one (false, no store made).
// `path`, when given, is what the traced path saw (raycache/path_record.hpp): the texel's tile keeps it
// for exact invalidation (raycache/invalidation.hpp); without it the texel counts as having seen anything.
// Thread-safe as CacheCube::store.
inline bool store_traced(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& origin,
                         const glm::vec3& direction, const TracedRay& traced, const ReliefParameters& p,
                         const PathRecord* path = nullptr) noexcept {
    const shared::raycache_cdct_store_key k = shared::raycache_cdct_traced_store(
        origin, direction, traced.distance, bounds.centre, bounds.half_size, p.max_depth);
    if (!k.store) return false;
    const DepthSample sample{traced.color, k.distance};
    return path ? cube.store(k.key, sample, *path) : cube.store(k.key, sample);
}

// Algorithm 1 with the CDCT: the search p.search names (depth_search) answers when it can; otherwise trace() runs, its hit is
// stored (store_traced: store_hit, or store_escape when it escaped; nothing for a negative distance, which
// would key the hit by a point behind the ray) and its colour returned unchanged.
// trace: callable `TracedRay trace()`, or `TracedRay trace(PathRecord&)`, which also reports what the path
// hit (raycache/path_record.hpp), stored with the texel so exact invalidation can keep it when nothing it
// saw moved. `texels_read`, when given, receives the search's texel count.
// `pyramid`, when given, speeds up the relief search (see relief_search); the secant search needs none.
// `found`, when given, receives the search's outcome (on a hit, where it met the cached surface).
template <class Trace>
glm::vec3 cdct_cached_trace(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& origin,
                            const glm::vec3& direction, const ReliefParameters& p, Trace&& trace,
                            int* texels_read = nullptr, const DepthPyramid* pyramid = nullptr, ReliefResult* found_out = nullptr) {
    constexpr bool records = std::is_invocable_r_v<TracedRay, Trace&, PathRecord&>;
    static_assert(records || std::is_invocable_r_v<TracedRay, Trace&>,
                  "RayCache cdct_cached_trace: trace must be callable as `TracedRay trace()` or `TracedRay trace(raycache::PathRecord&)`");
    const auto use = cube.in_frame();
    const ReliefResult found = depth_search(cube, bounds, origin, direction, p, pyramid);
    if (texels_read) *texels_read = found.texels_read;
    if (found_out) *found_out = found;
    if (found.hit) return found.color;
    PathRecord path;
    const TracedRay traced = [&] {
        if constexpr (records) return trace(path);
        else return trace();
    }();
    // A ray that filled a texel stands for what the texel's hits will save (raycache/resting.hpp).
    if (store_traced(cube, bounds, origin, direction, traced, p, records ? &path : nullptr)) cube.record_filled_work(traced.work);
    return traced.color;
}

} // namespace raycache
