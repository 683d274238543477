// raycache/requires_cpp17.hpp: every RayCache header includes this first, so that a build under C++11
// or C++14 stops at one clear message instead of a hundred errors from inside the library.
#pragma once

#if defined(_MSVC_LANG) ? _MSVC_LANG < 201703L : __cplusplus < 201703L
#error "RayCache needs C++17 or later: compile with -std=c++17 (CMake: link RayCache::RayCache, which asks for cxx_std_17)"
// Compilers carry on after #error; a missing include is fatal, so compilation stops here.
#include "RayCache stops here: C++17 is required (see the error above)"
#endif
