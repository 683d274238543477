#version 450
// rsh_scatter.comp: the stream reduction's last step (paper section 4): each kept (child, primitive)
// candidate goes to its prefix-sum offset in the next stream; offsets at or past the capacity are not
// written (the plan pass then marks the batch overflowed), so no write ever leaves the buffer.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 256) in;
#include "rsh_common.glsl"

void main() {
    uint j = gl_GlobalInvocationID.x;
    if (j >= control[CTL_N] || flags[j] == 0u) return;
    uint at = scan[j];
    if (at >= pc.capacity) return;
    raycache_rsh_pair p = pairs_in[j / 4u];
    pairs_out[at] = raycache_rsh_pair(pc.child_first + 4u * (p.node - pc.parent_first) + j % 4u, p.primitive);
}
