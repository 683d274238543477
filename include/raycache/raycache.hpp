// raycache/raycache.hpp: the whole core library (everything but the opt-in adapters).
#pragma once

#include "raycache/requires_cpp17.hpp"

#include "raycache/version.hpp"
#include "raycache/assert.hpp"
#include "raycache/cube_face.hpp"
#include "raycache/filtered_lookup.hpp"
#include "raycache/texel.hpp"
#include "raycache/statistics.hpp"
#include "raycache/memory_budget.hpp"
#include "raycache/cache_cube.hpp"
#include "raycache/adaptive_resolution.hpp"
#include "raycache/edge_confidence.hpp"
#include "raycache/cached_trace.hpp"
#include "raycache/depth_pyramid.hpp"
#include "raycache/cdct.hpp"
#include "raycache/cube_placement.hpp"
#include "raycache/cdct_cache.hpp"
#include "raycache/prefill.hpp"
#include "raycache/cache_file.hpp"
#include "raycache/gpu_buffers.hpp"
#include "raycache/gpu_adaptive.hpp"
