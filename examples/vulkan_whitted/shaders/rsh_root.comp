#version 450
// rsh_root.comp: the stream a batch starts with: one pair (root, primitive) per primitive of the batch,
// pc.count (<= capacity) primitives from pc.arg (none when the trace has no ray slot); resets the batch's
// control words.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
#include "rsh_common.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint count = control[CTL_RAYS] == 0u ? 0u : pc.count;
    if (i == 0u) {
        control[CTL_COUNT] = count;
        control[CTL_OVERFLOW] = 0u;
        control[CTL_LEAF_PAIRS] = 0u;
        control[CTL_SCALE] = floatBitsToUint(1.0);
    }
    if (i < count) pairs_in[i] = raycache_rsh_pair(0u, pc.arg + i);
}
