// One Whitted frame through the ray-space hierarchy; see rsh_frame.hpp.
#include "rsh_frame.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <vector>

#include <raycache/shared/rsh_layout.h>

namespace rcx::gpu {

namespace {

// shaders/rsh_whitted.comp's RayState and Candidate.
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
    std::uint32_t mode, count, side, hybrid;
};

void grow(vk::Context& context, std::unique_ptr<vk::Buffer>& buffer, std::uint64_t bytes) {
    if (!buffer || buffer->size() < bytes) buffer = std::make_unique<vk::Buffer>(context, std::max<std::uint64_t>(bytes, 64));
}

} // namespace

struct RshFrame::Impl {
    Impl(vk::Context& c, const std::string& spirv_dir, const RshSettings& s)
        : context(c), engine(c, spirv_dir, s),
          whitted(c, spirv_dir + "/rsh_whitted.spv", std::vector<VkDescriptorType>(13, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
                  sizeof(Push)) {}
    vk::Context& context;
    RshEngine engine;
    vk::ComputePipeline whitted;
    std::unique_ptr<vk::Buffer> rays, hits, states, shadow_rays, shadow_hits, local, candidates, dummy;
};

RshFrame::RshFrame(vk::Context& context, const std::string& spirv_dir, const RshSettings& settings)
    : impl_(std::make_unique<Impl>(context, spirv_dir, settings)) {}
RshFrame::~RshFrame() = default;
const RshEngine& RshFrame::engine() const noexcept { return impl_->engine; }

void RshFrame::render(int width, int height, int max_depth, const RshSceneBuffers& scene, const vk::Buffer& image,
                      RshFrameStats* stats) {
    Impl& f = *impl_;
    RshFrameStats local_stats;
    RshFrameStats& s = stats ? *stats : local_stats;
    s = RshFrameStats{};
    std::uint32_t side = 1;
    while (side < static_cast<std::uint32_t>(std::max(width, height))) side *= 2;
    std::uint32_t count = side * side;
    grow(f.context, f.dummy, 64);
    const vk::Buffer& gbuffer = scene.gbuffer ? *scene.gbuffer : *f.dummy;

    auto size_for = [&](std::uint32_t n) {
        grow(f.context, f.rays, std::uint64_t{n} * 32);
        grow(f.context, f.hits, std::uint64_t{n} * 8);
        grow(f.context, f.states, std::uint64_t{n} * 32);
        grow(f.context, f.shadow_rays, std::uint64_t{n} * 32);
        grow(f.context, f.shadow_hits, std::uint64_t{n} * 8);
        grow(f.context, f.local, std::uint64_t{n} * 32);
        grow(f.context, f.candidates, std::uint64_t{n} * 3 * 64);
    };
    auto pass = [&](std::uint32_t mode, std::uint32_t n) {
        const Push p{mode, n, side, scene.gbuffer ? 1u : 0u};
        f.context.submit([&](vk::Commands& c) {
            c.dispatch(f.whitted, {*f.rays, *f.hits, *f.states, *f.shadow_rays, *f.shadow_hits, *scene.prims, *scene.prims,
                                   *scene.objects, *scene.params, *f.local, *f.candidates, image, gbuffer},
                       &p, sizeof p, vk::group_count(n, 64));
        });
    };
    auto add = [&](const RshStats& t) {
        RshStats& a = s.trace;
        a.rays += t.rays, a.levels = std::max(a.levels, t.levels), a.batches += t.batches, a.overflows += t.overflows;
        a.cone_sphere_tests += t.cone_sphere_tests, a.leaf_pairs += t.leaf_pairs;
        a.build_ms += t.build_ms, a.traverse_ms += t.traverse_ms, a.compaction_ms += t.compaction_ms;
        a.final_ms += t.final_ms, a.wall_ms += t.wall_ms, a.timed = a.timed || t.timed;
    };

    size_for(count);
    auto start = std::chrono::steady_clock::now();
    pass(0, count);
    std::vector<Candidate> next;
    for (int generation = 0; count > 0; ++generation) {
        s.shade_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        if (generation > 0 || !scene.gbuffer) add(f.engine.trace(*f.rays, count, *scene.rsh_prims, scene.prim_count, *f.hits));
        start = std::chrono::steady_clock::now();
        pass(1, count);
        s.shade_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        const RshStats shadow = f.engine.trace(*f.shadow_rays, count, *scene.rsh_prims, scene.prim_count, *f.shadow_hits);
        add(shadow);
        start = std::chrono::steady_clock::now();
        const auto* sr = f.shadow_rays->as<raycache::shared::raycache_rsh_ray>();
        for (std::uint32_t i = 0; i < count; ++i) s.shadow_rays += sr[i].tmax > 0.0f ? 1 : 0;
        pass(2, count);
        s.generations = generation + 1;
        if (generation >= max_depth) break;
        // The next generation: the candidates that hold a ray, in order.
        const auto* cand = f.candidates->as<Candidate>();
        next.clear();
        for (std::uint64_t k = 0; k < std::uint64_t{count} * 3; ++k)
            if (cand[k].ray.tmax > 0.0f) next.push_back(cand[k]);
        count = static_cast<std::uint32_t>(next.size());
        s.secondary_rays += count;
        if (count == 0) break;
        size_for(count);
        auto* rays = f.rays->as<raycache::shared::raycache_rsh_ray>();
        auto* states = f.states->as<RayState>();
        for (std::uint32_t i = 0; i < count; ++i) rays[i] = next[i].ray, states[i] = next[i].state;
    }
    s.shade_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

} // namespace rcx::gpu
