// raycache_embree_whitted: a Whitted ray tracer on Embree 3 whose reflective and refractive objects cache
// the rays leaving them in per-object caching cubes (Ruff 2013). Renders a scene's camera path frame by
// frame, the caches persisting across frames, and prints per frame: time, rays traced, cache hit rate and
// fill. With --compare it also renders every frame uncached and prints the speed-up and the image error.
//
//   raycache_embree_whitted --scene behind-32 --size 512x512 --cache cct --frames 10 --compare
//
// --save-cache FILE keeps the warm cubes after the last frame; --load-cache FILE starts the next run with them.
//
// This file is only the command line; the tracer is tracer.hpp/.cpp.
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "rcx/image.hpp"
#include "rcx/memory.hpp"
#include "rcx/options.hpp"
#include "rcx/progress.hpp"
#include "rcx/scene.hpp"
#include "rcx/scene_hash.hpp"
#include "rcx/tracer_main.hpp"
#include "tracer.hpp"


namespace {

using rcx::InputError; // bad input: message on stderr, exit status 2 (rcx::tracer_main)

struct FrameRecord {
    double cached_ms = 0.0;
    double uncached_ms = 0.0;
    double psnr_db = 0.0;
    double mean_error = 0.0;
    double max_error = 0.0;
    double hit_rate = -1.0;
    double kept = -1.0;        // dynamic scenes: fraction of the cached texels kept when objects moved
    double invalidate_ms = 0.0;
    std::uint64_t lookups = 0;
    std::array<std::uint64_t, raycache::miss_reason_count> misses_by{}; // by raycache::MissReason
    std::uint64_t filled_work = 0, work_reports = 0; // rays the leaving rays that filled texels took, and how many
};

raycache::embree::Invalidation invalidation_of(rcx::InvalidationPolicy p) {
    switch (p) {
    case rcx::InvalidationPolicy::none: return raycache::embree::Invalidation::none;
    case rcx::InvalidationPolicy::all: return raycache::embree::Invalidation::all;
    case rcx::InvalidationPolicy::exact: break;
    }
    return raycache::embree::Invalidation::exact;
}

std::string frame_path(const rcx::Options& o, const std::string& scene, const char* what, int frame) {
    char name[256];
    std::snprintf(name, sizeof name, "%s-%s-%04d.png", scene.c_str(), what, frame);
    return (std::filesystem::path(o.out) / name).string();
}

// What a cache file is saved for and checked against: the scene's fingerprint and name.
raycache::SceneIdentity cache_identity(const rcx::Scene& scene) { return raycache::SceneIdentity{rcx::scene_hash(scene), scene.name}; }

double milliseconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

std::string percent(double fraction) {
    if (fraction < 0.0) return "    -";
    char text[32];
    std::snprintf(text, sizeof text, "%5.1f%%", 100.0 * fraction);
    return text;
}

int run(const rcx::Options& o) {
    rcx::Scene scene;
    try {
        scene = rcx::scene_from_options(o);
    } catch (const std::exception& e) {
        throw InputError(e.what());
    }
    // Exact invalidation tests shadow rays against point lights (SceneChange::lights): a disc light's rays
    // would escape its cones.
    if (scene.dynamic() && scene.light.samples > 1 && rcx::uses_caches(o.cache) && o.invalidate == rcx::InvalidationPolicy::exact)
        throw InputError("--light-samples > 1 cannot be used with --invalidate exact on a dynamic scene: exact invalidation knows point lights only");
    try {
        rcx::check_memory({rcx::cpu_cubes(o.cache, scene.cached_object_count(), o.face_size, o.pyramid && !o.secant, scene.dynamic()), rcx::frame_images(o)});
    } catch (const std::runtime_error& e) {
        throw InputError(e.what());
    }

    rcx::embree::Tracer tracer(scene);
    rcx::embree::RenderSettings settings;
    settings.width = o.width;
    settings.height = o.height;
    settings.mode = o.cache;
    settings.threads = o.threads;

    std::unique_ptr<raycache::embree::SceneCache> caches;
    if (rcx::uses_caches(o.cache)) {
        raycache::ReliefParameters relief;
        relief.step = o.delta;
        relief.epsilon = o.epsilon;
        relief.max_steps = o.max_steps;
        relief.max_gap = o.max_gap > 0.0f ? o.max_gap : std::numeric_limits<float>::infinity();
        relief.search = o.secant ? raycache::DepthSearch::secant : raycache::DepthSearch::relief;
        relief.max_reads = o.max_reads;
        try {
            raycache::embree::SceneCacheSettings cache_settings;
            cache_settings.relief = relief;
            cache_settings.depth_pyramid = o.pyramid;
            cache_settings.adaptive.rays_per_texel = o.rays_per_texel;
            cache_settings.adaptive.still_rays_per_texel = o.still_rays_per_texel;
            cache_settings.adaptive.first_face_size = o.first_face_size;
            cache_settings.budget_bytes = static_cast<std::size_t>(o.budget_mib) << 20;
            cache_settings.filtered = o.filtered;
            cache_settings.trace_hits = o.trace_hits;
            if (o.min_hit_rate >= 0.0f) cache_settings.min_hit_rate = o.min_hit_rate;
            cache_settings.lookup_work = o.lookup_work;
            cache_settings.edge_threshold = o.edge_threshold;
            cache_settings.origin_drift = o.origin_drift;
            cache_settings.origin_parallax = o.origin_parallax;
            // Objects of a dynamic scene move from the first frame on: keep what the paths saw from the start,
            // so the first move keeps what it can (a static scene keeps no records unless something moves).
            if (scene.dynamic()) cache_settings.path_records = raycache::embree::PathRecords::always;
            caches = std::make_unique<raycache::embree::SceneCache>(
                o.cache == rcx::CacheMode::cct ? raycache::embree::Technique::cct : raycache::embree::Technique::cdct,
                cache_settings);
            tracer.attach_caches(*caches, o.face_size);
        } catch (const std::invalid_argument& e) {
            throw InputError(e.what());
        }
        settings.caches = caches.get();
        if (!o.load_cache.empty()) {
            const auto started = std::chrono::steady_clock::now();
            try {
                caches->load(o.load_cache, cache_identity(scene));
            } catch (const raycache::CacheFileError& e) {
                throw InputError(e.what());
            }
            if (!o.quiet)
                std::printf("loaded cache %s: %zu texels in %.0f ms\n", o.load_cache.c_str(), caches->statistics().valid_texels,
                            milliseconds_since(started));
        }
        if (o.prefill) {
            double ms = 0.0;
            const std::size_t stored = tracer.prefill(*caches, o.threads, &ms);
            rcx::embree::end_frame(*caches, o.threads);
            if (!o.quiet) std::printf("prefilled %zu texels in %.0f ms\n", stored, ms);
        }
    }

    const int frames = scene.path.frames;
    if (!o.quiet) {
        std::printf("scene %s: %zu spheres, %zu meshes, %d cached objects; %dx%d, depth %d, %s path, %d frames of %.2f deg\n",
                    scene.name.c_str(), scene.spheres.size(), scene.meshes.size(), scene.cached_object_count(),
                    o.width, o.height, scene.max_depth, rcx::to_string(scene.path.kind), frames,
                    static_cast<double>(scene.path.step_degrees));
        std::printf("cache %s", rcx::to_string(o.cache));
        if (rcx::uses_caches(o.cache)) {
            if (o.face_size > 0) std::printf(", faces %dx%d", o.face_size, o.face_size);
            else std::printf(", adaptive faces, budget %zu MiB", caches->budget().limit() >> 20);
        }
        if (o.cache == rcx::CacheMode::cdct)
            std::printf(", delta %g, epsilon %g, max steps %d", static_cast<double>(o.delta), static_cast<double>(o.epsilon), o.max_steps);
        if (scene.dynamic() && rcx::uses_caches(o.cache)) std::printf(", invalidate %s", rcx::to_string(o.invalidate));
        std::printf("; threads %s; PNGs in %s\n", o.threads > 0 ? std::to_string(o.threads).c_str() : "all", o.out.c_str());
        std::printf("frame         ms   rays traced  hit rate  filled%s%s\n", scene.dynamic() ? "    kept  inval ms" : "",
                    o.compare ? "    uncached ms  speed-up   PSNR dB  mean err  max err  differing" : "");
        std::fflush(stdout);
    }

    if (o.compare) {
        // One untimed uncached frame first: the process's first render pays for page faults and cold caches,
        // which would otherwise land on frame 0's cached render and understate its speed-up.
        rcx::embree::RenderSettings plain = settings;
        plain.mode = rcx::CacheMode::off;
        plain.caches = nullptr;
        tracer.render(scene.camera_at(0), plain);
    }
    rcx::ProgressBar bar("rendering", frames * (o.compare ? 2 : 1), rcx::progress_enabled(o.quiet, o.progress));
    std::vector<FrameRecord> records;
    std::size_t cache_bytes = 0;
    for (int f = 0; f < frames; ++f) {
        const rcx::Camera camera = scene.camera_at(f);
        FrameRecord r;
        if (scene.dynamic() && f > 0) { // objects move between frames; the caches learn what moved
            const raycache::embree::SceneChange change = tracer.move_to(scene.at_frame(f));
            if (settings.caches) {
                const raycache::embree::InvalidationStatistics inv = rcx::embree::scene_changed(*settings.caches, change, invalidation_of(o.invalidate), settings.threads);
                r.kept = inv.kept_fraction();
                r.invalidate_ms = inv.milliseconds;
            }
        }
        rcx::embree::FrameStats stats;
        settings.warm_up_stride = f == 0 ? o.warm_up : 0; // only the first frame has nothing to reuse
        const rcx::Image image = tracer.render(camera, settings, &stats);
        r.cached_ms = stats.milliseconds + r.invalidate_ms; // invalidating is part of a cached frame's cost
        bar.advance();
        double filled = -1.0;
        if (settings.caches) {
            const auto end_start = std::chrono::steady_clock::now();
            const raycache::embree::SceneCacheStatistics s = rcx::embree::end_frame(*settings.caches, o.threads);
            // Ending the frame is part of a cached frame's cost.
            r.cached_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - end_start).count();
            r.hit_rate = s.hit_rate();
            r.lookups = s.lookups;
            r.misses_by = s.misses_by;
            r.filled_work = s.filled_work;
            r.work_reports = s.work_reports;
            filled = s.valid_fraction();
            cache_bytes = s.allocated_bytes + s.pyramid_bytes;
        }
        rcx::write_png(frame_path(o, scene.name, rcx::to_string(o.cache), f), image);

        rcx::ImageDifference diff;
        if (o.compare) {
            rcx::embree::RenderSettings plain = settings;
            plain.mode = rcx::CacheMode::off;
            plain.caches = nullptr;
            rcx::embree::FrameStats plain_stats;
            const rcx::Image reference = tracer.render(camera, plain, &plain_stats);
            bar.advance();
            r.uncached_ms = plain_stats.milliseconds;
            diff = rcx::compare(image, reference);
            r.psnr_db = diff.psnr_db;
            r.mean_error = diff.mean_abs_error;
            r.max_error = diff.max_abs_error;
            rcx::write_png(frame_path(o, scene.name, "reference", f), reference);
            rcx::write_png(frame_path(o, scene.name, (std::string(rcx::to_string(o.cache)) + "-diff").c_str(), f),
                           rcx::difference_image(image, reference));
        }
        records.push_back(r);

        if (!o.quiet) {
            bar.clear();
            std::printf("%5d %10.2f %13llu   %s  %s", f, r.cached_ms, static_cast<unsigned long long>(stats.rays),
                        percent(r.hit_rate).c_str(), percent(filled).c_str());
            if (scene.dynamic()) std::printf("  %s %9.3f", percent(r.kept).c_str(), r.invalidate_ms);
            if (o.compare)
                std::printf(" %12.2f %8.2fx   %s  %8.5f %8.4f   %s", r.uncached_ms, r.uncached_ms / r.cached_ms,
                            rcx::psnr_text(r.psnr_db).c_str(), r.mean_error, r.max_error,
                            percent(static_cast<double>(diff.differing_pixels) / static_cast<double>(diff.pixels)).c_str());
            std::printf("\n");
            std::fflush(stdout);
        }
    }
    bar.finish();
    if (!o.save_cache.empty()) {
        const auto started = std::chrono::steady_clock::now();
        caches->save(o.save_cache, cache_identity(scene));
        if (!o.quiet)
            std::printf("saved cache %s: %zu texels, %.1f MiB in %.0f ms\n", o.save_cache.c_str(), caches->statistics().valid_texels,
                        static_cast<double>(std::filesystem::file_size(o.save_cache)) / (1024.0 * 1024.0), milliseconds_since(started));
    }

    // Summary: means over all frames and over the frames after the first (warm caches).
    double cached_all = 0, cached_warm = 0, plain_all = 0, plain_warm = 0, psnr_min = std::numeric_limits<double>::infinity();
    double psnr_sum = 0;
    int psnr_finite = 0;
    for (std::size_t i = 0; i < records.size(); ++i) {
        cached_all += records[i].cached_ms;
        plain_all += records[i].uncached_ms;
        if (i > 0) cached_warm += records[i].cached_ms, plain_warm += records[i].uncached_ms;
        psnr_min = std::min(psnr_min, records[i].psnr_db);
        if (std::isfinite(records[i].psnr_db)) psnr_sum += records[i].psnr_db, ++psnr_finite;
    }
    const double n = static_cast<double>(records.size());
    const double warm = n > 1 ? n - 1 : 1;
    std::printf("summary %s, %dx%d, cache %s: mean %.2f ms/frame (%.2f ms after the first)",
                scene.name.c_str(), o.width, o.height, rcx::to_string(o.cache), cached_all / n,
                records.size() > 1 ? cached_warm / warm : cached_all / n);
    if (cache_bytes) std::printf(", cubes %.1f MiB", static_cast<double>(cache_bytes) / (1024.0 * 1024.0));
    std::printf("\n");
    // Why the lookups of the frames after the first missed (all frames' when there is one): what to change.
    std::uint64_t lookups = 0;
    std::array<std::uint64_t, raycache::miss_reason_count> misses_by{};
    raycache::embree::SceneCacheStatistics work; // its filled_work and work_reports, summed
    for (std::size_t i = records.size() > 1 ? 1 : 0; i < records.size(); ++i) {
        lookups += records[i].lookups;
        for (std::size_t k = 0; k < misses_by.size(); ++k) misses_by[k] += records[i].misses_by[k];
        work.filled_work += records[i].filled_work;
        work.work_reports += records[i].work_reports;
    }
    if (lookups) {
        std::printf("summary misses, share of lookups:");
        for (std::size_t k = 0; k < misses_by.size(); ++k)
            std::printf("%s %s %.1f%%", k ? "," : "", raycache::to_string(static_cast<raycache::MissReason>(k)),
                        100.0 * static_cast<double>(misses_by[k]) / static_cast<double>(lookups));
        std::printf(" (empty: not stored or dropped; fresh: stored this frame; doubtful: a colour edge;"
                    " origin: left too far from the tile's origins; search: no consistent CDCT crossing;"
                    " outside: not answerable; resting: a cube that did not pay, traced)\n");
    }
    // What a leaving ray that filled a texel cost, which sets how many hits a cube needs to pay (resting cubes).
    if (work.work_reports)
        std::printf("summary a leaving ray that filled a texel took %.2f rays (intersections and shadow rays), mean over %llu\n",
                    work.mean_filled_work(), static_cast<unsigned long long>(work.work_reports));
    if (o.compare) {
        const double speedup = records.size() > 1 ? plain_warm / cached_warm : plain_all / cached_all;
        std::printf("summary uncached: mean %.2f ms/frame (%.2f ms after the first); speed-up %.2fx after the first frame;"
                    " PSNR min %s dB, mean of finite %s dB (%d of %zu frames identical)\n",
                    plain_all / n, records.size() > 1 ? plain_warm / warm : plain_all / n, speedup,
                    rcx::psnr_text(psnr_min).c_str(), psnr_finite ? rcx::psnr_text(psnr_sum / psnr_finite).c_str() : "     -",
                    static_cast<int>(records.size()) - psnr_finite, records.size());
    }
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    const std::string program = rcx::program_name(argc, argv, "raycache_embree_whitted");
    return rcx::tracer_main(
        program, [&] { return rcx::parse_options(argc, argv); }, [&] { return rcx::help_text(program); },
        [](const rcx::Options& options) { return run(options); });
}
