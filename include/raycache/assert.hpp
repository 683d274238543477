// raycache/assert.hpp: RAYCACHE_ASSERT, the check for programmer errors (misuse of the API).
//
// Bad data (a NaN direction, an unfilled texel) is never asserted: it is a miss or a refused store.
// Define RAYCACHE_ASSERT before including any RayCache header to route these checks to your own handler.
#pragma once

#include "raycache/requires_cpp17.hpp"

#ifndef RAYCACHE_ASSERT
#include <cassert>
#define RAYCACHE_ASSERT(condition) assert(condition)
#endif
