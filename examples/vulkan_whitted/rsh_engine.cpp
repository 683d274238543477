// The ray-space hierarchy engine; see rsh_engine.hpp.
#include "rsh_engine.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <utility>
#include <vector>

#include <raycache/shared/rsh_layout.h>

#include "rcx/rsh_reference.hpp" // for_batches

namespace rcx::gpu {

namespace {

// The push constants of every rsh_*.comp (shaders/rsh_common.glsl).
struct Push {
    std::uint32_t capacity = 0, off1 = 0, off2 = 0, off3 = 0;
    std::uint32_t parent_first = 0, child_first = 0, count = 0, arg = 0;
};
static_assert(sizeof(Push) == 32, "rsh push constants");

// Control words and argument slots (shaders/rsh_common.glsl).
constexpr std::uint32_t ctl_overflow = 1, ctl_leaf_pairs = 2, ctl_args = 8, ctl_tests = 32, ctl_words = 64;
enum Arg : std::uint32_t { arg_traverse, arg_scan0, arg_scan1, arg_scan2, arg_add1, arg_add0, arg_scatter, arg_final };
constexpr std::uint32_t plan_final = 0x10000u, plan_first = 0x20000u;
constexpr std::uint32_t scan_block = 1024;

enum Phase { phase_build, phase_traverse, phase_compaction, phase_final, phase_count };

double ms_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

struct RshEngine::Impl {
    vk::Context& context;
    RshSettings settings;
    std::unique_ptr<vk::ComputePipeline> prepare, build, root, plan, traverse, scan, scan_add, scatter, final_pass;
    std::unique_ptr<vk::Buffer> control, spheres, nodes, pairs[2], flags, scan_words;
    std::uint32_t off1 = 0, off2 = 0, off3 = 0;
    std::uint32_t batch = 0;
    VkQueryPool queries = VK_NULL_HANDLE;
    static constexpr std::uint32_t query_count = 512;
    double tick_ns = 0.0;

    // Timestamps of one submission: the interval before each mark belongs to the mark's phase.
    std::vector<int> marks;
    void mark(vk::Commands& c, int phase) {
        if (!queries || marks.size() >= query_count) return;
        vkCmdWriteTimestamp(c.handle(), VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queries, static_cast<std::uint32_t>(marks.size()));
        marks.push_back(phase);
    }
    void begin_marks(vk::Commands& c) {
        marks.clear();
        if (!queries) return;
        vkCmdResetQueryPool(c.handle(), queries, 0, query_count);
        mark(c, -1);
    }
    void collect(RshStats& s) {
        if (!queries || marks.size() < 2) return;
        std::vector<std::uint64_t> t(marks.size());
        if (vkGetQueryPoolResults(context.device(), queries, 0, static_cast<std::uint32_t>(marks.size()),
                                  t.size() * sizeof(std::uint64_t), t.data(), sizeof(std::uint64_t),
                                  VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) != VK_SUCCESS)
            return;
        double* ms[phase_count] = {&s.build_ms, &s.traverse_ms, &s.compaction_ms, &s.final_ms};
        for (std::size_t i = 1; i < marks.size(); ++i)
            if (marks[i] >= 0 && t[i] >= t[i - 1]) *ms[marks[i]] += static_cast<double>(t[i] - t[i - 1]) * tick_ns * 1e-6;
        s.timed = true;
    }

    Impl(vk::Context& c, const RshSettings& s) : context(c), settings(s) {}
    ~Impl() {
        if (queries) vkDestroyQueryPool(context.device(), queries, nullptr);
    }
};

RshEngine::RshEngine(vk::Context& context, const std::string& spirv_dir, const RshSettings& settings)
    : impl_(std::make_unique<Impl>(context, settings)) {
    Impl& e = *impl_;
    if (!context.int64_atomics())
        throw std::invalid_argument("ray-space hierarchy: the device needs shaderInt64 and shaderBufferInt64Atomics");
    if (settings.pair_capacity < 64 || settings.pair_capacity > (1u << 24))
        throw std::invalid_argument("ray-space hierarchy: the pair capacity must be 64 .. 2^24");
    const std::vector<VkDescriptorType> bindings(10, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    auto load = [&](const char* name) {
        return std::make_unique<vk::ComputePipeline>(context, spirv_dir + "/" + name + ".spv", bindings, sizeof(Push));
    };
    e.prepare = load("rsh_prepare");
    e.build = load("rsh_build");
    e.root = load("rsh_root");
    e.plan = load("rsh_plan");
    e.traverse = load("rsh_traverse");
    e.scan = load("rsh_scan");
    e.scan_add = load("rsh_scan_add");
    e.scatter = load("rsh_scatter");
    e.final_pass = load("rsh_final");

    const std::uint64_t c = settings.pair_capacity;
    const std::uint64_t n0 = 4 * c, g0 = (n0 + scan_block - 1) / scan_block, g1 = (g0 + scan_block - 1) / scan_block;
    e.off1 = static_cast<std::uint32_t>(n0);
    e.off2 = static_cast<std::uint32_t>(n0 + g0);
    e.off3 = static_cast<std::uint32_t>(n0 + g0 + g1);
    e.control = std::make_unique<vk::Buffer>(context, ctl_words * 4);
    e.control->fill(0u);
    e.pairs[0] = std::make_unique<vk::Buffer>(context, c * 8);
    e.pairs[1] = std::make_unique<vk::Buffer>(context, c * 8);
    e.flags = std::make_unique<vk::Buffer>(context, n0 * 4);
    e.scan_words = std::make_unique<vk::Buffer>(context, (static_cast<std::uint64_t>(e.off3) + 4) * 4);
    e.batch = settings.pair_capacity;

    if (settings.timestamps && context.properties().limits.timestampComputeAndGraphics) {
        std::uint32_t families = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device(), &families, nullptr);
        std::vector<VkQueueFamilyProperties> props(families);
        vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device(), &families, props.data());
        if (context.queue_family() < families && props[context.queue_family()].timestampValidBits > 0) {
            VkQueryPoolCreateInfo info{};
            info.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO;
            info.queryType = VK_QUERY_TYPE_TIMESTAMP;
            info.queryCount = Impl::query_count;
            if (vkCreateQueryPool(context.device(), &info, nullptr, &e.queries) != VK_SUCCESS) e.queries = VK_NULL_HANDLE;
            e.tick_ns = context.properties().limits.timestampPeriod;
        }
    }
}

RshEngine::~RshEngine() = default;

std::uint32_t RshEngine::batch_size() const noexcept { return impl_->batch; }
std::uint32_t RshEngine::pair_capacity() const noexcept { return impl_->settings.pair_capacity; }

RshStats RshEngine::trace(const vk::Buffer& rays, std::uint32_t ray_count, const vk::Buffer& primitives,
                          std::uint32_t primitive_count, const vk::Buffer& hits) {
    using namespace raycache::shared;
    Impl& e = *impl_;
    const auto start = std::chrono::steady_clock::now();
    if (rays.size() < std::uint64_t{ray_count} * sizeof(raycache_rsh_ray) ||
        primitives.size() < std::uint64_t{primitive_count} * sizeof(raycache_rsh_primitive) ||
        hits.size() < std::uint64_t{ray_count} * sizeof(raycache_rsh_hit))
        throw std::invalid_argument("ray-space hierarchy: a buffer is smaller than its count says");
    RshStats stats;
    stats.rays = ray_count;
    int levels = 0;
    while ((std::uint64_t{1} << (2 * levels)) < ray_count) ++levels;
    if (levels > 12) throw std::invalid_argument("ray-space hierarchy: more than 4^12 rays");
    stats.levels = static_cast<std::uint32_t>(levels);
    const std::uint32_t leaves = 1u << (2 * levels);
    const std::uint32_t leaf_first = raycache_rsh_level_first(levels);
    const std::uint64_t node_bytes = std::uint64_t{raycache_rsh_level_first(levels + 1)} * sizeof(raycache_rsh_node);
    if (!e.nodes || e.nodes->size() < node_bytes) e.nodes = std::make_unique<vk::Buffer>(e.context, node_bytes);
    const std::uint64_t sphere_bytes = std::max<std::uint64_t>(std::uint64_t{primitive_count} * 16, 16);
    if (!e.spheres || e.spheres->size() < sphere_bytes) e.spheres = std::make_unique<vk::Buffer>(e.context, sphere_bytes);

    Push base;
    base.capacity = e.settings.pair_capacity;
    base.off1 = e.off1, base.off2 = e.off2, base.off3 = e.off3;
    // Every pass binds the same ten buffers; `in` picks which pair buffer is this level's input.
    auto direct = [&](vk::Commands& c, const vk::ComputePipeline& pipe, int in, const Push& p, std::uint32_t groups) {
        c.dispatch(pipe, {*e.control, rays, primitives, *e.spheres, *e.nodes, *e.pairs[in], *e.pairs[1 - in], *e.flags,
                          *e.scan_words, hits}, &p, sizeof p, groups);
    };
    auto indirect = [&](vk::Commands& c, const vk::ComputePipeline& pipe, int in, const Push& p, std::uint32_t slot) {
        c.dispatch_indirect(pipe, {*e.control, rays, primitives, *e.spheres, *e.nodes, *e.pairs[in], *e.pairs[1 - in],
                                   *e.flags, *e.scan_words, hits}, &p, sizeof p, *e.control, 4 * (ctl_args + 3 * slot));
    };

    // 1-2. Bounding spheres, leaves, levels bottom-up; hits emptied.
    e.context.submit([&](vk::Commands& c) {
        e.begin_marks(c);
        c.fill(hits, RAYCACHE_RSH_NO_HIT);
        Push p = base;
        p.count = primitive_count, p.arg = 0;
        if (primitive_count > 0) direct(c, *e.prepare, 0, p, vk::group_count(primitive_count, 64));
        p.count = ray_count, p.arg = 1, p.parent_first = leaves, p.child_first = leaf_first;
        direct(c, *e.prepare, 0, p, vk::group_count(leaves, 64));
        c.barrier();
        for (int l = levels - 1; l >= 0; --l) {
            p = base;
            p.parent_first = raycache_rsh_level_first(l), p.child_first = raycache_rsh_level_first(l + 1);
            p.count = 1u << (2 * l);
            direct(c, *e.build, 0, p, vk::group_count(p.count, 64));
            c.barrier();
        }
        e.mark(c, phase_build);
    });
    e.collect(stats);

    // 3-4. Batches of primitives; one submission each.
    auto run_batch = [&](std::uint32_t first, std::uint32_t count) {
        int in = 0;
        e.context.submit([&](vk::Commands& c) {
            e.begin_marks(c);
            Push p = base;
            p.count = count, p.arg = first;
            direct(c, *e.root, in, p, vk::group_count(count, 64));
            c.barrier();
            e.mark(c, phase_compaction);
            for (int l = 0; l < levels; ++l) {
                p = base;
                p.parent_first = raycache_rsh_level_first(l), p.child_first = raycache_rsh_level_first(l + 1);
                p.arg = static_cast<std::uint32_t>(l) | (l == 0 ? plan_first : 0u);
                direct(c, *e.plan, in, p, 1);
                c.barrier();
                e.mark(c, phase_compaction);
                indirect(c, *e.traverse, in, p, (arg_traverse));
                c.barrier();
                e.mark(c, phase_traverse);
                for (std::uint32_t k = 0; k < 3; ++k) {
                    p.arg = k;
                    indirect(c, *e.scan, in, p, ((arg_scan0 + k)));
                    c.barrier();
                }
                for (std::uint32_t k : {1u, 0u}) {
                    p.arg = k;
                    indirect(c, *e.scan_add, in, p, ((k == 1 ? arg_add1 : arg_add0)));
                    c.barrier();
                }
                indirect(c, *e.scatter, in, p, (arg_scatter));
                c.barrier();
                e.mark(c, phase_compaction);
                in = 1 - in;
            }
            p = base;
            p.arg = plan_final | (levels == 0 ? plan_first : 0u);
            direct(c, *e.plan, in, p, 1);
            c.barrier();
            e.mark(c, phase_compaction);
            p.child_first = leaf_first, p.count = ray_count;
            indirect(c, *e.final_pass, in, p, (arg_final));
            c.barrier();
            e.mark(c, phase_final);
        });
        e.collect(stats);
        const std::uint32_t* ctl = e.control->as<std::uint32_t>();
        for (int l = 0; l < levels && l < 32; ++l) stats.cone_sphere_tests += ctl[ctl_tests + l];
        if (ctl[ctl_overflow] != 0u) return false;
        stats.leaf_pairs += ctl[ctl_leaf_pairs];
        return true;
    };

    std::size_t batch = e.batch; // lowered by an overflow, for this call and the next (paper 3.4)
    try {
        rsh::for_batches(primitive_count, batch, [&](std::size_t first, std::size_t count) {
            return run_batch(static_cast<std::uint32_t>(first), static_cast<std::uint32_t>(count));
        }, stats.batches, stats.overflows);
    } catch (const std::length_error&) {
        throw std::runtime_error("ray-space hierarchy: one primitive meets more leaves than the pair capacity (" +
                                 std::to_string(e.settings.pair_capacity) + "); raise it");
    }
    e.batch = static_cast<std::uint32_t>(batch);
    stats.wall_ms = ms_since(start);
    return stats;
}

} // namespace rcx::gpu
