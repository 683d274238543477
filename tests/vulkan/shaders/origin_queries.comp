#version 450
// The CCT's stores and lookups with the origin test (RAYCACHE_ORIGINS) and the confidence test, RayCache's
// default bindings (CCT 0, 1, frame 4, doubtful bits 5, origin records 9), for test_vulkan_origins.cpp; the
// cubes come from the cube table the end-of-frame passes read (binding 7).
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_CONFIDENCE
#define RAYCACHE_ORIGINS
#include "raycache/cct.glsl"

layout(local_size_x = 64) in;

struct Query {
    vec3 direction;
    uint mode; // 0: store_from, 1: lookup_from
    vec3 color;
    float hit_distance;
    vec3 origin;
    uint cube;
};
layout(push_constant) uniform Push { uint count; float drift; float parallax; };
layout(std430, binding = 7) readonly buffer CctCubes { raycache_gpu_cube cubes[]; };
layout(std430, binding = 10) readonly buffer Queries { Query queries[]; };
layout(std430, binding = 11) writeonly buffer Results { uvec4 results[]; }; // hit or stored, colour bits

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    Query q = queries[i];
    raycache_origin_tolerance tolerance = raycache_origin_tolerance(drift, parallax);
    uvec4 result = uvec4(0u);
    if (q.mode == 0u) {
        result.x = raycache_cct_store_from(cubes[q.cube], q.direction, q.color, q.origin, q.hit_distance, tolerance) ? 1u : 0u;
    } else {
        raycache_cct_result r = raycache_cct_lookup_from(cubes[q.cube], q.direction, q.origin, tolerance);
        result = uvec4(r.hit ? 1u : 0u, floatBitsToUint(r.color));
    }
    results[i] = result;
}
