#version 450
// CDCT searches (relief, secant, and the one the parameters name) and stores through RayCache's GLSL include, for the C++ cross-check
// (test_vulkan_cdct.cpp). Bindings moved from the defaults, to show that the macros work.
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_CDCT_BINDING 0
#define RAYCACHE_CDCT_PENDING_BINDING 1
#define RAYCACHE_FRAME_BINDING 5 // counters and store list (raycache/frame.glsl)
#include "raycache/cdct.glsl"

layout(local_size_x = 64) in;

struct Query {
    vec3 origin; // search: ray origin; store_hit: the hit point
    uint cube;
    vec3 direction; // search and store_escape: ray direction; store: key
    uint mode;      // 0: relief search, 1: store_hit, 2: store_escape, 3: store(key, colour, distance),
                    // 4: secant search, 5: raycache_cdct_search (parameters.search)
    vec3 color;
    float distance;
};
struct Result {
    uint hit; // search: hit; stores: stored
    int texels_read;
    float distance;
    uint pad;
    vec3 color;
    float pad1;
    vec3 point;
    float pad2;
};
layout(push_constant) uniform Push {
    raycache_relief_parameters parameters; // raycache::ReliefParameters, copied byte for byte
    uint count;
};
layout(std430, binding = 2) readonly buffer Cubes { raycache_gpu_cube cubes[]; };
layout(std430, binding = 3) readonly buffer Queries { Query queries[]; };
layout(std430, binding = 4) writeonly buffer Results { Result results[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    Query q = queries[i];
    raycache_gpu_cube cube = cubes[q.cube];
    Result result;
    result.hit = 0u;
    result.texels_read = 0;
    result.distance = 0.0;
    result.pad = 0u;
    result.color = vec3(0.0);
    result.pad1 = 0.0;
    result.point = vec3(0.0);
    result.pad2 = 0.0;
    if (q.mode == 0u || q.mode >= 4u) {
        raycache_relief_result r;
        if (q.mode == 0u) r = raycache_relief_search(cube, q.origin, q.direction, parameters);
        else if (q.mode == 4u) r = raycache_cdct_secant_search(cube, q.origin, q.direction, parameters);
        else r = raycache_cdct_search(cube, q.origin, q.direction, parameters);
        result.hit = r.hit ? 1u : 0u;
        result.texels_read = r.texels_read;
        result.distance = r.distance;
        result.color = r.color;
        result.point = r.point;
    } else {
        bool stored = false;
        if (q.mode == 1u) stored = raycache_cdct_store_hit(cube, q.origin, q.color, parameters);
        else if (q.mode == 2u) stored = raycache_cdct_store_escape(cube, q.direction, q.color, parameters);
        else stored = raycache_cdct_store(cube, q.direction, q.color, q.distance);
        result.hit = stored ? 1u : 0u;
    }
    results[i] = result;
}
