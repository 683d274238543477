// rcx/scene_hash.hpp: a scene's fingerprint for cache files (raycache/cache_file.hpp): a file saved for one
// scene is refused by another.
#pragma once

#include <cstdint>

#include "rcx/scene.hpp"

namespace rcx {

// FNV-1a 64 of everything a cached colour depends on: every sphere and mesh (geometry, normals, material),
// the light, the environment, the ambient term and the recursion depth. Not the camera, its path or the
// name: a cache stays right when only those change. Equal scenes hash equal on every run and machine of
// one byte order.
std::uint64_t scene_hash(const Scene& scene);

} // namespace rcx
