// --secondary rsh against --secondary bvh in the Vulkan tracer: the same frames, all rays in compute and
// with --hybrid (raster primary hits), on behind-8 (mirrors), glass (refraction, reflection inside glass)
// and dynamic-8 at frame 6 (objects moved by set_scene: the BVH rebuilt, the hierarchy needs nothing).
// The bar is every pixel equal on the 8-bit output (it is, on these scenes at 48x48), though the two
// paths are not the same computation: shadow rays are traced reversed, from the light (paper section
// 3.5.1), so a grazing occluder could be decided differently by rounding, and a pixel's colours are
// summed generation by generation instead of depth first, so float sums round differently (1 in 8 bits
// at most); on other scenes or sizes expect rare pixels off by that.
//
// What goes through the hierarchy: only the secondary rays (reflected and refracted rays of every bounce)
// and the shadow rays, never the primary rays, with or without --hybrid. The rays that entered a
// hierarchy in the frame (counted on the device as the leaves are built) must equal what the Embree
// tracer, an independent implementation, traces besides its primary rays: its rtcIntersect1 calls less
// one per pixel, plus its rtcOccluded1 calls. A primary ray sent through the hierarchy would add up to a
// pixel's worth of rays (2304 here).
//
// No read-back between generations: the frame is one submission (plus the raster pass's with --hybrid),
// counted by the Vulkan harness, however many generations it has; the host waits for the device only at
// the end of a submission.
//
// A frame after one with fewer generations records too few, sees it at its end and renders again with
// all. A generation with more rays than the Morton slots (a glass sphere filling the view) makes the frame
// record itself again with more room, and the image is still the BVH path's.
//
// A pair capacity small enough to split the primitives into batches gives the same image bit for bit:
// capacities from 4160 (a little above the 64 x 64 Morton slots one primitive can meet) down by halves
// are tried until one splits a batch (one below what a single primitive meets is refused with an
// exception, which ends the search); every one that renders must give the same image, and one must have
// split. The validation layer must report nothing. Exit 77: no Vulkan device with 64-bit atomics.
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include <glm/glm.hpp>
#include <rcx/vulkan.hpp>

#include "gpu_tracer.hpp"
#include "test_support.hpp"
#include "tracer.hpp" // the Embree tracer: the independent count of secondary and shadow rays
#include "rcx/image.hpp"
#include "rcx/scene.hpp"

int main() {
    std::unique_ptr<rcx::vk::Context> context = rcx::gpu::test::context_or_skip(true);
    if (!context) return 77;
    int failures = 0;
    auto check = [&](bool ok, const std::string& what) {
        std::printf("%s %s\n", ok ? "ok  " : "FAIL", what.c_str());
        failures += ok ? 0 : 1;
    };
    const int size = 48;
    const std::string spirv = rcx::gpu::default_spirv_dir();
    for (const char* name : {"behind-8", "glass", "dynamic-8"}) {
        const rcx::Scene scene = rcx::make_scene(name);
        const int frame = scene.dynamic() ? 6 : 0;
        const rcx::Scene moved = scene.dynamic() ? scene.at_frame(frame) : scene;
        const rcx::Camera camera = scene.camera_at(frame);

        // The Embree tracer's rays besides the primary ones.
        rcx::embree::Tracer embree(moved);
        rcx::embree::RenderSettings es;
        es.width = es.height = size;
        es.mode = rcx::CacheMode::off;
        rcx::embree::FrameStats counted;
        embree.render(camera, es, &counted);
        const std::uint64_t primary = static_cast<std::uint64_t>(size) * size;
        const std::uint64_t expected = counted.rays - primary + counted.shadow_rays;
        std::printf("     %s: the Embree tracer traces %llu rays (%llu primary) and %llu shadow rays: %llu after the primary hits\n",
                    name, static_cast<unsigned long long>(counted.rays), static_cast<unsigned long long>(primary),
                    static_cast<unsigned long long>(counted.shadow_rays), static_cast<unsigned long long>(expected));

        for (bool hybrid : {false, true}) {
            const std::string label = std::string(name) + (hybrid ? " (hybrid)" : "");
            rcx::gpu::TracerSettings settings;
            settings.mode = rcx::CacheMode::off;
            settings.hybrid = hybrid;
            rcx::gpu::Tracer bvh(*context, scene, spirv, settings);
            settings.secondary = rcx::gpu::Secondary::rsh;
            rcx::gpu::Tracer rsh(*context, scene, spirv, settings);
            if (scene.dynamic()) bvh.set_scene(moved), rsh.set_scene(moved);
            const rcx::Image a = bvh.render(camera, size, size);
            rcx::gpu::FrameStats stats;
            const std::uint64_t before = context->submissions();
            const rcx::Image b = rsh.render(camera, size, size, &stats);
            const std::uint64_t submissions = context->submissions() - before;
            const rcx::ImageDifference d = rcx::compare(a, b);
            const bool ok = d.differing_pixels == 0;
            std::printf("%s %s: rsh against bvh PSNR %.2f dB, %zu of %zu pixels differ (max %.4f); %d generations, %u batches\n",
                        ok ? "ok  " : "FAIL", label.c_str(), d.psnr_db, d.differing_pixels, d.pixels, d.max_abs_error,
                        stats.rsh.generations, stats.rsh.trace.batches);
            if (!ok) {
                ++failures;
                const std::string stem = std::string("vulkan-rsh-") + name + (hybrid ? "-hybrid" : "");
                rcx::write_png(stem + "-bvh.png", a);
                rcx::write_png(stem + "-rsh.png", b);
                rcx::write_png(stem + "-diff.png", rcx::difference_image(a, b));
            }

            const rcx::gpu::RshFrameStats& r = stats.rsh;
            check(r.trace.live_rays == expected,
                  label + ": " + std::to_string(r.trace.live_rays) + " rays entered the hierarchy, the Embree tracer's " +
                      std::to_string(expected) + " secondary and shadow rays (" + std::to_string(r.secondary_rays) +
                      " secondary, " + std::to_string(r.shadow_rays) + " shadow counted by the frame)");
            check(r.generations >= 3 && r.submissions == 1 && submissions == (hybrid ? 2u : 1u),
                  label + ": " + std::to_string(r.generations) + " generations in " + std::to_string(submissions) +
                      " submission(s) (" + (hybrid ? "the raster pass's and " : "") + "one for every generation)");

            if (hybrid || scene.dynamic()) continue;
            // Batching: capacities below the frame's largest stream, the same image bit for bit.
            bool split = false;
            for (std::uint32_t capacity = 4160; capacity >= 64 && !split; capacity /= 2) {
                settings.pair_capacity = capacity;
                rcx::gpu::Tracer tight(*context, scene, spirv, settings);
                rcx::gpu::FrameStats tight_stats;
                rcx::Image c;
                try {
                    c = tight.render(camera, size, size, &tight_stats);
                } catch (const std::runtime_error& e) {
                    std::printf("     %s: pair capacity %u: %s\n", name, capacity, e.what());
                    break;
                }
                const bool same = rcx::bit_identical(b, c);
                split = tight_stats.rsh.trace.overflows > 0;
                check(same, std::string(name) + ": pair capacity " + std::to_string(capacity) + ": " +
                                std::to_string(tight_stats.rsh.trace.batches) + " batches (" +
                                std::to_string(tight_stats.rsh.trace.overflows) + " overflowed, " +
                                std::to_string(tight_stats.rsh.submissions) + " submissions), " +
                                (same ? "the same image bit for bit" : "a different image"));
            }
            check(split, std::string(name) + ": a pair capacity split the primitives into batches");
        }
    }

    // A generation larger than the Morton slots: a glass sphere filling a 64 x 64 frame sends a reflected
    // and a refracted ray from every pixel, 8192 rays for 4096 slots. The frame sees it only at its end
    // and records itself again with room for 4 times the rays: the same image as the BVH path; the next
    // frame keeps the room and is one submission again.
    {
        rcx::Scene scene = rcx::make_scene("glass");
        rcx::Sphere lens;
        lens.centre = scene.camera.target;
        lens.radius = 0.6f * glm::length(scene.camera.eye - scene.camera.target); // 37 degrees: beyond the 22.5 of the view
        lens.material.diffuse = glm::vec3(0.1f);
        lens.material.transparency = 0.9f;
        lens.material.ior = 1.3f;
        scene.spheres.push_back(lens);
        const int side = 64;
        rcx::gpu::TracerSettings settings;
        settings.mode = rcx::CacheMode::off;
        rcx::gpu::Tracer bvh(*context, scene, spirv, settings);
        settings.secondary = rcx::gpu::Secondary::rsh;
        rcx::gpu::Tracer rsh(*context, scene, spirv, settings);
        const rcx::Image a = bvh.render(scene.camera, side, side);
        rcx::gpu::FrameStats first, second;
        const rcx::Image b = rsh.render(scene.camera, side, side, &first);
        const std::uint64_t before = context->submissions();
        const rcx::Image c = rsh.render(scene.camera, side, side, &second);
        const std::uint64_t submissions = context->submissions() - before;
        const rcx::ImageDifference d = rcx::compare(a, b);
        check(first.rsh.ray_overflows > 0 && first.rsh.submissions == first.rsh.ray_overflows + 1 &&
                  first.rsh.ray_capacity >= 4u * side * side && d.differing_pixels == 0 && rcx::bit_identical(b, c),
              "a glass sphere filling the view: " + std::to_string(first.rsh.secondary_rays) + " secondary rays, " +
                  "a generation over the " + std::to_string(side * side) + " slots: recorded " +
                  std::to_string(first.rsh.ray_overflows) + " more time(s), with room for " +
                  std::to_string(first.rsh.ray_capacity) + " rays: " +
                  std::to_string(d.differing_pixels) + " pixels differ from the BVH path; the next frame " +
                  (rcx::bit_identical(b, c) ? "the same" : "different"));
        check(second.rsh.ray_overflows == 0 && second.rsh.submissions == 1 && submissions == 1,
              "the next frame keeps the room: " + std::to_string(submissions) + " submission(s)");
    }

    // A frame records as many generations as the last had rays in: glass seen after a view with fewer
    // generations (the camera turned away) has rays beyond them, which the frame sees at its end and
    // renders again with all generations: the BVH path's image.
    {
        const rcx::Scene scene = rcx::make_scene("glass");
        rcx::Camera away = scene.camera;
        away.target = away.eye + (away.eye - away.target);
        rcx::gpu::TracerSettings settings;
        settings.mode = rcx::CacheMode::off;
        rcx::gpu::Tracer bvh(*context, scene, spirv, settings);
        settings.secondary = rcx::gpu::Secondary::rsh;
        rcx::gpu::Tracer rsh(*context, scene, spirv, settings);
        rcx::gpu::FrameStats few, more;
        rsh.render(away, size, size, &few);
        const rcx::Image b = rsh.render(scene.camera, size, size, &more);
        const rcx::ImageDifference d = rcx::compare(bvh.render(scene.camera, size, size), b);
        check(few.rsh.generations < more.rsh.generations && more.rsh.truncations == 1 && more.rsh.submissions == 2 &&
                  d.differing_pixels == 0,
              "glass after a view of " + std::to_string(few.rsh.generations) + " generation(s): " +
                  std::to_string(more.rsh.generations) + " generations, recorded " + std::to_string(more.rsh.submissions) +
                  " times (" + std::to_string(more.rsh.truncations) + " with too few), " +
                  std::to_string(d.differing_pixels) + " pixels differ from the BVH path");
    }

    context.reset();
    failures += rcx::gpu::test::validation_failures();
    return failures == 0 ? 0 : 1;
}
