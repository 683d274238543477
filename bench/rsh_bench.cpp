// raycache_rsh_bench: the ray-space hierarchy (--secondary rsh) against the BVH (--secondary bvh, rebuilt
// every frame) in the Vulkan tracer on dynamic-N, hybrid (primary hits rasterised, the paper's setting),
// cache off. Per N: time to first picture (tracer set-up + first frame, each path in a fresh tracer), then
// frames 1..F with the objects moved each frame: BVH rebuild + upload and the frame for bvh; primitive
// upload and the frame for rsh, with the rsh frame split into hierarchy build, cone-sphere tests,
// compaction and final intersection (GPU timestamps summed over every trace of the frame), cone-sphere
// tests and pairs kept at the leaves per traced ray slot. One CSV line per (N, frame, path) on stdout.
//   raycache_rsh_bench [--size S] [--frames F] [--spheres N,N,...]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <rcx/vulkan.hpp>

#include "gpu_tracer.hpp"
#include "rcx/scene.hpp"

namespace {
double ms_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}
} // namespace

int main(int argc, char** argv) {
    int size = 128, frames = 3;
    std::vector<int> counts = {8, 64, 256};
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i], v = argv[i + 1];
        if (a == "--size") size = std::atoi(v.c_str());
        else if (a == "--frames") frames = std::atoi(v.c_str());
        else if (a == "--spheres") {
            counts.clear();
            std::stringstream ss(v);
            for (std::string x; std::getline(ss, x, ',');) counts.push_back(std::atoi(x.c_str()));
        }
    }
    rcx::vk::ContextOptions options;
    options.require_int64_atomics = true;
    options.validation = false;
    rcx::vk::Context context(options);
    std::fprintf(stderr, "device %s\n", context.device_name().c_str());
    std::printf("spheres,primitives,path,frame,ms,update_ms,build_ms,tests_ms,compaction_ms,final_ms,shade_ms,cone_sphere_tests,"
                "leaf_pairs,ray_slots,batches,first_picture_ms\n");
    const std::string spirv = rcx::gpu::default_spirv_dir();
    for (int n : counts) {
        const rcx::Scene scene = rcx::make_scene("dynamic-" + std::to_string(n));
        std::size_t prims = scene.spheres.size();
        for (const rcx::Mesh& m : scene.meshes) prims += m.triangles.size();
        for (rcx::gpu::Secondary path : {rcx::gpu::Secondary::bvh, rcx::gpu::Secondary::rsh}) {
            rcx::gpu::TracerSettings settings;
            settings.mode = rcx::CacheMode::off;
            settings.hybrid = true;
            settings.secondary = path;
            const auto start = std::chrono::steady_clock::now();
            rcx::gpu::Tracer tracer(context, scene, spirv, settings);
            rcx::gpu::FrameStats first;
            tracer.render(scene.camera_at(0), size, size, &first);
            const double first_ms = ms_since(start); // shader compilation on first use included
            for (int f = 1; f <= frames; ++f) {
                const auto t0 = std::chrono::steady_clock::now();
                tracer.set_scene(scene.at_frame(f));
                rcx::gpu::FrameStats s;
                tracer.render(scene.camera_at(f), size, size, &s);
                const double ms = ms_since(t0);
                const rcx::gpu::RshStats& r = s.rsh.trace;
                std::printf("%d,%zu,%s,%d,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%llu,%llu,%u,%u,%.1f\n", n, prims,
                            rcx::gpu::to_string(path), f, ms, s.update_ms, r.build_ms, r.traverse_ms, r.compaction_ms,
                            r.final_ms, s.rsh.shade_ms, static_cast<unsigned long long>(r.cone_sphere_tests),
                            static_cast<unsigned long long>(r.leaf_pairs), r.rays, r.batches, first_ms);
                std::fflush(stdout);
            }
        }
    }
    return 0;
}
