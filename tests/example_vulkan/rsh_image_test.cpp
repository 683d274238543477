// --secondary rsh against --secondary bvh in the Vulkan tracer: the same frames, all rays in compute and
// with --hybrid (raster primary hits), on behind-8 (mirrors), glass (refraction, reflection inside glass)
// and dynamic-8 at frame 6 (objects moved by set_scene: the BVH rebuilt, the hierarchy needs nothing).
// The bar is every pixel equal on the 8-bit output (it is, on these scenes at 48x48), though the two
// paths are not the same computation: shadow rays are traced reversed, from the light (paper section
// 3.5.1), so a grazing occluder could be decided differently by rounding, and a pixel's colours are
// summed generation by generation instead of depth first, so float sums round differently (1 in 8 bits
// at most); on other scenes or sizes expect rare pixels off by that. A pair capacity small enough to split the primitives into batches gives the same image
// bit for bit. The validation layer must report nothing. Exit 77: no Vulkan device with 64-bit atomics.
#include <cstdio>
#include <memory>
#include <string>

#include <rcx/vulkan.hpp>

#include "gpu_tracer.hpp"
#include "test_support.hpp"
#include "rcx/image.hpp"
#include "rcx/scene.hpp"

int main() {
    std::unique_ptr<rcx::vk::Context> context = rcx::gpu::test::context_or_skip(true);
    if (!context) return 77;
    int failures = 0;
    const int size = 48;
    const std::string spirv = rcx::gpu::default_spirv_dir();
    for (const char* name : {"behind-8", "glass", "dynamic-8"}) {
        const rcx::Scene scene = rcx::make_scene(name);
        const int frame = scene.dynamic() ? 6 : 0;
        for (bool hybrid : {false, true}) {
            rcx::gpu::TracerSettings settings;
            settings.mode = rcx::CacheMode::off;
            settings.hybrid = hybrid;
            rcx::gpu::Tracer bvh(*context, scene, spirv, settings);
            settings.secondary = rcx::gpu::Secondary::rsh;
            rcx::gpu::Tracer rsh(*context, scene, spirv, settings);
            if (scene.dynamic()) bvh.set_scene(scene.at_frame(frame)), rsh.set_scene(scene.at_frame(frame));
            const rcx::Camera camera = scene.camera_at(frame);
            const rcx::Image a = bvh.render(camera, size, size);
            rcx::gpu::FrameStats stats;
            const rcx::Image b = rsh.render(camera, size, size, &stats);
            const rcx::ImageDifference d = rcx::compare(a, b);
            const bool ok = d.differing_pixels == 0;
            std::printf("%s %s%s: rsh against bvh PSNR %.2f dB, %zu of %zu pixels differ (max %.4f); %d generations, %u batches\n",
                        ok ? "ok  " : "FAIL", name, hybrid ? " (hybrid)" : "", d.psnr_db, d.differing_pixels, d.pixels,
                        d.max_abs_error, stats.rsh.generations, stats.rsh.trace.batches);
            if (!ok) {
                ++failures;
                const std::string stem = std::string("vulkan-rsh-") + name + (hybrid ? "-hybrid" : "");
                rcx::write_png(stem + "-bvh.png", a);
                rcx::write_png(stem + "-rsh.png", b);
                rcx::write_png(stem + "-diff.png", rcx::difference_image(a, b));
            }
            if (hybrid || scene.dynamic()) continue;
            // Batching: a capacity below the frame's largest stream, the same image bit for bit.
            settings.pair_capacity = 4160; // a little above the 64 x 64 Morton slots one primitive can meet
            rcx::gpu::Tracer tight(*context, scene, spirv, settings);
            rcx::gpu::FrameStats tight_stats;
            const rcx::Image c = tight.render(camera, size, size, &tight_stats);
            const bool same = rcx::bit_identical(b, c) && tight_stats.rsh.trace.overflows > 0;
            std::printf("%s %s: pair capacity 4160: %u batches (%u overflowed), %s\n", same ? "ok  " : "FAIL", name,
                        tight_stats.rsh.trace.batches, tight_stats.rsh.trace.overflows,
                        rcx::bit_identical(b, c) ? "the same image bit for bit" : "a different image");
            failures += same ? 0 : 1;
        }
    }
    context.reset();
    failures += rcx::gpu::test::validation_failures();
    return failures == 0 ? 0 : 1;
}
