// raycache/cached_trace.hpp: Algorithm 1 of the thesis (the CCT's whole ray path) as one generic helper.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <cstdint>
#include <optional>
#include <type_traits>
#include <utility>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"
#include "raycache/filtered_lookup.hpp"
#include "raycache/path_record.hpp"
#include "raycache/traced_ray.hpp"

namespace raycache {

// What the ray leaving an object in `direction` brings back: the cube's value when it holds one,
// otherwise trace(), whose result is stored for later frames and returned unchanged (not re-encoded,
// so a frame rendered with a cold cube equals the uncached frame bit for bit).
// trace: any callable `Value trace()`; it runs only on a miss. Thread-safe as CacheCube::lookup/store.
// A `direction` that is not a direction misses and is not stored; trace() still answers it.
template <class Texel, class Trace>
typename Texel::Value cached_trace(CacheCube<Texel>& cube, const glm::vec3& direction, Trace&& trace) {
    using Value = typename Texel::Value;
    static_assert(std::is_invocable_r_v<Value, Trace&>, "RayCache cached_trace: trace must be callable as `Value trace()`");
    const auto use = cube.in_frame();
    if (std::optional<Value> cached = cube.lookup(direction)) return *cached;
    Value traced = std::forward<Trace>(trace)();
    cube.store(direction, traced);
    return traced;
}

namespace detail {
// TracedRay::work of a traced result, 0 for a result type without it (nothing reported).
template <class Traced>
std::uint32_t reported_work(const Traced& traced) noexcept {
    if constexpr (std::is_convertible_v<Traced, TracedRay>) return TracedRay(traced).work;
    else return 0;
}

// The answer of a filtered CCT lookup whose own texel is visible: the bilinear mean of the visible texels
// around `direction` (never empty, since the own texel is one of them).
inline glm::vec3 filtered_answer(const CctCube& cube, const glm::vec3& direction) noexcept {
    return *filtered_value(direction, cube.face_size(), [&](const TexelAddress& t) { return cube.peek_at(t); });
}
} // namespace detail

// cached_trace() for a CCT cube with a filtered value: a hit exactly when cached_trace() would hit (the
// direction's own texel is visible), answered by the bilinear mean of the visible texels around
// `direction` (raycache/filtered_lookup.hpp) rather than by the own texel alone. Gating on the own texel
// keeps every miss able to fill what caused it, and keeps hit rates and cold frames those of cached_trace().
// Thread-safe as CacheCube::lookup/store; counted as one lookup.
template <class Trace>
glm::vec3 filtered_cached_trace(CctCube& cube, const glm::vec3& direction, Trace&& trace) {
    static_assert(std::is_invocable_r_v<glm::vec3, Trace&>,
                  "RayCache filtered_cached_trace: trace must be callable as `glm::vec3 trace()`");
    const auto use = cube.in_frame();
    MissReason why = MissReason::empty;
    if (cube.peek(direction, &why)) {
        cube.record_hit();
        return detail::filtered_answer(cube, direction);
    }
    cube.record_miss(why);
    glm::vec3 traced = std::forward<Trace>(trace)();
    cube.store(direction, traced);
    return traced;
}

// cct_cached_trace() below, for a ray whose texel the caller already found (cube.texel_of(direction)):
// the Embree adapter uses the texel for its direction statistics too.
template <class Trace>
glm::vec3 cct_cached_trace_at(CctCube& cube, const std::optional<TexelAddress>& texel, const glm::vec3& direction,
                              const glm::vec3& origin, const OriginTolerance* tolerance, bool filtered, Trace&& trace) {
    constexpr bool records = std::is_invocable_v<Trace&, PathRecord&>;
    static_assert(records || std::is_invocable_v<Trace&>,
                  "RayCache cct_cached_trace: trace must be callable as `TracedRay trace()` or `TracedRay trace(raycache::PathRecord&)`");
    const auto use = cube.in_frame();
    PathRecord path;
    auto run = [&] {
        if constexpr (records) return trace(path);
        else return trace();
    };
    if (!texel) { // not a direction, or a ray the caller cannot let the cube answer: a miss, nothing stored
        cube.record_miss(MissReason::outside);
        return run().color;
    }
    const std::optional<glm::vec3> cached = tolerance ? cube.lookup_at(*texel, origin, *tolerance) : cube.lookup_at(*texel);
    if (cached)
        return filtered ? detail::filtered_answer(cube, direction)
                        : *cached;
    const auto traced = run();
    const glm::vec3 colour = traced.color;
    bool stored = false;
    if (tolerance) stored = cube.store_at(*texel, colour, origin, traced.distance, *tolerance, records ? &path : nullptr);
    else if (records) stored = cube.store_at(*texel, colour, path);
    else stored = cube.store_at(*texel, colour);
    // A ray that filled a texel stands for what the texel's hits will save (raycache/resting.hpp).
    if (stored) cube.record_filled_work(detail::reported_work(traced));
    return colour;
}

// The CCT's whole ray path for a ray leaving from `origin`, as SceneCache runs it: a lookup with the origin
// test (tolerance; null: none, the direction alone keys the texel), else trace() and a store of its colour
// with the origin and the hit distance. trace() returns anything with members `color` and `distance` (as
// raycache::TracedRay; infinity when the ray escaped) and is callable either as `trace()` or as
// `trace(PathRecord&)`: the second form reports what the path hit after leaving (raycache/path_record.hpp),
// and the colour is stored with that record, so raycache/invalidation.hpp can drop exactly the texels a
// moved object can have changed. filtered: a hit answers with the bilinear mean of the visible texels
// around `direction` instead of its own texel. The texel is found once for the lookup and the store.
// Thread-safe as CacheCube::lookup/store.
template <class Trace>
glm::vec3 cct_cached_trace(CctCube& cube, const glm::vec3& direction, const glm::vec3& origin, const OriginTolerance* tolerance,
                           bool filtered, Trace&& trace) {
    return cct_cached_trace_at(cube, cube.texel_of(direction), direction, origin, tolerance, filtered, std::forward<Trace>(trace));
}

} // namespace raycache
