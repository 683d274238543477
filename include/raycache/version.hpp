// raycache/version.hpp: the library's version, as macros for the preprocessor and a string at run time.
#pragma once

#include "raycache/requires_cpp17.hpp"

#define RAYCACHE_VERSION_MAJOR 0
#define RAYCACHE_VERSION_MINOR 1
#define RAYCACHE_VERSION_PATCH 0
/* Single number for comparisons: 100 * 100 * major + 100 * minor + patch. */
#define RAYCACHE_VERSION (RAYCACHE_VERSION_MAJOR * 10000 + RAYCACHE_VERSION_MINOR * 100 + RAYCACHE_VERSION_PATCH)

namespace raycache {

// "major.minor.patch" of the headers that were compiled in.
inline const char* version_string() noexcept { return "0.1.0"; }

} // namespace raycache
