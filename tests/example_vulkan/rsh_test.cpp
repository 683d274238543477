// The ray-space hierarchy engine on the device (rsh_engine.hpp) against brute force over all primitives
// (rcx/rsh_reference.hpp, in C++): for every ray the same closest primitive, the distance within 1e-5
// relative (the GPU runs the BVH tracer's GLSL tests, brute force their C++ transcription), on random
// triangles and spheres and on first-bounce rays of behind-8 and dynamic-8; a pair capacity too small
// for one batch gives bit-identical hits in several batches (and says so); the engine's prefix sum,
// recorded with its count on the device, gives a running sum's values; and the validation layer reports
// nothing. Exit 77 (CTest: skipped) when there is no Vulkan device with 64-bit atomics.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <rcx/vulkan.hpp>

#include "gpu_tracer.hpp"
#include "test_support.hpp"
#include "rcx/rsh_reference.hpp"
#include "rcx/scene.hpp"
#include "rsh_engine.hpp"

namespace {

using rcx::rsh::Hit;
using rcx::rsh::Primitive;
using rcx::rsh::Ray;

int failures = 0;

void fail(const std::string& what) {
    std::printf("FAIL %s\n", what.c_str());
    ++failures;
}

std::uint32_t next(std::uint64_t& state) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<std::uint32_t>(state >> 32);
}
float uniform(std::uint64_t& s) { return static_cast<float>(next(s) >> 8) * (1.0f / 16777216.0f) * 2.0f - 1.0f; }

struct GpuRun {
    std::vector<raycache::shared::raycache_rsh_hit> hits;
    rcx::gpu::RshStats stats;
};

GpuRun run(rcx::vk::Context& vk, rcx::gpu::RshEngine& engine, const std::vector<Ray>& rays, const std::vector<Primitive>& prims) {
    rcx::vk::Buffer ray_buffer = rcx::vk::buffer_of(vk, rays, 32);
    rcx::vk::Buffer prim_buffer = rcx::vk::buffer_of(vk, prims, 48);
    rcx::vk::Buffer hit_buffer(vk, rays.size() * 8);
    GpuRun r;
    r.stats = engine.trace(ray_buffer, static_cast<std::uint32_t>(rays.size()), prim_buffer,
                           static_cast<std::uint32_t>(prims.size()), hit_buffer);
    r.hits.resize(rays.size());
    std::memcpy(r.hits.data(), hit_buffer.data(), rays.size() * 8);
    return r;
}

// Every ray's GPU hit against brute force.
void compare(const std::string& name, const GpuRun& gpu, const std::vector<Hit>& expected) {
    std::size_t hits = 0, bad = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
        const auto& g = gpu.hits[i];
        const Hit& e = expected[i];
        if (e.primitive == rcx::rsh::no_hit) {
            if (g.primitive != RAYCACHE_RSH_NO_HIT) {
                if (bad++ < 5) std::printf("  %s ray %zu: GPU hit primitive %u, brute force none\n", name.c_str(), i, g.primitive);
            }
            continue;
        }
        ++hits;
        float t = 0.0f;
        std::memcpy(&t, &g.t_bits, 4);
        if (g.primitive != e.primitive || !(std::abs(t - e.t) <= 1e-5f * e.t)) {
            if (bad++ < 5)
                std::printf("  %s ray %zu: GPU primitive %u at %.7g, brute force %u at %.7g\n", name.c_str(), i, g.primitive,
                            static_cast<double>(t), e.primitive, static_cast<double>(e.t));
        }
    }
    const double live = gpu.stats.rays ? static_cast<double>(gpu.stats.rays) : 1.0;
    std::printf("%s %s: %zu rays, %zu hit, %zu differ; %u batches (%u overflowed), %llu cone-sphere tests, %.2f leaf pairs "
                "a ray slot; GPU ms: build %.2f, tests %.2f, compaction %.2f, final %.2f; wall %.1f ms\n",
                bad ? "FAIL" : "ok  ", name.c_str(), expected.size(), hits, bad, gpu.stats.batches, gpu.stats.overflows,
                static_cast<unsigned long long>(gpu.stats.cone_sphere_tests), static_cast<double>(gpu.stats.leaf_pairs) / live,
                gpu.stats.build_ms, gpu.stats.traverse_ms, gpu.stats.compaction_ms, gpu.stats.final_ms, gpu.stats.wall_ms);
    if (bad) ++failures;
}

} // namespace

int main() {
    std::unique_ptr<rcx::vk::Context> context = rcx::gpu::test::context_or_skip(true);
    if (!context) return 77;
    rcx::vk::Context& vk = *context;
    const std::string spirv = rcx::gpu::default_spirv_dir();
    {
        rcx::gpu::RshEngine engine(vk, spirv);

        // Random triangles and spheres; coherent rays (origins on a patch, directions fanning out with the
        // Morton index, as from a curved mirror), every 7th slot empty, one bounded.
        std::uint64_t seed = 5;
        std::vector<Primitive> prims;
        for (int i = 0; i < 600; ++i) {
            const glm::vec3 c(6.0f * uniform(seed), 6.0f * uniform(seed), 6.0f * uniform(seed));
            auto corner = [&] { return c + 0.5f * glm::vec3(uniform(seed), uniform(seed), uniform(seed)); };
            prims.push_back(rcx::rsh::triangle(corner(), corner(), corner()));
        }
        for (int i = 0; i < 50; ++i)
            prims.push_back(rcx::rsh::sphere(glm::vec3(6.0f * uniform(seed), 6.0f * uniform(seed), 6.0f * uniform(seed)),
                                             0.1f + 0.4f * std::abs(uniform(seed))));
        std::vector<Ray> rays(64 * 64);
        for (std::size_t m = 0; m < rays.size(); ++m) {
            const glm::uvec2 px = rcx::rsh::morton_pixel(static_cast<std::uint32_t>(m));
            const float x = (static_cast<float>(px.x) + 0.5f) / 64.0f - 0.5f, y = (static_cast<float>(px.y) + 0.5f) / 64.0f - 0.5f;
            rays[m] = Ray{glm::vec3(x, y, -7.0f), m % 7 == 3 ? 0.0f : (m == 100 ? 6.5f : INFINITY),
                          glm::normalize(glm::vec3(1.5f * x, 1.5f * y, 1.0f)), 0u};
        }
        rays.resize(3000); // not a power of 4: padded with empty leaves
        const std::vector<Hit> expected = rcx::rsh::brute_force(rays, prims);
        const GpuRun one = run(vk, engine, rays, prims);
        compare("random, one batch", one, expected);
        if (one.stats.batches != 1 || one.stats.overflows != 0) fail("random: one batch expected");

        // The same with a capacity that overflows: several batches, the same hits bit for bit.
        rcx::gpu::RshSettings small;
        small.pair_capacity = static_cast<std::uint32_t>(std::max<std::uint64_t>(one.stats.leaf_pairs / 4, 64));
        rcx::gpu::RshEngine tight(vk, spirv, small);
        const GpuRun many = run(vk, tight, rays, prims);
        compare("random, capacity " + std::to_string(small.pair_capacity), many, expected);
        if (many.stats.batches < 2 || many.stats.overflows == 0) fail("random: the small capacity did not split the batch");
        if (std::memcmp(many.hits.data(), one.hits.data(), one.hits.size() * 8) != 0) fail("random: batches changed the hits");
        if (many.stats.leaf_pairs != one.stats.leaf_pairs) fail("random: batches changed the pairs reaching the leaves");
        if (tight.batch_size() >= small.pair_capacity) fail("random: the next frame's batch size was not lowered");
        // A second call starts with the lowered batch size: fewer overflows.
        const GpuRun again = run(vk, tight, rays, prims);
        if (std::memcmp(again.hits.data(), one.hits.data(), one.hits.size() * 8) != 0) fail("random: second call differs");
        std::printf("     second call with the lowered batch size: %u batches, %u overflowed\n", again.stats.batches,
                    again.stats.overflows);

        // The C++ reference keeps the same number of pairs at the leaves (the same cone-sphere decisions),
        // up to rounding of tan/cos/atan between the device and libm.
        rcx::rsh::TraceStats ref;
        rcx::rsh::trace(rays, rcx::rsh::build(rays), prims, 1u << 22, &ref);
        const double ratio = static_cast<double>(one.stats.leaf_pairs) / static_cast<double>(ref.leaf_pairs);
        std::printf("     leaf pairs: GPU %llu, C++ reference %zu\n", static_cast<unsigned long long>(one.stats.leaf_pairs), ref.leaf_pairs);
        if (ratio < 0.999 || ratio > 1.001) fail("random: the GPU keeps a different number of leaf pairs than the reference");

        // First-bounce rays of the tracers' scenes.
        for (const char* name : {"behind-8", "dynamic-8"}) {
            const rcx::Scene base = rcx::make_scene(name);
            const rcx::Scene scene = base.dynamic() ? base.at_frame(7) : base;
            const std::vector<Ray> bounce = rcx::rsh::first_bounce_rays(scene, scene.camera_at(7), 64);
            const std::vector<Primitive> sp = rcx::rsh::primitives_of(scene);
            compare(std::string(name) + " first bounce", run(vk, engine, bounce, sp), rcx::rsh::brute_force(bounce, sp));
        }

        // The engine's prefix sum over a caller's flags, recorded with its count on the device (as the
        // frame compacts a generation's candidates): exclusive sums and total against a running sum on
        // the host, over three scan levels (more than 1024 * 1024 elements) and over a short stream.
        for (const std::uint32_t units : {400000u, 5u}) {
            const std::uint32_t scale = 3, n = scale * units, max_elements = n + 1000;
            std::vector<std::uint32_t> flags(max_elements, 1u); // past n: must not be counted
            std::uint64_t state = 11;
            for (std::uint32_t i = 0; i < n; ++i) flags[i] = next(state) % 3 == 0 ? 1u : 0u;
            rcx::vk::Buffer flag_buffer = rcx::vk::buffer_of(vk, flags, 4);
            rcx::vk::Buffer counts(vk, 16);
            const std::uint32_t count_words[4] = {0u, 0u, units, 0u};
            counts.upload(count_words, sizeof count_words);
            rcx::vk::Buffer sums(vk, rcx::gpu::RshEngine::prefix_sum_bytes(max_elements));
            sums.fill(0xDEADBEEFu);
            vk.submit([&](rcx::vk::Commands& c) {
                engine.begin(c);
                engine.record_prefix_sum(c, flag_buffer, counts, 2, scale, max_elements, sums);
            });
            engine.end();
            const std::uint32_t* out = sums.as<std::uint32_t>();
            std::uint32_t running = 0, bad = 0;
            for (std::uint32_t i = 0; i < n; ++i) {
                if (out[i] != running && bad++ < 5) std::printf("  prefix sum %u: %u, expected %u\n", i, out[i], running);
                running += flags[i];
            }
            const std::uint32_t total = out[rcx::gpu::RshEngine::prefix_sum_total_word(max_elements)];
            const bool ok = bad == 0 && total == running;
            std::printf("%s prefix sum of %u flags with the count on the device: %u differ, total %u (expected %u)\n",
                        ok ? "ok  " : "FAIL", n, bad, total, running);
            if (!ok) ++failures;
        }

        // No primitives, no rays: nothing hit, nothing written out of bounds.
        const GpuRun empty = run(vk, engine, rays, {});
        for (const auto& h : empty.hits)
            if (h.primitive != RAYCACHE_RSH_NO_HIT) { fail("no primitives: a ray hit something"); break; }
    }
    context.reset();
    failures += rcx::gpu::test::validation_failures();
    std::printf("%s\n", failures ? "FAILED" : "all passed");
    return failures ? 1 : 0;
}
