#version 450
// rsh_build.comp: one level of the hierarchy, bottom-up (paper section 3.2): node k of the level starting at
// pc.parent_first encloses nodes 4k..4k+3 of the level below (pc.child_first); pc.count nodes. A node over
// no ray slot (its first slot, k * 4^pc.arg, at or past control[CTL_RAYS]) is empty without reading its
// children: the passes run only over the nodes that the count needs (rsh_plan.comp), so the children of
// such a node may be left from an earlier trace.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
#include "rsh_common.glsl"

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= pc.count) return;
    if ((k << (2u * pc.arg)) >= control[CTL_RAYS]) {
        nodes[pc.parent_first + k] = raycache_rsh_empty_node();
        return;
    }
    uint c = pc.child_first + 4u * k;
    nodes[pc.parent_first + k] = raycache_rsh_enclose(nodes[c], nodes[c + 1u], nodes[c + 2u], nodes[c + 3u]);
}
