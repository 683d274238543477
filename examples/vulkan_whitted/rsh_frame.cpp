// One Whitted frame through the ray-space hierarchy; see rsh_frame.hpp.
#include "rsh_frame.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include <raycache/shared/rsh_layout.h>

namespace rcx::gpu {

namespace {

// shaders/rsh_whitted.comp's RayState, Candidate, push constants and frame control words.
struct RayState {
    float weight[4];
    std::uint32_t pixel;
    std::int32_t depth;
    std::uint32_t pad[2];
};
struct Candidate {
    raycache::shared::raycache_rsh_ray ray;
    RayState state;
};
static_assert(sizeof(RayState) == 32 && sizeof(Candidate) == 64, "rsh_whitted.comp layouts");

struct Push {
    std::uint32_t mode, generation, side, hybrid, capacity, total_word;
};
enum Mode : std::uint32_t { mode_generate, mode_shade, mode_gather, mode_flag, mode_plan, mode_scatter };
constexpr std::uint32_t fc_counts = 0, fc_overflow = 32, fc_shadow = 33, fc_args = 64, fc_words = 64 + 6 * 32;
constexpr int max_generations = 31;

void grow(vk::Context& context, std::unique_ptr<vk::Buffer>& buffer, std::uint64_t bytes) {
    if (!buffer || buffer->size() < bytes) buffer = std::make_unique<vk::Buffer>(context, std::max<std::uint64_t>(bytes, 64));
}

std::uint32_t groups(std::uint64_t n) { return static_cast<std::uint32_t>((n + 63) / 64); }

// The side of the square of Morton slots a width x height image's rays lie in: the next power of two of
// the larger side.
std::uint32_t square_side(int width, int height) {
    std::uint32_t side = 1;
    while (side < static_cast<std::uint32_t>(std::max(width, height))) side *= 2;
    return side;
}

// Bytes a ray slot takes in the candidates buffer, the largest: three candidate pairs of 64 bytes.
constexpr std::uint64_t candidate_bytes = 3 * 64;

} // namespace

struct RshFrame::Impl {
    Impl(vk::Context& c, const std::string& spirv_dir, const RshSettings& s)
        : context(c), engine(c, spirv_dir, s),
          whitted(c, spirv_dir + "/rsh_whitted.spv", std::vector<VkDescriptorType>(16, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
                  sizeof(Push)) {}
    vk::Context& context;
    RshEngine engine;
    vk::ComputePipeline whitted;
    std::unique_ptr<vk::Buffer> rays, hits, states, shadow_rays, shadow_hits, local, candidates, flags, sums, control, dummy;
    std::uint32_t ray_capacity = 0; // kept between frames: raised when a generation outgrew it
    int generations_hint = 0;       // generations the last frame had rays in (0: record all)
};

RshFrame::RshFrame(vk::Context& context, const std::string& spirv_dir, const RshSettings& settings)
    : impl_(std::make_unique<Impl>(context, spirv_dir, settings)) {}
RshFrame::~RshFrame() = default;
const RshEngine& RshFrame::engine() const noexcept { return impl_->engine; }

void RshFrame::check_image_size(int width, int height, std::uint64_t max_buffer_bytes, std::uint32_t max_groups) {
    const std::uint64_t side = square_side(width, height), slots = side * side, bytes = slots * candidate_bytes;
    if (bytes <= max_buffer_bytes && groups(3 * slots) <= max_groups) return;
    std::uint64_t fits = side;
    while (fits > 1 && (fits * fits * candidate_bytes > max_buffer_bytes || groups(3 * fits * fits) > max_groups)) fits /= 2;
    throw std::invalid_argument("--size " + std::to_string(width) + "x" + std::to_string(height) + ": the Vulkan tracer's --secondary rsh lays the rays out in a " +
                                std::to_string(side) + " x " + std::to_string(side) + " square, whose " + std::to_string(bytes) +
                                "-byte buffer or " + std::to_string(groups(3 * slots)) + " groups pass this device's limits (" +
                                std::to_string(max_buffer_bytes) + " bytes, " + std::to_string(max_groups) +
                                " groups); image sides up to " + std::to_string(fits) + " fit");
}

void RshFrame::render(int width, int height, int max_depth, const RshSceneBuffers& scene, const vk::Buffer& image,
                      RshFrameStats* stats) {
    Impl& f = *impl_;
    if (max_depth < 0 || max_depth + 1 > max_generations)
        throw std::invalid_argument("ray-space hierarchy frame: the depth limit must be 0.." + std::to_string(max_generations - 1));
    if (!scene.gbuffer && (!scene.bvh_nodes || !scene.bvh_prims))
        throw std::invalid_argument("ray-space hierarchy frame: without a G-buffer the primary rays need the BVH");
    RshFrameStats local_stats;
    RshFrameStats& s = stats ? *stats : local_stats;
    s = RshFrameStats{};
    const auto start = std::chrono::steady_clock::now();
    const std::uint32_t side = square_side(width, height);
    const std::uint32_t slots = side * side;
    grow(f.context, f.dummy, 64);
    grow(f.context, f.control, std::uint64_t{fc_words} * 4);
    const vk::Buffer& gbuffer = scene.gbuffer ? *scene.gbuffer : *f.dummy;
    const std::uint32_t hybrid = scene.gbuffer ? 1u : 0u;

    for (;;) { // once, or again with more room for rays, smaller batches or all generations
        // Generation 0 holds the Morton slots; later ones as many rays as the capacity (grown by 4 after
        // a frame whose generation exceeded it, so that the hierarchy over it stays a full 4-ary tree).
        const std::uint32_t capacity = std::max(f.ray_capacity, slots);
        // Generations recorded: as many as the last frame had (all of them the first time); a frame whose
        // rays outlive them is recorded again with all.
        const int recorded = f.generations_hint > 0 ? std::min(f.generations_hint, max_depth + 1) : max_depth + 1;
        const std::uint64_t n = capacity;
        grow(f.context, f.rays, n * 32);
        grow(f.context, f.hits, n * 8);
        grow(f.context, f.states, n * 32);
        grow(f.context, f.shadow_rays, n * 32);
        grow(f.context, f.shadow_hits, n * 8);
        grow(f.context, f.local, n * 32);
        grow(f.context, f.candidates, n * candidate_bytes);
        grow(f.context, f.flags, n * 3 * 4);
        grow(f.context, f.sums, RshEngine::prefix_sum_bytes(3 * capacity));
        const std::uint32_t total_word = RshEngine::prefix_sum_total_word(3 * capacity);

        // Before the submission (a write, not a read-back): generation 0's count and dispatch sizes.
        std::vector<std::uint32_t> control(fc_words, 0u);
        control[fc_counts] = slots;
        control[fc_args + 0] = groups(slots), control[fc_args + 1] = 1, control[fc_args + 2] = 1;
        control[fc_args + 3] = groups(std::uint64_t{3} * slots), control[fc_args + 4] = 1, control[fc_args + 5] = 1;
        f.control->upload(control.data(), control.size() * 4);

        f.context.submit([&](vk::Commands& c) {
            f.engine.begin(c);
            auto pass = [&](std::uint32_t mode, std::uint32_t generation, bool indirect, std::uint32_t slot) {
                const Push p{mode, generation, side, hybrid, capacity, total_word};
                // The primary rays read the BVH (bindings 5, 6: nodes, primitives in leaf order); the
                // shading the primitives in scene order.
                const bool bvh = mode == mode_generate && !hybrid;
                std::initializer_list<vk::Resource> resources = {
                    *f.rays, *f.hits, *f.states, *f.shadow_rays, *f.shadow_hits,
                    bvh ? *scene.bvh_nodes : *scene.prims, bvh ? *scene.bvh_prims : *scene.prims,
                    *scene.objects, *scene.params, *f.local, *f.candidates, image, gbuffer, *f.control, *f.flags, *f.sums};
                if (indirect) // the generation's sizes, as the plan pass (or, for generation 0, the host) wrote them
                    c.dispatch_indirect(f.whitted, resources, &p, sizeof p, *f.control,
                                        4 * (std::uint64_t{fc_args} + 6 * generation + slot));
                else
                    c.dispatch(f.whitted, resources, &p, sizeof p, mode == mode_plan ? 1 : groups(slots));
                c.barrier();
            };
            pass(mode_generate, 0, false, 0);
            for (int g = 0; g < recorded; ++g) {
                const std::uint32_t gen = static_cast<std::uint32_t>(g);
                if (g > 0)
                    f.engine.record_trace(c, *f.rays, capacity, *f.control, fc_counts + gen, *scene.rsh_prims, scene.prim_count,
                                          *f.hits);
                pass(mode_shade, gen, true, 0);
                f.engine.record_trace(c, *f.shadow_rays, capacity, *f.control, fc_counts + gen, *scene.rsh_prims,
                                      scene.prim_count, *f.shadow_hits);
                pass(mode_gather, gen, true, 0);
                if (g == max_depth) break;
                // The next generation: the candidates that hold a ray, in order, compacted on the device.
                pass(mode_flag, gen, true, 3);
                f.engine.record_prefix_sum(c, *f.flags, *f.control, fc_counts + gen, 3, 3 * capacity, *f.sums);
                pass(mode_plan, gen, false, 0);
                if (g + 1 < recorded) pass(mode_scatter, gen, true, 3); // the last one only counts what would follow
            }
        });
        ++s.submissions;
        const RshStats t = f.engine.end(); // lowers the batch size when a batch overflowed
        const std::uint32_t* words = f.control->as<std::uint32_t>();
        const bool rays_overflowed = words[fc_overflow] > 0;
        if (rays_overflowed) {
            ++s.ray_overflows;
            while (f.ray_capacity < words[fc_overflow]) f.ray_capacity = std::max(capacity, f.ray_capacity) * 4;
        }
        // Rays past the generations recorded: record them all.
        const bool truncated = recorded <= max_depth && words[fc_counts + static_cast<std::uint32_t>(recorded)] > 0;
        if (truncated) {
            ++s.truncations;
            f.generations_hint = max_depth + 1;
        }
        s.trace.overflows += t.overflows;
        s.trace.cone_sphere_tests += t.cone_sphere_tests;
        if (rays_overflowed || t.overflows > 0 || truncated) continue;

        const std::uint32_t overflows = s.trace.overflows;
        const std::uint64_t tests = s.trace.cone_sphere_tests;
        s.trace = t;
        s.trace.overflows = overflows, s.trace.cone_sphere_tests = tests;
        s.ray_capacity = capacity;
        s.shadow_rays = words[fc_shadow];
        s.generations = 1;
        for (int g = 1; g <= max_depth && words[fc_counts + static_cast<std::uint32_t>(g)] > 0; ++g) {
            s.secondary_rays += words[fc_counts + static_cast<std::uint32_t>(g)];
            s.generations = g + 1;
        }
        // The next frame records as many generations as this one had rays (and counts the one after, to
        // know that none was left out).
        f.generations_hint = s.generations;
        break;
    }
    s.trace.wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const double phases = s.trace.timed ? s.trace.build_ms + s.trace.traverse_ms + s.trace.compaction_ms + s.trace.final_ms : 0.0;
    s.shade_ms = std::max(0.0, s.trace.wall_ms - phases);
}

} // namespace rcx::gpu
