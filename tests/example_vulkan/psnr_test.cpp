// The Vulkan tracer against the Embree tracer: uncached images of behind-8 and grid-32 at 96x96 (all rays
// in compute, or with --hybrid primary hits rasterised) agree at PSNR >= 40 dB, and the validation layer reports no error. Exit 77 (CTest: skipped) only when there is
// no Vulkan device.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <rcx/vulkan.hpp>

#include "gpu_tracer.hpp"
#include "test_support.hpp"
#include "rcx/image.hpp"
#include "rcx/scene.hpp"
#include "tracer.hpp"

int main(int argc, char** argv) {
    // Arguments: other scene names (and, after --frame N, the camera frame), for checking by hand.
    // --hybrid: primary hits from the raster pass (otherwise every ray in compute).
    std::vector<std::string> names;
    int frame = 0;
    bool hybrid = false;
    for (int i = 1; i < argc; ++i) {
        if (std::string(argv[i]) == "--frame" && i + 1 < argc) frame = std::stoi(argv[++i]);
        else if (std::string(argv[i]) == "--hybrid") hybrid = true;
        else names.push_back(argv[i]);
    }
    if (names.empty()) names = {"behind-8", "grid-32"};
    std::unique_ptr<rcx::vk::Context> context = rcx::gpu::test::context_or_skip();
    if (!context) return 77;
    int failures = 0;
    const int size = 96;
    for (const std::string& name : names) {
        const rcx::Scene scene = rcx::make_scene(name);
        const rcx::Camera camera = scene.camera_at(frame);
        rcx::gpu::TracerSettings gpu_settings;
        gpu_settings.hybrid = hybrid;
        rcx::gpu::Tracer gpu(*context, scene, rcx::gpu::default_spirv_dir(), gpu_settings);
        const rcx::Image a = gpu.render(camera, size, size);
        rcx::embree::Tracer cpu(scene);
        rcx::embree::RenderSettings settings;
        settings.width = settings.height = size;
        settings.mode = rcx::CacheMode::off;
        const rcx::Image b = cpu.render(camera, settings);
        const rcx::ImageDifference d = rcx::compare(a, b);
        const bool ok = d.psnr_db >= 40.0;
        std::printf("%s %s%s: PSNR %.2f dB, mean error %.5f, max error %.4f, %zu of %zu pixels differ\n", ok ? "ok  " : "FAIL",
                    name.c_str(), hybrid ? " (hybrid)" : "", d.psnr_db, d.mean_abs_error, d.max_abs_error, d.differing_pixels, d.pixels);
        if (!ok) {
            ++failures;
            const std::string stem = std::string("vulkan-psnr-") + name + (hybrid ? "-hybrid" : "");
            rcx::write_png(stem + "-gpu.png", a);
            rcx::write_png(stem + "-embree.png", b);
            rcx::write_png(stem + "-diff.png", rcx::difference_image(a, b));
        }
    }
    context.reset();
    failures += rcx::gpu::test::validation_failures();
    return failures == 0 ? 0 : 1;
}
