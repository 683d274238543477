#version 450
// CCT lookups and stores through RayCache's GLSL include, for the C++ cross-check (test_vulkan_cct.cpp).
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_CCT_BINDING 0
#define RAYCACHE_CCT_PENDING_BINDING 1
#define RAYCACHE_FRAME_BINDING 5 // counters and store list (raycache/frame.glsl)
#include "raycache/cct.glsl"

layout(local_size_x = 64) in;

struct Query {
    vec3 direction;
    uint cube;
    vec3 color;
    uint store; // 0: lookup, 1: store
};
layout(push_constant) uniform Push { uint count; };
layout(std430, binding = 2) readonly buffer Cubes { raycache_gpu_cube cubes[]; };
layout(std430, binding = 3) readonly buffer Queries { Query queries[]; };
layout(std430, binding = 4) writeonly buffer Results { uvec4 results[]; }; // hit or stored, colour bits

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    Query q = queries[i];
    raycache_gpu_cube cube = cubes[q.cube];
    if (q.store != 0u) {
        results[i] = uvec4(raycache_cct_store(cube, q.direction, q.color) ? 1u : 0u, 0u, 0u, 0u);
    } else {
        raycache_cct_result r = raycache_cct_lookup(cube, q.direction);
        results[i] = uvec4(r.hit ? 1u : 0u, floatBitsToUint(r.color));
    }
}
