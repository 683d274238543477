#version 450
// rsh_final.comp: the final intersection at the leaves (paper section 3.3): each (leaf, primitive) pair
// intersects its ray with the primitive (the BVH tracer's very tests, primitives.glsl) and keeps the
// closest hit by a 64-bit atomicMin of (t bits, primitive), across pairs and batches.
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_gpu_shader_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
layout(local_size_x = 64) in;
#include "rsh_common.glsl"
#include "primitives.glsl"

layout(std430, binding = 9) buffer Hits { uint64_t hits[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= control[CTL_COUNT]) return;
    raycache_rsh_pair p = pairs_in[i];
    uint ray = p.node - pc.child_first;
    if (ray >= control[CTL_RAYS]) return;
    raycache_rsh_ray r = rays[ray];
    raycache_rsh_primitive q = primitives[p.primitive];
    float t = 0.0, u = 0.0, v = 0.0;
    bool hit = q.c.w != 0.0 ? hit_sphere(q.a, r.origin, r.direction, r.tmax, t)
                            : hit_triangle_vertices(q.a.xyz, q.b.xyz, q.c.xyz, r.origin, r.direction, r.tmax, t, u, v);
    if (hit) atomicMin(hits[ray], (uint64_t(floatBitsToUint(t)) << 32) | uint64_t(p.primitive));
}
