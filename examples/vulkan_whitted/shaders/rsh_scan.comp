#version 450
// rsh_scan.comp: one level of a work-efficient exclusive prefix sum (Blelloch's up-sweep and down-sweep
// in shared memory), 1024 elements per workgroup. pc.arg = level k (0, 1, 2): level 0 scans the flags
// into scan[0..), level k > 0 scans the block sums at its own offset in place; each workgroup writes its
// block's total to the next level's region (level 2 runs one group: its total is the grand total).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 256) in;
#include "rsh_common.glsl"

shared uint partial[256];

uint offset_of(uint level) { return level == 0u ? 0u : level == 1u ? pc.off1 : level == 2u ? pc.off2 : pc.off3; }

uint load(uint level, uint j, uint n) {
    if (j >= n) return 0u;
    return level == 0u ? flags[j] : scan[offset_of(level) + j];
}

void main() {
    uint level = pc.arg;
    uint n = control[CTL_N + level];
    uint lid = gl_LocalInvocationID.x;
    uint base = gl_WorkGroupID.x * SCAN_BLOCK + 4u * lid;
    uint v0 = load(level, base, n), v1 = load(level, base + 1u, n), v2 = load(level, base + 2u, n),
         v3 = load(level, base + 3u, n);
    partial[lid] = v0 + v1 + v2 + v3;
    // Up-sweep: partial sums in a balanced tree.
    for (uint d = 1u; d < 256u; d <<= 1u) {
        barrier();
        uint i = (lid + 1u) * 2u * d - 1u;
        if (i < 256u) partial[i] += partial[i - d];
    }
    barrier();
    if (lid == 0u) {
        scan[offset_of(level + 1u) + gl_WorkGroupID.x] = partial[255];
        partial[255] = 0u;
    }
    // Down-sweep: exclusive prefixes.
    for (uint d = 128u; d >= 1u; d >>= 1u) {
        barrier();
        uint i = (lid + 1u) * 2u * d - 1u;
        if (i < 256u) {
            uint t = partial[i - d];
            partial[i - d] = partial[i];
            partial[i] += t;
        }
    }
    barrier();
    uint e = partial[lid];
    uint out_base = offset_of(level) + base;
    if (base < n) scan[out_base] = e;
    if (base + 1u < n) scan[out_base + 1u] = e + v0;
    if (base + 2u < n) scan[out_base + 2u] = e + v0 + v1;
    if (base + 3u < n) scan[out_base + 3u] = e + v0 + v1 + v2;
}
