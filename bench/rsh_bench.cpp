// raycache_rsh_bench: the ray-space hierarchy (--secondary rsh) against the BVH (--secondary bvh, rebuilt
// every frame) in the Vulkan tracer on dynamic-N, hybrid (primary hits rasterised, the paper's setting),
// cache off, for a growing triangle count: the moving spheres tessellated at each level of --levels
// (rcx::tessellate_moving_spheres; level 0 keeps them analytic). Per scene: time to first picture (tracer
// set-up + first frame, each path in a fresh tracer), then frames 1..F with the objects moved each frame,
// the two paths interleaved frame by frame in this one process: BVH rebuild + upload and the frame for
// bvh; primitive upload and the frame for rsh, with the rsh frame split into hierarchy build, cone-sphere
// tests, compaction and final intersection (GPU timestamps summed over every trace of the frame),
// cone-sphere tests and pairs kept at the leaves. Writes rsh_frames.csv (one line per scene, path and
// frame) and rsh.md (how it was run); make_results.py (bench/rsh_results.py) makes the tables and plots.
//
// Usage: raycache_rsh_bench [--quick] [--out DIR] [--size S] [--frames F] [--spheres LIST] [--levels LIST]
// Exit 77 when there is no Vulkan device.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <rcx/vulkan.hpp>

#include "bench_common.hpp"
#include "gpu_tracer.hpp"
#include "rcx/scene.hpp"
#include "rcx/tessellate.hpp"

namespace {

using rcx::bench::fmt;
using rcx::bench::progress;

struct Config {
    std::string out = "docs/results";
    int size = 128, frames = 2;
    std::vector<int> spheres = {64};
    std::vector<int> levels = {0, 4, 8, 12, 16, 24}; // 3.7 k to 145 k triangles on dynamic-64
    bool quick = false;
};

double ms_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// One path's tracer on one scene, made and timed to its first picture.
struct Path {
    rcx::gpu::Secondary secondary;
    std::unique_ptr<rcx::gpu::Tracer> tracer;
    double first_picture_ms = 0.0; // shader compilation on first use included
};

Path first_picture(rcx::vk::Context& context, const rcx::Scene& scene, rcx::gpu::Secondary secondary, int size) {
    rcx::gpu::TracerSettings settings;
    settings.mode = rcx::CacheMode::off;
    settings.hybrid = true;
    settings.secondary = secondary;
    Path p{secondary, nullptr, 0.0};
    const auto start = std::chrono::steady_clock::now();
    p.tracer = std::make_unique<rcx::gpu::Tracer>(context, scene, rcx::gpu::default_spirv_dir(), settings);
    p.tracer->render(scene.camera_at(0), size, size);
    p.first_picture_ms = ms_since(start);
    return p;
}

void run(const Config& c, rcx::vk::Context& context) {
    std::ofstream csv(c.out + "/rsh_frames.csv");
    if (!csv) throw std::runtime_error("cannot write " + c.out + "/rsh_frames.csv");
    csv << "spheres,level,triangles,primitives,path,frame,ms,update_ms,build_ms,tests_ms,compaction_ms,final_ms,shade_ms,"
           "cone_sphere_tests,leaf_pairs,ray_slots,rays,batches,overflows,first_picture_ms\n";
    const auto started = std::chrono::steady_clock::now();
    for (int n : c.spheres)
        for (int level : c.levels) {
            const rcx::Scene base = rcx::make_scene("dynamic-" + std::to_string(n));
            const rcx::Scene scene = level > 0 ? rcx::tessellate_moving_spheres(base, level) : base;
            std::size_t triangles = 0;
            for (const rcx::Mesh& m : scene.meshes) triangles += m.triangles.size();
            const std::size_t prims = triangles + scene.spheres.size();
            progress("dynamic-" + std::to_string(n) + ", level " + std::to_string(level) + ": " + std::to_string(triangles) +
                     " triangles");
            std::vector<Path> paths;
            for (rcx::gpu::Secondary s : {rcx::gpu::Secondary::bvh, rcx::gpu::Secondary::rsh})
                paths.push_back(first_picture(context, scene, s, c.size));
            for (int f = 1; f <= c.frames; ++f) {
                const rcx::Scene moved = scene.at_frame(f);
                for (std::size_t k = 0; k < paths.size(); ++k) {
                    Path& p = paths[(k + static_cast<std::size_t>(f)) % paths.size()]; // alternate who goes first
                    const auto t0 = std::chrono::steady_clock::now();
                    p.tracer->set_scene(moved);
                    rcx::gpu::FrameStats s;
                    p.tracer->render(scene.camera_at(f), c.size, c.size, &s);
                    const double ms = ms_since(t0);
                    const rcx::gpu::RshStats& r = s.rsh.trace;
                    csv << n << "," << level << "," << triangles << "," << prims << "," << rcx::gpu::to_string(p.secondary) << ","
                        << f << "," << ms << "," << s.update_ms << "," << r.build_ms << "," << r.traverse_ms << ","
                        << r.compaction_ms << "," << r.final_ms << "," << s.rsh.shade_ms << "," << r.cone_sphere_tests << ","
                        << r.leaf_pairs << "," << r.rays << "," << (s.rsh.shadow_rays + s.rsh.secondary_rays) << ","
                        << r.batches << "," << r.overflows << "," << p.first_picture_ms << "\n";
                }
            }
            csv.flush();
        }
    std::ofstream md(c.out + "/rsh.md");
    md << "Machine: " << rcx::bench::machine_name() << ", " << std::thread::hardware_concurrency() << " hardware threads; "
       << "Vulkan device: " << context.device_name() << " (validation off). "
       << (c.quick ? "QUICK MODE: smoke test, not results. " : "") << "Generated by `raycache_rsh_bench --size " << c.size
       << " --frames " << c.frames << "` in " << fmt(ms_since(started) / 1000.0, 0) << " s: " << c.size << "x" << c.size
       << " pixels, hybrid (primary hits rasterised), cache off, " << c.frames << " moved frames after the first picture.\n";
    if (!md) throw std::runtime_error("cannot write " + c.out + "/rsh.md");
}

std::vector<int> ints(const std::string& text) { return rcx::bench::parse_list(text); }

} // namespace

int main(int argc, char** argv) {
    Config c;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has_value = i + 1 < argc;
        if (a == "--quick") {
            c.quick = true;
            c.size = 16;
            c.frames = 1;
            c.spheres = {8};
            c.levels = {0, 4};
        } else if (a == "--out" && has_value) c.out = argv[++i];
        else if (a == "--size" && has_value) c.size = std::max(8, std::atoi(argv[++i]));
        else if (a == "--frames" && has_value) c.frames = std::max(1, std::atoi(argv[++i]));
        else if (a == "--spheres" && has_value) c.spheres = ints(argv[++i]);
        else if (a == "--levels" && has_value) c.levels = ints(argv[++i]);
        else {
            std::fprintf(stderr, "usage: raycache_rsh_bench [--quick] [--out DIR] [--size S] [--frames F] [--spheres LIST] "
                                 "[--levels LIST]\n");
            return a == "--help" ? 0 : 2;
        }
    }
    try {
        std::filesystem::create_directories(c.out);
        rcx::vk::ContextOptions options;
        options.require_int64_atomics = true;
        options.validation = false;
        rcx::vk::Context context(options);
        progress("device " + context.device_name());
        run(c, context);
    } catch (const rcx::vk::NoDeviceError& e) {
        std::fprintf(stderr, "raycache_rsh_bench: %s\n", e.what());
        return 77;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raycache_rsh_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
