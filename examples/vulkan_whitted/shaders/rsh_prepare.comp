#version 450
// rsh_prepare.comp: the per-trace set-up of the ray-space hierarchy (rsh_engine.cpp): arg 0: the
// bounding sphere of each primitive (pc.count of them); arg 1: the leaves, one per ray slot (the trace's
// control[CTL_RAYS] slots, a count that may come from an earlier pass), empty for the padding up to
// 4^levels (leaves from pc.child_first, pc.parent_first of them in all); counts the slots and the rays
// that enter the hierarchy (tmax > 0) into the accumulators.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
#include "rsh_common.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (pc.arg == 0u) {
        if (i < pc.count) spheres[i] = raycache_rsh_bounding_sphere(primitives[i]);
        return;
    }
    if (i >= pc.parent_first) return;
    uint slots = control[CTL_RAYS];
    if (i == 0u) atomicAdd(control[ACC_SLOTS], slots);
    raycache_rsh_node leaf = i < slots ? raycache_rsh_leaf(rays[i]) : raycache_rsh_empty_node();
    if (leaf.radius >= 0.0) atomicAdd(control[ACC_LIVE], 1u);
    nodes[pc.child_first + i] = leaf;
}
