#version 450
// rsh_scan_add.comp: finishes a level of the prefix sum: each element of level pc.arg gets the exclusive
// prefix of its block (the scanned level above).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 256) in;
#include "rsh_common.glsl"

void main() {
    uint level = pc.arg;
    uint j = gl_GlobalInvocationID.x;
    if (j >= control[CTL_N + level]) return;
    uint here = level == 0u ? 0u : pc.off1;
    uint above = level == 0u ? pc.off1 : pc.off2;
    scan[here + j] += scan[above + j / SCAN_BLOCK];
}
