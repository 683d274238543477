// raycache/recorded_trace.hpp: cached_trace() for tracers that report what a traced path saw
// (raycache/path_record.hpp), so that the texels it fills can be invalidated exactly when objects move
// (raycache/invalidation.hpp).
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <optional>
#include <type_traits>
#include <utility>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"
#include "raycache/filtered_lookup.hpp"
#include "raycache/path_record.hpp"

namespace raycache {

// cached_trace(cube, direction, origin, drift, trace) (raycache/cached_trace.hpp) with a trace callable as
// `Value trace(PathRecord& path)`: on a miss it traces, filling `path` with what the path hit after leaving
// (PathRecord::hit, and the lit / chained / unbounded flags), and the value is stored with that record.
// drift < 0: no origin test. filtered: a hit answers with the bilinear mean of the visible texels around
// `direction` (as filtered_cached_trace). Thread-safe as CacheCube::lookup/store.
template <class Texel, class Trace>
typename Texel::Value cached_trace_recorded(CacheCube<Texel>& cube, const glm::vec3& direction, const glm::vec3& origin,
                                           float drift, bool filtered, Trace&& trace) {
    using Value = typename Texel::Value;
    static_assert(std::is_invocable_r_v<Value, Trace&, PathRecord&>,
                  "RayCache cached_trace_recorded: trace must be callable as `Value trace(raycache::PathRecord&)`");
    const auto use = cube.in_frame();
    const std::optional<Value> cached = drift >= 0.0f ? cube.lookup(direction, origin, drift) : cube.lookup(direction);
    if (cached) {
        if constexpr (std::is_same_v<Texel, CctTexel>) {
            if (filtered)
                return *filtered_value(direction, cube.face_size(), [&](const TexelAddress& t) { return cube.peek_at(t); });
        }
        return *cached;
    }
    PathRecord path;
    Value traced = trace(path);
    if (drift >= 0.0f) cube.store(direction, traced, origin, path);
    else cube.store(direction, traced, path);
    return traced;
}

} // namespace raycache
