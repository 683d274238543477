#version 450
// Stores, lookups and searches of both techniques with the confidence test (RAYCACHE_CONFIDENCE), RayCache's
// default bindings (CCT 0, 1, CDCT 2, 3, frame 4, doubtful bits 5, 6), for test_vulkan_confidence.cpp. The
// cubes come from the cube tables that the mark pass reads (bindings 7, 8). Compiled again with
// -DCONFIDENCE_QUERIES_CCT (confidence_queries_cct.spv: modes 2 to 4 answer nothing; no 64-bit feature).
#extension GL_GOOGLE_include_directive : require
#ifndef CONFIDENCE_QUERIES_CCT
#define RAYCACHE_CDCT
#endif
#define RAYCACHE_CONFIDENCE
#include "raycache/raycache.glsl"

layout(local_size_x = 64) in;

struct Query {
    vec3 direction; // CCT: the direction; CDCT store: the key; searches: the ray's direction
    uint mode;      // 0: CCT store, 1: CCT lookup, 2: CDCT store(key, colour, distance), 3: secant search, 4: relief walk
    vec3 color;
    float distance;
    vec3 origin; // searches: the ray's origin
    uint cube;   // in the technique's table
};
layout(push_constant) uniform Push { uint count; };
layout(std430, binding = 7) readonly buffer CctCubes { raycache_gpu_cube cct_cubes[]; };
layout(std430, binding = 8) readonly buffer CdctCubes { raycache_gpu_cube cdct_cubes[]; };
layout(std430, binding = 9) readonly buffer Queries { Query queries[]; };
layout(std430, binding = 10) writeonly buffer Results { uvec4 results[]; }; // hit or stored, colour bits

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    Query q = queries[i];
    uvec4 result = uvec4(0u);
    if (q.mode == 0u) {
        result.x = raycache_cct_store(cct_cubes[q.cube], q.direction, q.color) ? 1u : 0u;
    } else if (q.mode == 1u) {
        raycache_cct_result r = raycache_cct_lookup(cct_cubes[q.cube], q.direction);
        result = uvec4(r.hit ? 1u : 0u, floatBitsToUint(r.color));
    }
#ifndef CONFIDENCE_QUERIES_CCT
    else if (q.mode == 2u) {
        result.x = raycache_cdct_store(cdct_cubes[q.cube], q.direction, q.color, q.distance) ? 1u : 0u;
    } else {
        raycache_relief_result r = q.mode == 3u
            ? raycache_cdct_secant_search(cdct_cubes[q.cube], q.origin, q.direction, raycache_default_relief_parameters())
            : raycache_relief_search(cdct_cubes[q.cube], q.origin, q.direction, raycache_default_relief_parameters());
        result = uvec4(r.hit ? 1u : 0u, floatBitsToUint(r.color));
    }
#endif
    results[i] = result;
}
