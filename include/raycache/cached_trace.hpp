// raycache/cached_trace.hpp: Algorithm 1 of the thesis (the CCT's whole ray path) as one generic helper.
#pragma once

#include <type_traits>
#include <utility>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"

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
    if (std::optional<Value> cached = cube.lookup(direction)) return *cached;
    Value traced = std::forward<Trace>(trace)();
    cube.store(direction, traced);
    return traced;
}

} // namespace raycache
