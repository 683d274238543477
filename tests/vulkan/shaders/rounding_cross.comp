#version 450
// raycache/shared/rounding.h in GLSL for the C++ cross-check (test_vulkan_rounding.cpp): query i holds
// (a, b, q0, y) of a division or (x, s0, h0, -) of a square root (kind 0 or 1); the result holds the bits
// of the refinement from those starts, and of raycache_divide / raycache_sqrt (the device's own operator,
// corrected) on the same operands.
#extension GL_GOOGLE_include_directive : require
#include "raycache/shared/rounding.h"

layout(local_size_x = 64) in;
struct Query {
    vec4 operands;
    uint kind;
    uint pad0;
    uint pad1;
    uint pad2;
};
layout(push_constant) uniform Push { uint count; };
layout(std430, binding = 0) readonly buffer Queries { Query queries[]; };
layout(std430, binding = 1) writeonly buffer Results { uvec2 results[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    vec4 q = queries[i].operands;
    if (queries[i].kind == 0u)
        results[i] = uvec2(floatBitsToUint(raycache_divide_refined(q.x, q.y, q.z, q.w)), floatBitsToUint(raycache_divide(q.x, q.y)));
    else
        results[i] = uvec2(floatBitsToUint(raycache_sqrt_refined(q.x, q.y, q.z)), floatBitsToUint(raycache_sqrt(q.x)));
}
