// raycache_vulkan_bench: the thesis's Table 5.1 (hybrid: primary visibility rasterised, secondary rays
// traced) and its all-rays-traced counterpart on the Vulkan compute tracer (examples/vulkan_whitted/), on
// whatever Vulkan device is found (lavapipe on a machine without a GPU). Writes table_5_1.csv and
// vulkan_tables.md into the output folder; make_results.py puts them into docs/RESULTS.md.
//
// Every speed-up is a ratio of medians of frames rendered interleaved in this one process (off, CCT, CDCT,
// ceiling, in the compute and the hybrid pipeline, in a rotating order), on the same camera, with warm
// caches (filled by rendering the same view twice first). The validation layer is off (it slows lavapipe
// down); the tests run with it on.
//
// Usage: raycache_vulkan_bench [--quick] [--out DIR] [--rounds N] [--ns LIST] [--size N]
// Exit 77 when there is no Vulkan device.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <rcx/vulkan.hpp>

#include "bench_common.hpp"
#include "gpu_tracer.hpp"
#include "rcx/image.hpp"
#include "rcx/scene.hpp"

namespace {

using rcx::CacheMode;
using rcx::bench::fmt;
using rcx::bench::median;
using rcx::bench::progress;

struct Config : rcx::bench::CommonOptions {
    Config() { rounds = 3; }
    int size = 1024;
    int face = 512;
};

// One way of rendering: a pipeline (compute or hybrid) and a cache mode, with its own tracer and cubes.
struct Variant {
    CacheMode mode;
    bool hybrid;
    std::unique_ptr<rcx::gpu::Tracer> tracer;
    std::vector<double> ms;
    rcx::gpu::FrameStats last_stats;
    rcx::Image last;
};

double render(Variant& v, const rcx::Camera& camera, int size) {
    v.last = v.tracer->render(camera, size, size, &v.last_stats);
    return v.last_stats.milliseconds; // the frame's submission, the end-of-frame passes (the cache's cost) in it
}

double hit_rate(const Variant& v) {
    return v.last_stats.lookups ? double(v.last_stats.hits) / double(v.last_stats.lookups) : 0.0;
}

void run(const Config& c, rcx::vk::Context& context) {
    const bool cdct = context.int64_atomics();
    const std::map<int, double> thesis_hybrid = {{1, 1.90}, {2, 1.98}, {4, 2.00}, {8, 2.24}, {16, 2.74}, {32, 3.50}};
    const std::map<int, double> thesis_conventional = {{1, 1.02}, {2, 1.07}, {4, 1.15}, {8, 1.32}, {16, 1.95}, {32, 2.68}};
    std::ofstream csv(c.out + "/table_5_1.csv");
    if (!csv) throw std::runtime_error("cannot write " + c.out + "/table_5_1.csv");
    csv << "n,pipeline,cct_face,cdct_face,off_ms,cct_ms,cdct_ms,ceiling_ms,cct_speedup,cdct_speedup,ceiling_speedup,"
           "cct_psnr,cdct_psnr,cct_hit_rate,cdct_hit_rate,thesis_cct_speedup\n";
    std::ostringstream md;
    md << "## Table 5.1: the Vulkan tracer on behind-N, hybrid and all rays traced\n\n"
       << "Device: " << context.device_name() << " (validation off). " << c.size << "x" << c.size << " pixels, "
       << c.face << "-texel faces asked for, every reflective sphere cached, warm caches (filled by rendering the "
       << "same view twice), recursion depth 5. *hybrid*: primary visibility by a raster pass into a G-buffer, "
       << "secondary rays in compute (thesis Table 5.1); *compute*: every ray traced in compute (thesis Table 5.2). "
       << "Speed-up = median ms with the cache off / median ms of the technique (end-frame pass included), "
       << c.rounds << " interleaved rounds of all eight variants. Ceiling: every cached secondary ray answered by "
       << "the environment colour. All cubes of a technique share one storage buffer, so where they exceed the "
       << "device's maxStorageBufferRange, or with their pending twin and doubtful bits the tracer's 256 MiB "
       << "budget, the face size is lowered (columns *faces*). The CDCT search is the "
       << "GLSL include's secant search (raycache_cdct_search, as in the Embree tracer).\n\n"
       << "| N | pipeline | faces CCT / CDCT | off ms | CCT ms | CDCT ms | ceiling ms | CCT speed-up | CDCT speed-up | "
          "ceiling | CCT hit rate | CDCT hit rate | CCT PSNR dB | CDCT PSNR dB | thesis CCT |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";

    for (int n : c.ns) {
        progress("Table 5.1 (Vulkan): behind-" + std::to_string(n));
        const rcx::Scene scene = rcx::make_scene("behind-" + std::to_string(n));
        const rcx::Camera camera = scene.camera_at(0);
        const std::string spirv = rcx::gpu::default_spirv_dir();
        std::vector<std::unique_ptr<Variant>> variants;
        for (const bool hybrid : {false, true})
            for (const CacheMode mode : {CacheMode::off, CacheMode::cct, CacheMode::cdct, CacheMode::ceiling}) {
                if (mode == CacheMode::cdct && !cdct) continue;
                rcx::gpu::TracerSettings s;
                s.mode = mode;
                s.face_size = c.face;
                s.hybrid = hybrid;
                s.min_hit_rate = 0.0f; // the thesis's caches: every cube answers every frame (no resting)
                auto v = std::make_unique<Variant>(Variant{mode, hybrid, std::make_unique<rcx::gpu::Tracer>(context, scene, spirv, s), {}, {}, {}});
                variants.push_back(std::move(v));
            }
        for (auto& v : variants)
            if (rcx::uses_caches(v->mode))
                for (int warm = 0; warm < 2; ++warm) render(*v, camera, c.size);
        for (int r = 0; r < c.rounds; ++r)
            for (std::size_t k = 0; k < variants.size(); ++k) {
                Variant& v = *variants[(k + r) % variants.size()];
                v.ms.push_back(render(v, camera, c.size));
            }

        for (const bool hybrid : {false, true}) {
            auto find = [&](CacheMode mode) -> Variant* {
                for (auto& v : variants)
                    if (v->mode == mode && v->hybrid == hybrid) return v.get();
                return nullptr;
            };
            Variant& off = *find(CacheMode::off);
            Variant& cct = *find(CacheMode::cct);
            Variant& ceiling = *find(CacheMode::ceiling);
            Variant* cd = find(CacheMode::cdct);
            const double off_ms = median(off.ms), cct_ms = median(cct.ms), ceil_ms = median(ceiling.ms);
            const double cdct_ms = cd ? median(cd->ms) : 0.0;
            const double cct_psnr = rcx::compare(cct.last, off.last).psnr_db;
            const double cdct_psnr = cd ? rcx::compare(cd->last, off.last).psnr_db : 0.0;
            const auto& thesis = hybrid ? thesis_hybrid : thesis_conventional;
            const auto t = thesis.find(n);
            const char* pipeline = hybrid ? "hybrid" : "compute";
            csv << n << "," << pipeline << "," << cct.tracer->face_size() << "," << (cd ? cd->tracer->face_size() : 0) << ","
                << off_ms << "," << cct_ms << "," << cdct_ms << "," << ceil_ms << "," << off_ms / cct_ms << ","
                << (cd ? off_ms / cdct_ms : 0.0) << "," << off_ms / ceil_ms << "," << cct_psnr << "," << cdct_psnr << ","
                << hit_rate(cct) << "," << (cd ? hit_rate(*cd) : 0.0) << ","
                << (t == thesis.end() ? std::string("") : fmt(t->second)) << "\n";
            md << "| " << n << " | " << pipeline << " | " << cct.tracer->face_size() << " / "
               << (cd ? std::to_string(cd->tracer->face_size()) : "-") << " | " << fmt(off_ms, 1) << " | " << fmt(cct_ms, 1)
               << " | " << (cd ? fmt(cdct_ms, 1) : "-") << " | " << fmt(ceil_ms, 1) << " | " << fmt(off_ms / cct_ms) << "x | "
               << (cd ? fmt(off_ms / cdct_ms) + "x" : "-") << " | " << fmt(off_ms / ceil_ms) << "x | "
               << fmt(100.0 * hit_rate(cct), 1) << "% | " << (cd ? fmt(100.0 * hit_rate(*cd), 1) + "%" : "-") << " | "
               << fmt(cct_psnr, 1) << " | " << (cd ? fmt(cdct_psnr, 1) : "-") << " | "
               << (t == thesis.end() ? std::string("-") : fmt(t->second) + "x (" + (hybrid ? "5.1" : "5.2") + ")") << " |\n";
            if (n == c.ns.back() && hybrid) {
                rcx::write_png(c.out + "/vulkan_behind-" + std::to_string(n) + "_hybrid_cct.png", cct.last);
                rcx::write_png(c.out + "/vulkan_behind-" + std::to_string(n) + "_hybrid_cct_diff.png",
                               rcx::difference_image(off.last, cct.last));
            }
        }
    }
    md << "\nImages of the last row (hybrid): `vulkan_behind-" << c.ns.back() << "_hybrid_cct.png` and its difference "
       << "image against the uncached frame, `vulkan_behind-" << c.ns.back() << "_hybrid_cct_diff.png`.\n\n";
    std::ofstream tables(c.out + "/vulkan_tables.md");
    tables << md.str();
    if (!tables) throw std::runtime_error("cannot write " + c.out + "/vulkan_tables.md");
    std::printf("%s", md.str().c_str());
}

} // namespace

int main(int argc, char** argv) {
    Config c;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (rcx::bench::parse_common_option(argc, argv, i, c)) continue;
        if (a == "--size" && i + 1 < argc) {
            c.size = std::max(1, std::atoi(argv[++i]));
        } else {
            std::fprintf(stderr, "usage: raycache_vulkan_bench [--quick] [--out DIR] [--rounds N] [--ns LIST] [--size N]\n");
            return a == "--help" ? 0 : 2;
        }
    }
    if (c.quick) {
        c.size = std::min(c.size, 96);
        c.face = 32;
    }
    if (c.ns.empty()) c.ns = c.quick ? std::vector<int>{0, 32} : std::vector<int>{0, 1, 2, 4, 8, 16, 32};
    std::unique_ptr<rcx::vk::Context> context;
    try {
        rcx::vk::ContextOptions options;
        options.validation = false;
        context = std::make_unique<rcx::vk::Context>(options);
    } catch (const rcx::vk::NoDeviceError& e) {
        std::fprintf(stderr, "raycache_vulkan_bench: skipped, no Vulkan device: %s\n", e.what());
        return 77;
    }
    try {
        std::filesystem::create_directories(c.out);
        const auto started = std::chrono::steady_clock::now();
        run(c, *context);
        std::fprintf(stderr, "[bench] Vulkan tables done in %.0f s in %s/vulkan_tables.md\n",
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), c.out.c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raycache_vulkan_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
