// raycache_vulkan_whitted: the Whitted tracer of raycache_embree_whitted as a Vulkan compute shader (one
// invocation per pixel, its own BVH traversed in GLSL; runs on Mesa's lavapipe), with the rays leaving
// reflective and refractive objects cached in caching cubes through RayCache's GLSL include. Same
// scenes, camera paths and options as the Embree example (rcx::CommandLine; --help).
//
//   raycache_vulkan_whitted --scene behind-32 --size 256x256 --cache cct --frames 10 --compare
//
// Differences from the Embree example: --threads is ignored (the Vulkan driver decides), --prefill,
// --load-cache and --save-cache are refused, --cdct-search relief is the linear walk (no depth pyramid in
// GLSL), and a ray leaving a cached object inside the subtree of a missed leaving ray is traced without a
// lookup (no recursion in GLSL).
// --hybrid (this tracer's own option): primary visibility by a raster pass into a G-buffer, secondary
// rays in compute, as in the thesis's Table 5.1.
// Exit status 2: bad options, more memory needed than is available, no Vulkan device, a shader that does
// not load.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <rcx/vulkan.hpp>

#include "gpu_tracer.hpp"
#include "rsh_frame.hpp"
#include "rcx/command_line.hpp"
#include "rcx/image.hpp"
#include "rcx/memory.hpp"
#include "rcx/option_values.hpp"
#include "rcx/options.hpp"
#include "rcx/scene.hpp"
#include "rcx/scene_hash.hpp"
#include "rcx/tracer_main.hpp"

namespace {

using rcx::InputError; // bad input: message on stderr, exit status 2 (rcx::tracer_main)

std::string frame_path(const rcx::Options& o, const std::string& scene, const std::string& what, int frame, bool hybrid) {
    char name[256];
    std::snprintf(name, sizeof name, "%s-vulkan%s-%s-%04d.png", scene.c_str(), hybrid ? "-hybrid" : "", what.c_str(), frame);
    return (std::filesystem::path(o.out) / name).string();
}

// This tracer's own options (beside the shared rcx::Options).
struct VulkanOptions {
    bool hybrid = false;
    rcx::gpu::Secondary secondary = rcx::gpu::Secondary::bvh;
    std::uint32_t pair_capacity = 1u << 21;
    rcx::vk::BufferMemory buffer_memory = rcx::vk::BufferMemory::host; // --buffer-memory
    bool shader_statistics = false;                                     // --shader-stats
};

int run(const rcx::Options& o, const VulkanOptions& v) {
    const bool hybrid = v.hybrid;
    if (o.prefill) throw InputError("--prefill is not supported by the Vulkan tracer (only by raycache_embree_whitted)");
    // What the GPU side does not do yet: refused rather than ignored.
    const rcx::Options defaults;
    if (o.filtered) throw InputError("--filtered is not supported by the Vulkan tracer (only by raycache_embree_whitted)");
    if (o.trace_hits) throw InputError("--trace-hits is not supported by the Vulkan tracer (only by raycache_embree_whitted)");
    if (v.secondary == rcx::gpu::Secondary::rsh && o.depth && *o.depth > 30)
        throw InputError("--depth: the Vulkan tracer's --secondary rsh traces at most 30 bounces, got " + std::to_string(*o.depth));
    if (o.lookup_work)
        throw InputError("--lookup-work is not supported by the Vulkan tracer: its cubes rest at a fixed --min-hit-rate");
    if (o.light_samples > 1)
        throw InputError("--light-samples is not supported by the Vulkan tracer (only by raycache_embree_whitted)");
    if (!o.pyramid)
        throw InputError("--no-pyramid is not supported by the Vulkan tracer: its relief walk never uses a depth pyramid");
    if (o.invalidate != defaults.invalidate)
        throw InputError("--invalidate is not supported by the Vulkan tracer: its cubes cannot be invalidated yet");
    rcx::Scene scene;
    try {
        scene = rcx::scene_from_options(o);
    } catch (const std::exception& e) {
        throw InputError(e.what());
    }
    if (scene.dynamic() && rcx::uses_caches(o.cache))
        throw InputError("scene '" + scene.name + "' moves objects, and the Vulkan tracer's cubes cannot be invalidated "
                         "yet: use --cache off here, or raycache_embree_whitted (--invalidate)");

    rcx::vk::ContextOptions context_options;
    context_options.require_int64_atomics = o.cache == rcx::CacheMode::cdct || v.secondary == rcx::gpu::Secondary::rsh;
    context_options.buffer_memory = v.buffer_memory;
    context_options.shader_statistics = v.shader_statistics;
    std::unique_ptr<rcx::vk::Context> context;
    try {
        context = std::make_unique<rcx::vk::Context>(context_options);
    } catch (const rcx::vk::NoDeviceError& e) {
        throw InputError(std::string("no usable Vulkan device: ") + e.what() +
                         ". On Debian/Ubuntu install mesa-vulkan-drivers (lavapipe, Vulkan on the CPU) and libvulkan1.");
    }

    if (v.secondary == rcx::gpu::Secondary::rsh) {
        const auto& limits = context->properties().limits;
        try {
            rcx::gpu::RshFrame::check_image_size(o.width, o.height, limits.maxStorageBufferRange, limits.maxComputeWorkGroupCount[0]);
        } catch (const std::invalid_argument& e) {
            throw InputError(e.what());
        }
    }

    // The cubes live in two host-visible buffers (texels and pending) of at most maxStorageBufferRange
    // each, within the budget with their doubtful bits (a larger --face-size is lowered to fit); the frame
    // images come on top.
    const std::uint64_t budget_bytes = std::uint64_t(o.budget_mib) << 20;
    std::vector<rcx::MemoryNeed> needs{rcx::frame_images(o)};
    if (rcx::uses_caches(o.cache)) {
        // Adaptive cubes may grow to the largest face size, and while they are resized the old and the new
        // buffers live together.
        const bool adaptive = o.face_size <= 0;
        const std::uint64_t n = static_cast<std::uint64_t>(adaptive ? std::max(o.first_face_size, raycache::AdaptiveResolution{}.max_face_size)
                                                                    : o.face_size);
        const std::uint64_t cubes = static_cast<std::uint64_t>(scene.cached_object_count()) * 6 * n * n *
                                    (o.cache == rcx::CacheMode::cdct ? 8 : 4);
        const std::uint64_t buffer = std::min<std::uint64_t>(cubes, context->properties().limits.maxStorageBufferRange);
        const std::uint64_t held = std::min<std::uint64_t>(2 * buffer, budget_bytes);
        needs.push_back({adaptive ? "cube texel and pending buffers, old and new while resizing" : "cube texel and pending buffers",
                         (adaptive ? 2 : 1) * held});
    }
    try {
        rcx::check_memory(needs);
    } catch (const std::runtime_error& e) {
        throw InputError(e.what());
    }

    rcx::gpu::TracerSettings settings;
    settings.mode = o.cache;
    settings.face_size = o.face_size > 0 ? o.face_size : o.first_face_size;
    settings.adaptive = o.face_size <= 0; // auto: each cube's size follows its rays (raycache/gpu_adaptive.hpp)
    settings.adaptive_resolution.rays_per_texel = o.rays_per_texel;
    settings.adaptive_resolution.still_rays_per_texel = o.still_rays_per_texel;
    settings.adaptive_resolution.first_face_size = o.first_face_size;
    settings.budget_bytes = budget_bytes;
    settings.secant = o.secant;
    settings.max_reads = o.max_reads;
    settings.delta = o.delta;
    settings.epsilon = o.epsilon;
    settings.max_steps = o.max_steps;
    settings.max_gap = o.max_gap;
    settings.hybrid = hybrid;
    settings.secondary = v.secondary;
    settings.pair_capacity = v.pair_capacity;
    settings.edge_threshold = o.edge_threshold;
    settings.origin_drift = o.origin_drift;
    settings.origin_parallax = o.origin_parallax;
    settings.min_hit_rate = o.min_hit_rate; // -1 unless given: the technique's default
    const std::string spirv = rcx::gpu::default_spirv_dir();
    std::unique_ptr<rcx::gpu::Tracer> tracer, reference;
    try {
        tracer = std::make_unique<rcx::gpu::Tracer>(*context, scene, spirv, settings);
        if (o.compare) {
            rcx::gpu::TracerSettings plain = settings;
            plain.mode = rcx::CacheMode::off;
            reference = std::make_unique<rcx::gpu::Tracer>(*context, scene, spirv, plain);
        }
    } catch (const rcx::vk::Error& e) {
        throw InputError(std::string("cannot set up the Vulkan tracer: ") + e.what() +
                         " (shaders are looked for in " + spirv + "; RAYCACHE_VULKAN_WHITTED_SHADERS overrides it)");
    } catch (const std::invalid_argument& e) {
        throw InputError(e.what());
    }

    const bool caching = rcx::uses_caches(o.cache);
    const raycache::SceneIdentity identity{rcx::scene_hash(scene), scene.name};
    if (!o.load_cache.empty()) {
        try {
            tracer->load_caches(o.load_cache, identity);
        } catch (const raycache::CacheFileError& e) {
            throw InputError(e.what());
        }
        if (!o.quiet) std::printf("loaded cache %s\n", o.load_cache.c_str());
    }
    if (caching && o.face_size > 0 && tracer->face_size() != o.face_size)
        std::fprintf(stderr, "%s: note: --face-size %d: the cubes do not fit in one storage buffer of this device "
                             "(maxStorageBufferRange %llu bytes) or within --budget-mib %d; using face size %d\n",
                     "raycache_vulkan_whitted", o.face_size,
                     static_cast<unsigned long long>(context->properties().limits.maxStorageBufferRange), o.budget_mib,
                     tracer->face_size());
    const int frames = scene.path.frames;
    if (!o.quiet) {
        std::printf("device %s (validation %s); scene %s: %zu spheres, %zu meshes, %d cached objects, BVH %zu nodes; "
                    "%dx%d, depth %d, %s path, %d frames of %.2f deg\n",
                    context->device_name().c_str(), context->validation_enabled() ? "on" : "off", scene.name.c_str(),
                    scene.spheres.size(), scene.meshes.size(), scene.cached_object_count(), tracer->bvh_nodes(), o.width,
                    o.height, scene.max_depth, rcx::to_string(scene.path.kind), frames,
                    static_cast<double>(scene.path.step_degrees));
        std::printf("buffers: scene in %s memory", rcx::vk::memory_description(tracer->scene_memory_flags()).c_str());
        if (tracer->cube_memory_flags())
            std::printf(", cubes in %s memory", rcx::vk::memory_description(tracer->cube_memory_flags()).c_str());
        std::printf("\n");
        std::printf("%s; cache %s", hybrid ? "hybrid: primary hits rasterised into a G-buffer, secondary rays in compute" : "all rays in compute",
                    rcx::to_string(o.cache));
        if (caching)
            std::printf(", %s %dx%d, cubes %.1f MiB", settings.adaptive ? "adaptive faces from" : "faces", tracer->face_size(),
                        tracer->face_size(), static_cast<double>(tracer->cube_bytes()) / (1024.0 * 1024.0));
        if (o.cache == rcx::CacheMode::cdct && o.secant)
            std::printf(", secant search, epsilon %g, max reads %d", static_cast<double>(o.epsilon), o.max_reads);
        else if (o.cache == rcx::CacheMode::cdct)
            std::printf(", delta %g, epsilon %g, max steps %d, linear search", static_cast<double>(o.delta),
                        static_cast<double>(o.epsilon), o.max_steps);
        std::printf("; PNGs in %s\n", o.out.c_str());
        std::printf("frame         ms  GPU: trace  end-frame  hit rate%s\n",
                    o.compare ? "    uncached ms  speed-up   PSNR dB  GPU: uncached" : "");
        std::fflush(stdout);
    }

    if (v.shader_statistics) {
        auto print_statistics = [&](const char* which, const rcx::gpu::Tracer& t) {
            const std::vector<std::string> statistics = t.shader_statistics();
            std::printf("tracing shader, %s: ", which);
            if (statistics.empty()) std::printf("no statistics (%s has no VK_KHR_pipeline_executable_properties)", context->device_name().c_str());
            for (std::size_t i = 0; i < statistics.size(); ++i) std::printf("%s%s", i ? ", " : "", statistics[i].c_str());
            std::printf("\n");
        };
        print_statistics(rcx::to_string(o.cache), *tracer);
        if (reference) print_statistics("uncached", *reference);
        std::fflush(stdout);
    }

    double sum_ms = 0.0, warm_ms = 0.0, sum_plain = 0.0, warm_plain = 0.0, psnr_min = std::numeric_limits<double>::infinity();
    // GPU time alone (timestamps) after the first frame: the cached frame's tracing dispatch and end-of-frame
    // passes (and its host-side resizing), the uncached frame's dispatch. The frames' host-waited times also
    // hold what both pay alike (submitting, waiting, the image written to host memory).
    double warm_gpu = 0.0, warm_gpu_plain = 0.0;
    bool gpu_times = true;
    // After the first frame: the lookups, their hits, and the 32-lane groups with lookups and with hits alone.
    std::uint64_t warm_lookups = 0, warm_hits = 0;
    std::size_t warm_warps = 0, warm_warps_all_hit = 0;
    for (int f = 0; f < frames; ++f) {
        const rcx::Camera camera = scene.camera_at(f);
        if (scene.dynamic() && f > 0) { // objects move: the BVH is rebuilt, the ray-space hierarchy needs nothing
            const rcx::Scene moved = scene.at_frame(f);
            tracer->set_scene(moved);
            if (reference) reference->set_scene(moved);
        }
        rcx::gpu::FrameStats stats;
        const int warm_up = f == 0 ? o.warm_up : 0; // only the first frame has nothing to reuse
        const rcx::Image image = tracer->render(camera, o.width, o.height, &stats, warm_up);
        rcx::write_png(frame_path(o, scene.name, std::string(rcx::to_string(o.cache)) +
                                   (v.secondary == rcx::gpu::Secondary::rsh ? "-rsh" : ""), f, hybrid), image);
        // A cached frame's cost: its warm-up pass, tracing and end-of-frame passes, resizing the cubes after it.
        const double ms = stats.warm_up_milliseconds + stats.milliseconds + stats.resize_milliseconds;
        sum_ms += ms;
        if (f > 0) {
            warm_ms += ms;
            warm_lookups += stats.lookups;
            warm_hits += stats.hits;
            warm_warps += stats.warps.with_lookups;
            warm_warps_all_hit += stats.warps.all_hit;
        }
        double plain_ms = 0.0, plain_gpu_ms = 0.0, psnr = 0.0;
        if (o.compare) {
            rcx::gpu::FrameStats plain_stats;
            const rcx::Image plain = reference->render(camera, o.width, o.height, &plain_stats);
            plain_ms = plain_stats.milliseconds;
            sum_plain += plain_ms;
            if (f > 0) warm_plain += plain_ms;
            if (f > 0) {
                warm_gpu += stats.gpu_trace_milliseconds + stats.end_frame_milliseconds + stats.resize_milliseconds;
                warm_gpu_plain += plain_stats.gpu_trace_milliseconds;
                gpu_times = gpu_times && stats.gpu_trace_milliseconds > 0.0 && plain_stats.gpu_trace_milliseconds > 0.0;
            }
            plain_gpu_ms = plain_stats.gpu_trace_milliseconds;
            psnr = rcx::compare(image, plain).psnr_db;
            psnr_min = std::min(psnr_min, psnr);
            rcx::write_png(frame_path(o, scene.name, "reference", f, hybrid), plain);
            rcx::write_png(frame_path(o, scene.name, std::string(rcx::to_string(o.cache)) + "-diff", f, hybrid),
                           rcx::difference_image(image, plain));
        }
        if (!o.quiet) {
            char hit[32] = "    -";
            if (caching && stats.lookups > 0)
                std::snprintf(hit, sizeof hit, "%5.1f%%", 100.0 * static_cast<double>(stats.hits) / static_cast<double>(stats.lookups));
            // GPU times come from timestamps: "-" where there are none (no timestamps, rsh, no end-of-frame passes).
            auto gpu_ms = [](double ms) {
                char text[32] = "-";
                if (ms > 0.0) std::snprintf(text, sizeof text, "%.2f", ms);
                return std::string(text);
            };
            std::printf("%5d %10.2f %11s %10s   %s", f, stats.milliseconds, gpu_ms(stats.gpu_trace_milliseconds).c_str(),
                        gpu_ms(stats.end_frame_milliseconds).c_str(), hit);
            if (o.compare)
                std::printf(" %14.2f %8.2fx   %7s %11s", plain_ms, plain_ms / ms, rcx::psnr_text(psnr).c_str(), gpu_ms(plain_gpu_ms).c_str());
            if (v.secondary == rcx::gpu::Secondary::rsh) {
                const rcx::gpu::RshStats& r = stats.rsh.trace;
                std::printf("   rsh: %d generations, %u batches (%u overflowed), %.3g cone-sphere tests, %llu leaf pairs; GPU ms "
                            "build %.1f, tests %.1f, compaction %.1f, final %.1f; other (primary rays, shading, ray compaction) %.1f",
                            stats.rsh.generations, r.batches, r.overflows, static_cast<double>(r.cone_sphere_tests),
                            static_cast<unsigned long long>(r.leaf_pairs), r.build_ms, r.traverse_ms, r.compaction_ms,
                            r.final_ms, stats.rsh.shade_ms);
            } else if (stats.update_ms > 0.0) {
                std::printf("   BVH rebuild %.1f ms", stats.update_ms);
            }
            if (warm_up > 1 && caching)
                std::printf("   warm-up (stride %d): %.2f ms, %llu texels stored", warm_up, stats.warm_up_milliseconds,
                            static_cast<unsigned long long>(stats.warm_up_stored_texels));
            if (stats.resting_cubes > 0)
                std::printf("   %zu cubes rested (%.1f%% of the leaving rays traced alone)", stats.resting_cubes,
                            100.0 * static_cast<double>(stats.rested) / static_cast<double>(std::max<std::uint64_t>(stats.lookups, 1)));
            if (stats.resized_cubes > 0) {
                const std::vector<int> sizes = tracer->face_sizes();
                std::printf("   %zu cubes resized in %.1f ms: faces %d..%d, cubes %.1f MiB", stats.resized_cubes,
                            stats.resize_milliseconds, *std::min_element(sizes.begin(), sizes.end()),
                            *std::max_element(sizes.begin(), sizes.end()),
                            static_cast<double>(tracer->cube_bytes()) / (1024.0 * 1024.0));
            }
            std::printf("\n");
            std::fflush(stdout);
        }
    }
    if (!o.save_cache.empty()) {
        tracer->save_caches(o.save_cache, identity);
        if (!o.quiet)
            std::printf("saved cache %s: %.1f MiB\n", o.save_cache.c_str(),
                        static_cast<double>(std::filesystem::file_size(o.save_cache)) / (1024.0 * 1024.0));
    }
    const double n = frames;
    const double warm = frames > 1 ? n - 1 : 1;
    std::printf("summary %s, %dx%d, cache %s (Vulkan, %s): mean %.2f ms/frame (%.2f ms after the first), warm-up, end-frame passes and resizing included\n",
                scene.name.c_str(), o.width, o.height, rcx::to_string(o.cache), context->device_name().c_str(), sum_ms / n,
                frames > 1 ? warm_ms / warm : sum_ms / n);
    if (o.compare)
        std::printf("summary uncached: mean %.2f ms/frame (%.2f ms after the first); speed-up %.2fx after the first frame; PSNR min %s dB\n",
                    sum_plain / n, frames > 1 ? warm_plain / warm : sum_plain / n,
                    frames > 1 ? warm_plain / warm_ms : sum_plain / sum_ms, rcx::psnr_text(psnr_min).c_str());
    if (warm_warps > 0 && warm_lookups > 0)
        std::printf("summary after the first frame: %.1f%% of the lookups hit; in %.1f%% of the 32-lane groups "
                    "(8 x 4 pixels) with lookups all of them hit (only then does a GPU's group skip the traces)\n",
                    100.0 * static_cast<double>(warm_hits) / static_cast<double>(warm_lookups),
                    100.0 * static_cast<double>(warm_warps_all_hit) / static_cast<double>(warm_warps));
    if (o.compare && frames > 1 && gpu_times && warm_gpu > 0.0)
        std::printf("summary GPU time after the first frame (tracing, end-of-frame passes and resizing; uncached: tracing): "
                    "%.3f ms against %.3f ms uncached; speed-up %.2fx\n",
                    warm_gpu / warm, warm_gpu_plain / warm, warm_gpu_plain / warm_gpu);
    tracer.reset();
    reference.reset();
    context.reset();
    if (rcx::vk::validation_errors_in_process() > 0) { // the context's own count is part of it
        std::fprintf(stderr, "Vulkan validation reported %llu error(s)\n",
                     static_cast<unsigned long long>(rcx::vk::validation_errors_in_process()));
        return 1;
    }
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    const std::string program = rcx::program_name(argc, argv, "raycache_vulkan_whitted");
    // --hybrid, --secondary and --pair-capacity are this tracer's own options, declared beside the shared ones.
    VulkanOptions vulkan;
    rcx::CommandLine command_line(program);
    command_line.section("Vulkan tracer");
    command_line.add_flag("--hybrid", vulkan.hybrid,
                          "primary visibility by a raster pass into a G-buffer, secondary rays in\n"
                          "compute (thesis Table 5.1); with --compare the uncached reference is\n"
                          "rendered the same way");
    command_line.add_option("--secondary", "S",
                            "trace the rays after the primary hits (reflected, refracted, shadow)\n"
                            "through the BVH (bvh) or the ray-space hierarchy of Roger et al. 2007\n"
                            "(rsh; needs --cache off); primary hits come from the BVH, or from the\n"
                            "raster pass with --hybrid " + rcx::shown_default(rcx::gpu::to_string(vulkan.secondary)),
                            [&vulkan](const std::string& text) {
                                if (text != "bvh" && text != "rsh")
                                    throw rcx::UsageError("--secondary: '" + text + "' is not bvh or rsh");
                                vulkan.secondary = text == "rsh" ? rcx::gpu::Secondary::rsh : rcx::gpu::Secondary::bvh;
                            });
    command_line.add_option("--pair-capacity", "N",
                            "rsh: pairs a stream holds, 64..16777216; a level that would exceed it\n"
                            "splits the primitives into batches " + rcx::shown_default(std::to_string(vulkan.pair_capacity)),
                            [&vulkan](const std::string& text) {
                                vulkan.pair_capacity =
                                    static_cast<std::uint32_t>(rcx::parse_int_value("--pair-capacity", text, 64, 1l << 24));
                            });
    command_line.add_option("--buffer-memory", "M",
                            "memory the shaders' buffers prefer (scene, cubes, frame buffer; not the\n"
                            "image, read back from host-cached memory): host (the first mappable type),\n"
                            "cached (host-cached) or device (device-local memory the host can map);\n"
                            "one type on lavapipe " + rcx::shown_default("host"),
                            [&vulkan](const std::string& text) {
                                if (text == "host") vulkan.buffer_memory = rcx::vk::BufferMemory::host;
                                else if (text == "cached") vulkan.buffer_memory = rcx::vk::BufferMemory::host_cached;
                                else if (text == "device") vulkan.buffer_memory = rcx::vk::BufferMemory::device_local;
                                else throw rcx::UsageError("--buffer-memory: '" + text + "' is not host, cached or device");
                            });
    command_line.add_flag("--shader-stats", vulkan.shader_statistics,
                          "print the driver's statistics of the tracing shader's compiled code\n"
                          "(registers, memory, instructions; where the device has\n"
                          "VK_KHR_pipeline_executable_properties), for the cached and the\n"
                          "uncached pipeline");
    command_line.ignore_threads("the Vulkan tracer's work is spread by the Vulkan driver");
    command_line.add_note("Vulkan tracer: --threads is ignored; the options marked (Embree tracer), --prefill,\n"
                          "--no-pyramid, --invalidate and caches on dynamic-N are refused; the CDCT relief search is\n"
                          "the linear walk. Shaders: RAYCACHE_VULKAN_WHITTED_SHADERS=<folder> overrides where the .spv\n"
                          "files are looked for.");
    return rcx::tracer_main(
        program, [&] { return command_line.parse(argc, argv); }, [&] { return command_line.help(); },
        [&vulkan](const rcx::Options& options) { return run(options, vulkan); });
}
