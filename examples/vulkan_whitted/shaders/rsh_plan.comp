#version 450
// rsh_plan.comp (one invocation): sizes the passes of the next step from what the previous one produced,
// as indirect dispatch arguments, so the host never waits for a count. pc.arg: the level about to be
// traversed (its tests are counted there) or, with bit 16 set, the final intersection. Unless pc.arg has
// bit 17 set (the first level: the root pass set the count), the count is the last compaction's total,
// clamped to the capacity; a total above it marks the batch overflowed (the scatter wrote only the
// first `capacity` pairs), and an overflowed batch runs no final pass.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 1) in;
#include "rsh_common.glsl"

void args(uint slot, uint groups) {
    uint a = CTL_ARGS + 3u * slot;
    control[a] = groups;
    control[a + 1u] = 1u;
    control[a + 2u] = 1u;
}

uint groups(uint n, uint size) { return (n + size - 1u) / size; }

void main() {
    uint count = control[CTL_COUNT];
    if ((pc.arg & 0x20000u) == 0u) {
        uint total = scan[pc.off3];
        if (total > pc.capacity) control[CTL_OVERFLOW] = 1u;
        count = min(total, pc.capacity);
        control[CTL_COUNT] = count;
    }
    if ((pc.arg & 0x10000u) != 0u) {
        bool ok = control[CTL_OVERFLOW] == 0u;
        control[CTL_LEAF_PAIRS] = ok ? count : 0u;
        args(ARG_FINAL, ok ? groups(count, 64u) : 0u);
        return;
    }
    uint level = pc.arg & 0xFFFFu;
    uint n0 = 4u * count;
    uint n1 = groups(n0, SCAN_BLOCK), n2 = groups(n1, SCAN_BLOCK);
    control[CTL_N] = n0;
    control[CTL_N + 1u] = n1;
    control[CTL_N + 2u] = n2;
    if (level < 32u) control[CTL_TESTS + level] = n0;
    args(ARG_TRAVERSE, groups(count, 64u));
    // Every scan level runs at least one group, so each writes its block total (0 for no elements).
    args(ARG_SCAN0, max(n1, 1u));
    args(ARG_SCAN1, max(n2, 1u));
    args(ARG_SCAN2, 1u);
    args(ARG_ADD1, groups(n1, 256u));
    args(ARG_ADD0, groups(n0, 256u));
    args(ARG_SCATTER, groups(n0, 256u));
}
