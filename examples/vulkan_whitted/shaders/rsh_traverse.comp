#version 450
// rsh_traverse.comp: one level of the top-down traversal (paper section 3.3): each pair (node, primitive)
// of the stream tests the primitive's bounding sphere against the node's four children (equation 1),
// one flag per child (pc.parent_first, pc.child_first: first nodes of the two levels).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
#include "rsh_common.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= control[CTL_COUNT]) return;
    raycache_rsh_pair p = pairs_in[i];
    vec4 s = spheres[p.primitive];
    uint first = pc.child_first + 4u * (p.node - pc.parent_first);
    for (uint c = 0u; c < 4u; ++c) flags[4u * i + c] = raycache_rsh_cone_sphere(nodes[first + c], s) ? 1u : 0u;
}
