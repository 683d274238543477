// rsh_engine.hpp: the ray-space hierarchy of Roger, Assarsson and Holzschuch (EGSR 2007) as a Vulkan
// compute engine: give it a buffer of rays (raycache_rsh_ray) and one of primitives
// (raycache_rsh_primitive: triangles and spheres, anywhere, moved every frame: nothing about them is
// kept between calls) and it writes each ray's closest hit (raycache_rsh_hit). Per trace:
//   1. prepare: bounding spheres of the primitives, one leaf per ray (shaders/rsh_prepare.comp);
//   2. build: the hierarchy bottom-up, 4 consecutive rays / nodes per parent (rsh_build.comp);
//   3. per batch of primitives: the stream of (root, primitive) pairs (rsh_root.comp), then per level the
//      cone-sphere tests against the four children (rsh_traverse.comp) and the stream reduction: a
//      work-efficient prefix sum over the kept flags (rsh_scan.comp, rsh_scan_add.comp) and the scatter
//      (rsh_scatter.comp), sized by a one-invocation plan pass (rsh_plan.comp) through indirect dispatch,
//      so the levels run in one submission without the host reading a count;
//   4. at the leaves, each ray against its remaining primitives, the closest kept (rsh_final.comp).
// Traces can be recorded into a caller's submission (begin, record_trace, end), their ray counts read on
// the device from where an earlier pass wrote them, so that a whole frame of traces runs with no trip to
// the host; the same prefix sum compacts a caller's streams (record_prefix_sum). trace() is one such
// recording of one trace, with a count the host knows.
// The pair streams have a fixed capacity; a level that would exceed it is cut at the capacity (no write
// past a buffer) and marks the batch overflowed, which the accumulators count; end() then lowers the batch
// size of that trace (section 3.4: the primitives are split into more, smaller batches; traces are told
// apart by their order in the recording, as a frame records the same sequence every time), for the
// caller to record the work again (trace() does) and for every later recording. Layouts and the geometry are
// raycache/shared/rsh_layout.h, shared with the C++ reference rcx/rsh_reference.hpp.
// Needs 64-bit buffer atomics (shaderBufferInt64Atomics; lavapipe has them).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <rcx/vulkan.hpp>

namespace rcx::gpu {

struct RshSettings {
    std::uint32_t pair_capacity = 1u << 21; // pairs a stream holds (two streams, plus 4 flags and 4 prefix
                                            // sums a pair: about 48 bytes a pair in all); 64 .. 1 << 24
    bool timestamps = true;                 // time the phases with GPU timestamps (when the queue has them)
};

struct RshStats {
    std::uint32_t rays = 0;                 // slots traced (empty ones included)
    std::uint32_t levels = 0;               // of the hierarchy below the root
    std::uint32_t batches = 0;              // batches of primitives that completed (in the recording that counted)
    std::uint32_t overflows = 0;            // batches that overflowed (their recording was done again, smaller)
    std::uint64_t live_rays = 0;            // rays that entered a hierarchy (slots with tmax > 0)
    std::uint64_t cone_sphere_tests = 0;    // all levels and batches, overflowed ones included
    std::uint64_t leaf_pairs = 0;           // (ray, primitive) pairs intersected at the leaves
    // GPU time of each phase (timestamps; 0 when the device has none), milliseconds.
    double build_ms = 0.0;                  // bounding spheres, leaves, levels
    double traverse_ms = 0.0;               // cone-sphere tests
    double compaction_ms = 0.0;             // plan, prefix sum, scatter, root streams
    double final_ms = 0.0;                  // final intersection
    double wall_ms = 0.0;                   // trace(): the whole call on the host, submissions and waits included
    bool timed = false;                     // whether the phase times are measured
};

class RshEngine {
public:
    // Loads shaders/rsh_*.spv from spirv_dir (rcx::vk::Error naming a missing file). Throws
    // std::invalid_argument when the context has no 64-bit atomics or the capacity is out of range.
    RshEngine(vk::Context& context, const std::string& spirv_dir, const RshSettings& settings = {});
    ~RshEngine();
    RshEngine(const RshEngine&) = delete;
    RshEngine& operator=(const RshEngine&) = delete;

    // Traces rays[0 .. ray_count) (slots with tmax <= 0 are empty) against primitives[0 .. primitive_count)
    // and writes hits[0 .. ray_count). The rays should be ordered so that neighbours are coherent (Morton
    // order over the screen makes each 4 consecutive rays a 2x2 block, as in the paper). Buffers must hold
    // what the counts say (std::invalid_argument otherwise). One submission; again with smaller batches
    // while a batch overflows.
    RshStats trace(const vk::Buffer& rays, std::uint32_t ray_count, const vk::Buffer& primitives,
                   std::uint32_t primitive_count, const vk::Buffer& hits);

    // Recording traces into the caller's submission. begin() zeroes the device counters and starts the
    // timestamps; then any number of record_trace() and record_prefix_sum(); after the submission has
    // completed, end() reads the counters (the only read-back) and, when a batch overflowed, lowers the
    // batch size: the hits of that recording are then incomplete, and the caller records it again.
    // Buffers that the recording uses are kept alive until end().
    void begin(vk::Commands& commands);
    // A trace whose ray count is on the device: the uint32 at word `count_word` of `counts`, written by an
    // earlier pass of this submission, at most ray_capacity (rays and hits must hold ray_capacity). The
    // hierarchy has the levels of ray_capacity; the passes run as many groups as the count needs. The
    // primitives are cut into batches of this trace's batch size (by its order in the recording), and
    // must not change during the recording (their bounding spheres are computed once).
    void record_trace(vk::Commands& commands, const vk::Buffer& rays, std::uint32_t ray_capacity, const vk::Buffer& counts,
                      std::uint32_t count_word, const vk::Buffer& primitives, std::uint32_t primitive_count,
                      const vk::Buffer& hits);
    // The engine's work-efficient exclusive prefix sum over a caller's flags (uint 0 or 1): n = scale *
    // (uint32 at word `count_word` of `counts`) elements, at most max_elements (< 2^30), are summed into
    // sums[0 .. n) and the total into sums[prefix_sum_total_word(max_elements)]; `sums` must hold
    // prefix_sum_bytes(max_elements). Its passes are sized on the device (indirect dispatch).
    void record_prefix_sum(vk::Commands& commands, const vk::Buffer& flags, const vk::Buffer& counts, std::uint32_t count_word,
                           std::uint32_t scale, std::uint32_t max_elements, const vk::Buffer& sums);
    static std::uint64_t prefix_sum_bytes(std::uint32_t max_elements) noexcept;
    static std::uint32_t prefix_sum_total_word(std::uint32_t max_elements) noexcept;
    // After the submission: what the traces recorded since begin() did (wall_ms 0). Throws
    // std::runtime_error when a batch of one primitive overflowed (the capacity is too small for it).
    RshStats end();

    // The smallest batch size a trace of the next recording starts with (the capacity until a batch
    // overflows; then at most half of what overflowed).
    std::uint32_t batch_size() const noexcept;
    std::uint32_t pair_capacity() const noexcept;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

} // namespace rcx::gpu
