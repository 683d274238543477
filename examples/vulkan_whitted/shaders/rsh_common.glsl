// rsh_common.glsl: what the ray-space hierarchy's passes (rsh_*.comp, driven by rsh_engine.cpp) share: one
// descriptor layout for all of them, the push constants, and the control buffer's slots. Layouts of
// nodes, pairs, rays and primitives come from raycache/shared/rsh_layout.h, as in the C++ reference.
#ifndef RSH_COMMON_GLSL
#define RSH_COMMON_GLSL

#include "raycache/shared/rsh_layout.h"

// Control words (uints), written and read on the device only; the host zeroes them before a recording
// (RshEngine::begin) and reads the accumulators after its submission (RshEngine::end).
const uint CTL_COUNT = 0u;       // pairs in the current stream
const uint CTL_OVERFLOW = 1u;    // 1 when a level of this batch produced more pairs than the capacity
const uint CTL_LEAF_PAIRS = 2u;  // pairs that reached the leaves (the final pass's count)
const uint CTL_RAYS = 3u;        // ray slots of the current trace (copied from where the caller keeps it)
const uint CTL_N = 4u;           // 4..6: elements of scan levels 0, 1, 2
const uint CTL_SCALE = 7u;       // float bits: how much the batch's streams were cut so far (1: not cut)
const uint CTL_ARGS = 8u;        // indirect dispatch arguments, 3 uints each, from here:
const uint ARG_TRAVERSE = 0u, ARG_SCAN0 = 1u, ARG_SCAN1 = 2u, ARG_SCAN2 = 3u, ARG_ADD1 = 4u, ARG_ADD0 = 5u,
           ARG_SCATTER = 6u, ARG_FINAL = 7u;
// Accumulators over every trace and batch since RshEngine::begin (64-bit ones as low, high words).
const uint ACC_TESTS = 32u;      // 32, 33: cone-sphere tests (4 per pair and level)
const uint ACC_LEAF_PAIRS = 34u; // 34, 35: pairs intersected at the leaves (batches that did not overflow)
// Per trace k of the recording (k < 64, pc.count of the plan pass), from ACC_TRACES + 2 k: batches that
// overflowed (their hits are incomplete: record again), and the largest stream a level of an overflowed
// batch would have had, estimated: its total times the factors by which earlier levels were cut.
const uint ACC_TRACES = 128u;
const uint ACC_TRACE_COUNT = 64u;
const uint ACC_LIVE = 38u;       // rays that entered a hierarchy (tmax > 0)
const uint ACC_SLOTS = 39u;      // ray slots traced (empty ones included)
const uint CTL_BUILD_ARGS = 64u; // 64 + 3 l: dispatch arguments of the build of level l (13 levels at most)
const uint CTL_WORDS = 256u;

const uint SCAN_BLOCK = 1024u;   // elements per scan workgroup (256 invocations, 4 each)

layout(std430, binding = 0) buffer Control { uint control[]; };
layout(std430, binding = 1) readonly buffer Rays { raycache_rsh_ray rays[]; };
layout(std430, binding = 2) readonly buffer Primitives { raycache_rsh_primitive primitives[]; };
layout(std430, binding = 3) buffer Spheres { vec4 spheres[]; };
layout(std430, binding = 4) buffer Nodes { raycache_rsh_node nodes[]; };
layout(std430, binding = 5) buffer PairsIn { raycache_rsh_pair pairs_in[]; };
layout(std430, binding = 6) buffer PairsOut { raycache_rsh_pair pairs_out[]; };
layout(std430, binding = 7) buffer Flags { uint flags[]; };
layout(std430, binding = 8) buffer Scan { uint scan[]; };
// binding 9: the hits (64-bit words), declared by rsh_final.comp alone (it needs 64-bit atomics).

layout(push_constant) uniform Push {
    uint capacity;     // pairs a stream may hold
    uint off1;         // scan buffer: level 1 (block sums of level 0) starts here (level 0 at 0)
    uint off2;         // level 2
    uint off3;         // level 3: one word, the grand total
    uint parent_first; // first node of the parent level (traversal), of the level being built (build)
    uint child_first;  // first node of the child level
    uint count;        // nodes of the level (build), primitives (spheres, root), elements a count stands for (plan)
    uint arg;          // first primitive of the batch (root), level (plan, scan), ...
} pc;

#endif
