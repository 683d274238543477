#version 450
// rsh_plan.comp (one invocation): sizes the passes of the next step from what the previous one produced,
// as indirect dispatch arguments, so the host never waits for a count. pc.arg: the level about to be
// traversed or, with bit 16 set, the final intersection, or, with bit 18 set, a prefix sum over a caller's
// flags (RshEngine::record_prefix_sum: pc.count elements per unit of control[CTL_RAYS], at most
// pc.capacity), or, with bit 19 set, the build of a hierarchy of pc.count levels. Unless pc.arg has bit
// 17 set (the first level: the root pass set the count), the count is
// the last compaction's total, clamped to the capacity; a total above it marks the batch overflowed (the
// scatter wrote only the first `capacity` pairs), and an overflowed batch runs no final pass. Adds the
// cone-sphere tests, the leaf pairs and the overflows to the accumulators, and estimates the largest
// stream an overflowed batch would have needed (for the host's next batch size), both per trace of the
// recording (pc.count: its index).
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

void add64(uint at, uint v) { // one invocation: no atomics needed
    uint lo = control[at];
    uint sum = lo + v;
    control[at] = sum;
    if (sum < lo) control[at + 1u] += 1u;
}

// The sizes of the three scan levels over n0 elements and of the passes that read them.
void plan_scan(uint n0) {
    uint n1 = groups(n0, SCAN_BLOCK), n2 = groups(n1, SCAN_BLOCK);
    control[CTL_N] = n0;
    control[CTL_N + 1u] = n1;
    control[CTL_N + 2u] = n2;
    // Every scan level runs at least one group, so each writes its block total (0 for no elements).
    args(ARG_SCAN0, max(n1, 1u));
    args(ARG_SCAN1, max(n2, 1u));
    args(ARG_SCAN2, 1u);
    args(ARG_ADD1, groups(n1, 256u));
    args(ARG_ADD0, groups(n0, 256u));
    args(ARG_SCATTER, groups(n0, 256u));
}

void main() {
    if ((pc.arg & 0x80000u) != 0u) {
        // The build of a hierarchy of pc.count levels over control[CTL_RAYS] ray slots: level l writes the
        // nodes that cover a slot, rounded up to whole groups of 4 siblings (so every child of a node that
        // covers a slot is written, empty or not), level 0 its root; no slot: nothing (the root pass then
        // starts no stream).
        uint levels = pc.count, slots = control[CTL_RAYS];
        for (uint l = 0u; l <= levels; ++l) {
            uint span = 1u << (2u * (levels - l)); // slots under a node of level l
            uint covering = (slots + span - 1u) / span;
            uint nodes = l == 0u ? min(covering, 1u) : (covering + 3u) / 4u * 4u;
            uint a = CTL_BUILD_ARGS + 3u * l;
            control[a] = groups(nodes, 64u);
            control[a + 1u] = 1u;
            control[a + 2u] = 1u;
        }
        return;
    }
    if ((pc.arg & 0x40000u) != 0u) {
        plan_scan(min(pc.count * control[CTL_RAYS], pc.capacity));
        return;
    }
    uint count = control[CTL_COUNT];
    if ((pc.arg & 0x20000u) == 0u) {
        uint total = scan[pc.off3];
        // A level after a cut one was computed from the capacity's pairs instead of all: scale it back.
        float scale = uintBitsToFloat(control[CTL_SCALE]);
        float wanted = float(total) * scale;
        if (wanted > float(pc.capacity))
            control[ACC_TRACES + 2u * pc.count + 1u] = max(control[ACC_TRACES + 2u * pc.count + 1u], uint(min(wanted, 4.0e9)));
        if (total > pc.capacity) {
            control[CTL_OVERFLOW] = 1u;
            control[CTL_SCALE] = floatBitsToUint(scale * float(total) / float(pc.capacity));
        }
        count = min(total, pc.capacity);
        control[CTL_COUNT] = count;
    }
    if ((pc.arg & 0x10000u) != 0u) {
        bool ok = control[CTL_OVERFLOW] == 0u;
        control[CTL_LEAF_PAIRS] = ok ? count : 0u;
        if (ok) add64(ACC_LEAF_PAIRS, count);
        else control[ACC_TRACES + 2u * pc.count] += 1u;
        args(ARG_FINAL, ok ? groups(count, 64u) : 0u);
        return;
    }
    uint n0 = 4u * count;
    add64(ACC_TESTS, n0);
    args(ARG_TRAVERSE, groups(count, 64u));
    plan_scan(n0);
}
