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

// cct_cached_trace() (raycache/cached_trace.hpp) for a trace callable as `R trace(PathRecord& path)`, R with
// members `color` and `distance` (as raycache::TracedRay): on a miss it traces, filling `path` with what the
// path hit after leaving (PathRecord::hit, and the lit / chained / unbounded flags), and the colour is
// stored with that record. tolerance: the origin test (null: none, the ray's direction alone keys it).
// filtered: a hit answers with the bilinear mean of the visible texels around `direction`.
// Thread-safe as CacheCube::lookup/store.
template <class Trace>
glm::vec3 cct_cached_trace_recorded(CctCube& cube, const glm::vec3& direction, const glm::vec3& origin,
                                    const OriginTolerance* tolerance, bool filtered, Trace&& trace) {
    static_assert(std::is_invocable_v<Trace&, PathRecord&>,
                  "RayCache cct_cached_trace_recorded: trace must be callable as `TracedRay trace(raycache::PathRecord&)`");
    const auto use = cube.in_frame();
    const std::optional<glm::vec3> cached = tolerance ? cube.lookup(direction, origin, *tolerance) : cube.lookup(direction);
    if (cached)
        return filtered ? *filtered_value(direction, cube.face_size(), [&](const TexelAddress& t) { return cube.peek_at(t); })
                        : *cached;
    PathRecord path;
    const auto traced = trace(path);
    const glm::vec3 colour = traced.color;
    if (tolerance) cube.store(direction, colour, origin, traced.distance, *tolerance, path);
    else cube.store(direction, colour, path);
    return colour;
}

} // namespace raycache
