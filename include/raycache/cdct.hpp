// raycache/cdct.hpp: the colour-and-depth caching technique (thesis ch. 4): stores keyed by where the ray
// hit, and the relief search (thesis Algorithm 4) that finds a ray's hit in the cube's depth image.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"
#include "raycache/depth_pyramid.hpp"
#include "raycache/shared/depth_secant.h"
#include "raycache/shared/ray_box.h"

namespace raycache {

// Where a cube sits: the box [centre - half_size, centre + half_size] encloses the cached object.
struct CubeBounds {
    glm::vec3 centre{0.0f};
    float half_size = 1.0f;
};

// How a CDCT lookup finds the ray's hit in the cube's depth image.
enum class DepthSearch {
    secant = RAYCACHE_DEPTH_SEARCH_SECANT, // a few reads: jump to the sphere of the distance read, then false
                                           // position (shared/depth_secant.h)
    relief = RAYCACHE_DEPTH_SEARCH_RELIEF, // the thesis's walk in steps of `step` (over a DepthPyramid when one
                                           // is given), then bisection
};

// Tuning of the CDCT's search; step and epsilon default to one of the thesis's (delta, epsilon) pairs.
struct ReliefParameters {
    float step = 0.2f;        // delta: length of a linear step along the ray, world units (linear walk only)
    float epsilon = 0.02f;    // binary refinement stops when the bracket is shorter than this
    int max_steps = 1024;     // linear steps, or pyramid nodes read, before giving up (a miss); at most
                              // RAYCACHE_MAX_RELIEF_STEPS (16,777,216)
    float max_depth = 100.0f; // distance at which rays that escaped to the environment are stored
    // A crossing where the ray ends up more than max_gap beyond the cached surface (|Q - C| - d, after
    // refinement) is a depth discontinuity: the ray passed behind an edge, where the cube saw nothing.
    // Such a crossing is a miss instead of the wrong surface. Infinity (the thesis) accepts every crossing.
    float max_gap = std::numeric_limits<float>::infinity();
    DepthSearch search = DepthSearch::secant; // what cdct_cached_trace uses (relief_search is always the walk)
    int max_reads = 8;                        // secant: reads before giving up (a miss), 1..RAYCACHE_SECANT_MAX_READS
};
// GLSL's raycache_relief_parameters (raycache/cdct.glsl) is this struct field for field: a std430 copy of
// its bytes (a push constant, a buffer) reads as the same parameters in a shader.
static_assert(sizeof(ReliefParameters) == 28 && offsetof(ReliefParameters, max_gap) == 16 &&
                  offsetof(ReliefParameters, search) == 20 && offsetof(ReliefParameters, max_reads) == 24 &&
                  sizeof(DepthSearch) == 4,
              "ReliefParameters must keep the layout of GLSL's raycache_relief_parameters");

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

// For each face, the vectors whose dot product with v gives its major coordinate m, sc and tc: read once,
// at start-up, off the shared face table (sc and tc are linear in v; m points along the face's axis).
struct FaceAxes {
    glm::vec3 m{0.0f}, sc{0.0f}, tc{0.0f};
};
inline std::array<FaceAxes, RAYCACHE_FACE_COUNT> make_face_axes() {
    std::array<FaceAxes, RAYCACHE_FACE_COUNT> axes{};
    for (int f = 0; f < RAYCACHE_FACE_COUNT; ++f) {
        axes[static_cast<std::size_t>(f)].m[f / 2] = f % 2 == 0 ? 1.0f : -1.0f;
        for (int axis = 0; axis < 3; ++axis) {
            glm::vec3 e(0.0f);
            e[axis] = 1.0f;
            const glm::vec2 st = shared::raycache_face_coordinates(e, f);
            axes[static_cast<std::size_t>(f)].sc[axis] = st.x;
            axes[static_cast<std::size_t>(f)].tc[axis] = st.y;
        }
    }
    return axes;
}
inline const std::array<FaceAxes, RAYCACHE_FACE_COUNT> face_axes = make_face_axes();

// True when the box can be searched (shared/ray_box.h, as the GLSL search decides).
inline bool is_usable(const CubeBounds& b) noexcept { return shared::raycache_box_is_usable(b.centre, b.half_size); }

// The relief search's state along one ray origin + t * d (d unit), shared by the linear and the pyramid walk.
class ReliefWalk {
public:
    ReliefWalk(const CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& origin, const glm::vec3& d,
               const ReliefParameters& p)
        : cube_(cube), bounds_(bounds), origin_(origin), d_(d), p_(p) {}

    ReliefResult result;
    DepthSample sample; // the texel read last
    bool crossed = false; // whether the ray at the last read is at or beyond that texel's surface

    // (origin + t d) - centre, without FMA (shared/ray_box.h, as GLSL computes it).
    glm::vec3 from_centre(float t) const { return shared::raycache_ray_from_centre(origin_, d_, t, bounds_.centre); }

    // Reads the texel in the direction of the ray's point at t; false when it is empty or not yet visible.
    bool read(float t) {
        const glm::vec3 v = from_centre(t);
        ++result.texels_read;
        const std::optional<DepthSample> texel = cube_.peek(v);
        if (!texel) return false;
        sample = *texel;
        crossed = sample.distance <= shared::raycache_length(v);
        return true;
    }

    // Bisects [lo, hi] (lo before the crossing, hi at or past it, `sample` read at hi) down to epsilon,
    // then accepts the crossing unless it is a depth discontinuity.
    ReliefResult refine(float lo, float hi) {
        DepthSample at_hi = sample;
        for (int k = 0; k < 64 && hi - lo > p_.epsilon; ++k) {
            const float mid = 0.5f * (lo + hi);
            if (!read(mid)) return miss();
            if (crossed) {
                hi = mid;
                at_hi = sample;
            } else {
                lo = mid;
            }
        }
        if (shared::raycache_length(from_centre(hi)) - at_hi.distance > p_.max_gap) return miss();
        sample = at_hi;
        return hit(hi);
    }

    ReliefResult hit(float t) {
        result.hit = true;
        result.distance = t;
        result.point = shared::raycache_ray_point(origin_, d_, t);
        result.color = sample.color;
        return result;
    }
    ReliefResult miss() {
        result.hit = false;
        return result;
    }

    // Linear walk (thesis Algorithm 4): steps of p.step from t until the first crossing. A step too small
    // to change t (t + step == t) would read the same point for ever: the walk ends there, a miss. As that
    // happens once t exceeds about 2^24 steps, the walk takes at most about 2^25 steps whatever max_steps says.
    ReliefResult linear(float t) {
        for (int i = 0; i < p_.max_steps; ++i) {
            const float previous = t;
            t += p_.step;
            if (!(t > previous)) return miss();
            if (!read(t)) return miss();
            if (crossed) return refine(previous, t);
        }
        return miss();
    }

    // Pyramid walk: at the ray's point, look at the block around its texel at some level; when the whole
    // block lies beyond the point, jump to where the ray leaves the block or reaches the block's nearest
    // distance and go up a level; otherwise go down one; at level 0, a crossing is refined as usual.
    ReliefResult hierarchical(float t, const DepthPyramid& pyramid) {
        const int n = cube_.face_size();
        float safe = t; // the ray is before every surface on [start, safe]
        int level = std::min(1, pyramid.levels());
        for (int visits = 0; visits < p_.max_steps; ++visits) {
            const glm::vec3 v = from_centre(t);
            const float distance_to_centre = shared::raycache_length(v);
            const shared::raycache_texel_address a = shared::raycache_texel_of(v, n);
            if (a.face == RAYCACHE_NO_FACE) return miss();
            float nearest;
            if (level == 0) {
                if (!read(t)) return miss();
                if (crossed) return refine(safe, t);
                nearest = sample.distance;
            } else {
                ++result.texels_read;
                nearest = pyramid.min_distance(a.face, level, a.column >> level, a.row >> level);
                if (!(distance_to_centre < nearest)) {
                    --level;
                    continue;
                }
            }
            // Safe up to where the ray leaves this block or comes within `nearest` of the centre.
            const float next = std::min(block_exit(t, a, level), reach(nearest));
            safe = std::max(safe, next);
            t = std::max(next, t) + std::max(1e-3f * p_.epsilon, 1e-6f * (1.0f + t));
            level = std::min(level + 1, pyramid.levels());
        }
        return miss();
    }

private:
    // Where |from_centre(t)| reaches `radius` going outwards (the far root; the ray is inside that sphere;
    // 0 when it lies behind the origin, which the walk treats as any point behind t).
    float reach(float radius) const { return shared::raycache_sphere_exit(origin_ - bounds_.centre, d_, radius); }

    // Where the ray, now at t inside block (a.column >> level, a.row >> level) of face a.face, leaves the
    // block's cone from the centre. The block spans face coordinates sc/m in [u0, u1] and tc/m in [v0, v1];
    // each bound is a plane through the centre, so along the ray each test is linear in t.
    float block_exit(float t, const shared::raycache_texel_address& a, int level) const {
        const int n = cube_.face_size();
        const int first_column = (a.column >> level) << level, first_row = (a.row >> level) << level;
        const float u0 = 2.0f * first_column / n - 1.0f, u1 = 2.0f * std::min(first_column + (1 << level), n) / n - 1.0f;
        const float v0 = 2.0f * first_row / n - 1.0f, v1 = 2.0f * std::min(first_row + (1 << level), n) / n - 1.0f;
        const glm::vec3 p = from_centre(t);
        // sc, tc and m as linear forms of the vector from the centre (the face table).
        const FaceAxes& axes = face_axes[static_cast<std::size_t>(a.face)];
        const glm::vec3 &m_axis = axes.m, &u_axis = axes.sc, &v_axis = axes.tc;
        float exit = std::numeric_limits<float>::infinity();
        auto leave = [&](const glm::vec3& normal) { // the ray stays where dot(normal, p) >= 0
            const float rate = shared::raycache_dot_no_fma(normal, d_);
            if (rate < 0.0f) exit = std::min(exit, t + std::max(shared::raycache_dot_no_fma(normal, p), 0.0f) / -rate);
        };
        // (m_axis holds 0 and +-1: its products are exact, fused or not.)
        leave(u_axis - u0 * m_axis);
        leave(u1 * m_axis - u_axis);
        leave(v_axis - v0 * m_axis);
        leave(v1 * m_axis - v_axis);
        return exit;
    }


    const CacheCube<CdctTexel>& cube_;
    const CubeBounds& bounds_;
    glm::vec3 origin_;
    glm::vec3 d_;
    const ReliefParameters& p_;
};

} // namespace detail

// Thesis Algorithm 4 on a perspective depth cube: walk the ray origin + t * unit(direction) from where it
// leaves the cube's box; at each point Q read the texel in direction Q - centre and compare |Q - centre|
// with its distance; at the first crossing, bisect down to p.epsilon. Without a pyramid the walk takes
// steps of p.step (the thesis); with one (kept up to date for this cube) it skips blocks of texels that
// lie beyond the ray. An empty or not-yet-visible texel read on the way makes the search a miss; so do
// running out of p.max_steps, a linear step too small to move the ray on, a crossing more than p.max_gap
// behind the surface, a bad origin, direction or box, and parameters no search can run with (step or
// epsilon not > 0, max_steps above RAYCACHE_MAX_RELIEF_STEPS: no texel read). Reads at most
// 1 + min(p.max_steps, RAYCACHE_MAX_RELIEF_STEPS) + 64 texels or pyramid nodes. Counts one lookup on the
// cube (hit or miss); texels_read counts pyramid nodes too. Thread-safe as CacheCube::lookup.
inline ReliefResult relief_search(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& origin,
                                  const glm::vec3& direction, const ReliefParameters& p,
                                  const DepthPyramid* pyramid = nullptr) noexcept {
    if (!is_direction(direction) || !shared::raycache_is_finite3(origin) || !detail::is_usable(bounds) || !(p.step > 0.0f) ||
        !(p.epsilon > 0.0f) || p.max_steps > RAYCACHE_MAX_RELIEF_STEPS) {
        cube.record_lookup(false);
        return ReliefResult{};
    }
    RAYCACHE_ASSERT(!pyramid || pyramid->face_size() == cube.face_size());
    const glm::vec3 d = shared::raycache_unit(direction);
    const auto use = cube.in_frame();
    detail::ReliefWalk walk(cube, bounds, origin, d, p);
    const float start = shared::raycache_box_exit_distance(origin, d, bounds.centre, bounds.half_size);
    ReliefResult result;
    if (!walk.read(start))
        result = walk.miss();
    else if (walk.crossed)
        result = walk.hit(start); // the cached surface lies inside the box: nothing to refine
    else if (pyramid && pyramid->face_size() == cube.face_size())
        result = walk.hierarchical(start, *pyramid);
    else
        result = walk.linear(start);
    cube.record_lookup(result.hit);
    return result;
}

// The CDCT's cheap search (shared/depth_secant.h, the same steps as GLSL's): from where the ray leaves the
// box, jump to where the ray reaches the distance read, then refine a bracketed crossing by false position;
// answer only when the point read lies within p.epsilon of its texel's surface (or a bracket shorter than
// p.epsilon ends at most p.max_gap behind it). A miss for an empty or not-yet-visible texel, after
// p.max_reads reads without such an answer, and for bad input (no texel read). Reads at most
// min(p.max_reads, RAYCACHE_SECANT_MAX_READS) texels. Counts one lookup. Thread-safe as CacheCube::lookup.
inline ReliefResult secant_search(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& origin,
                                  const glm::vec3& direction, const ReliefParameters& p) noexcept {
    ReliefResult result;
    const auto use = cube.in_frame();
    shared::raycache_secant_search s = shared::raycache_secant_start(origin, direction, bounds.centre, bounds.half_size,
                                                                     p.epsilon, p.max_gap, p.max_reads);
    while (s.status == RAYCACHE_SECANT_READ) {
        const std::optional<DepthSample> texel = cube.peek(shared::raycache_secant_point(s, s.t));
        s = texel ? shared::raycache_secant_step(s, true, texel->distance, texel->color)
                  : shared::raycache_secant_step(s, false, 0.0f, glm::vec3(0.0f));
    }
    result.texels_read = s.reads;
    result.hit = s.status == RAYCACHE_SECANT_HIT;
    if (result.hit) {
        result.distance = s.t;
        result.point = shared::raycache_ray_point(origin, s.d, s.t);
        result.color = s.color;
    }
    cube.record_lookup(result.hit);
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
    if (!shared::raycache_is_finite3(hit_point) || !detail::is_usable(bounds)) return cube.store(glm::vec3(0.0f), DepthSample{});
    const glm::vec3 from_centre = hit_point - bounds.centre;
    return cube.store(from_centre, DepthSample{color, std::min(shared::raycache_length(from_centre), p.max_depth)});
}

// Stores the colour of a ray that escaped to the environment in `direction`, as far away (p.max_depth).
inline bool store_escape(CacheCube<CdctTexel>& cube, const glm::vec3& direction, const glm::vec3& color,
                         const ReliefParameters& p) noexcept {
    return cube.store(direction, DepthSample{color, p.max_depth});
}

// What a secondary-ray trace returns to the CDCT: its colour, and the distance along the unit ray
// direction to what it hit (infinity or NaN when it escaped to the environment). A negative distance
// (a hit behind the ray's origin) is never stored: the colour is used, the cube left alone.
struct TracedRay {
    glm::vec3 color{0.0f};
    float distance = std::numeric_limits<float>::infinity();
};

// Algorithm 1 with the CDCT: the search p.search names (depth_search) answers when it can; otherwise trace() runs, its hit is
// stored (store_hit, or store_escape when it escaped; nothing for a negative distance, which would key
// the hit by a point behind the ray) and its colour returned unchanged.
// trace: callable `TracedRay trace()`. `texels_read`, when given, receives the search's texel count.
// `pyramid`, when given, speeds up the relief search (see relief_search); the secant search needs none.
template <class Trace>
glm::vec3 cdct_cached_trace(CacheCube<CdctTexel>& cube, const CubeBounds& bounds, const glm::vec3& origin,
                            const glm::vec3& direction, const ReliefParameters& p, Trace&& trace,
                            int* texels_read = nullptr, const DepthPyramid* pyramid = nullptr) {
    static_assert(std::is_invocable_r_v<TracedRay, Trace&>, "RayCache cdct_cached_trace: trace must be callable as `TracedRay trace()`");
    const auto use = cube.in_frame();
    const ReliefResult found = depth_search(cube, bounds, origin, direction, p, pyramid);
    if (texels_read) *texels_read = found.texels_read;
    if (found.hit) return found.color;
    const TracedRay traced = std::forward<Trace>(trace)();
    if (!is_direction(direction) || traced.distance < 0.0f) return traced.color;
    if (std::isfinite(traced.distance))
        store_hit(cube, bounds, shared::raycache_ray_point(origin, shared::raycache_unit(direction), traced.distance),
                  traced.color, p);
    else
        store_escape(cube, direction, traced.color, p);
    return traced.color;
}

} // namespace raycache
