#version 450
// raycache_cube_rests for the C++ cross-check (test_vulkan_resting.cpp): one direction and cube a query.
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_FRAME_BINDING 2 // counters and resting words (raycache/frame.glsl)
#include "raycache/cube.glsl"

layout(local_size_x = 64) in;

struct Query {
    vec3 direction;
    uint cube;
};
layout(push_constant) uniform Push { uint count; };
layout(std430, binding = 0) readonly buffer Cubes { raycache_gpu_cube cubes[]; };
layout(std430, binding = 1) readonly buffer Queries { Query queries[]; };
layout(std430, binding = 3) writeonly buffer Results { uint results[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    results[i] = raycache_cube_rests(cubes[queries[i].cube], queries[i].direction) ? 1u : 0u;
}
