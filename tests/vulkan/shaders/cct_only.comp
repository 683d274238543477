#version 450
// A shader that uses only the CCT, through raycache/raycache.glsl as the README says to include it: it must
// need no 64-bit feature (test_vulkan_glsl_features.cpp creates it on a device without shaderInt64). Each of
// six invocations looks up one axis direction in the cube of the push constants and stores on a miss.
// Compiled again with -DWITH_CDCT (with_cdct.spv), which asks for the CDCT and stores through it too: that
// one must declare Int64 (the check's control).
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_CCT_BINDING 0
#define RAYCACHE_CCT_PENDING_BINDING 1
#define RAYCACHE_FRAME_BINDING 3
#ifdef WITH_CDCT
#define RAYCACHE_CDCT
#define RAYCACHE_CDCT_BINDING 4
#define RAYCACHE_CDCT_PENDING_BINDING 5
#endif
#include "raycache/raycache.glsl"

layout(local_size_x = 6) in;
layout(push_constant) uniform Push { raycache_gpu_cube cube; };
layout(std430, binding = 2) writeonly buffer Results { uvec2 results[]; }; // (hit, stored) per invocation

void main() {
    uint i = gl_LocalInvocationID.x;
    vec3 direction = vec3(0.0);
    direction[i / 2u] = (i % 2u == 0u) ? 1.0 : -1.0;
    raycache_cct_result c = raycache_cct_lookup(cube, direction);
    bool stored = false;
    if (!c.hit) stored = raycache_cct_store(cube, direction, vec3(0.25, 0.5, 1.0));
#ifdef WITH_CDCT
    stored = raycache_cdct_store_escape(cube, direction, vec3(0.25), raycache_default_relief_parameters()) && stored;
#endif
    results[i] = uvec2(c.hit ? 1u : 0u, stored ? 1u : 0u);
}
