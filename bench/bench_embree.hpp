// bench_embree.hpp: what the benchmarks on the Embree tracer share (raycache_bench, raycache_walkthrough_bench):
// the CDCT settings that stand for "the CDCT", a Variant (one way of rendering, with its own caches and its
// measurements), rendering one frame of a variant, and rendering every variant once in a rotating order.
#pragma once

#include <chrono>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tracer.hpp"

namespace rcx::bench {

// The CDCT settings our results use wherever one CDCT stands for all: the thesis's (0.2, 0.02), the depth
// pyramid (chosen per variant) and crossings more than 0.5 behind the cached surface rejected.
inline const raycache::ReliefParameters our_relief{0.2f, 0.02f, 1024, 100.0f, 0.5f};

// A SceneCache of `technique` for a scene whose objects move from the first frame on: the tracer's search,
// and path records kept from the start (as the tracer keeps them for dynamic scenes). Cubes never rest, so
// the invalidation policies' hit rates and PSNR differ by what they invalidated alone.
inline std::unique_ptr<raycache::embree::SceneCache> dynamic_scene_cache(raycache::embree::Technique technique) {
    raycache::embree::SceneCacheSettings settings;
    settings.relief = our_relief;
    settings.path_records = raycache::embree::PathRecords::always;
    settings.min_hit_rate = 0.0f;
    return std::make_unique<raycache::embree::SceneCache>(technique, settings);
}

// behind-32 orbited 1 degree a frame while the first of the 32 spheres behind the camera circles (radius
// 0.2, 3 degrees a frame) and everything else stands still: one moved object among behind-32-sized caches.
inline Scene behind_with_one_mover() {
    Scene behind = make_scene("behind-32");
    behind.path.kind = CameraPath::Kind::orbit;
    behind.path.step_degrees = 1.0f;
    Motion m;
    m.index = 1;
    m.circle_radius = 0.2f;
    m.degrees_per_frame = 3.0f;
    behind.motions.push_back(m);
    return behind;
}

// One way of rendering a frame: a mode and, for the cached modes, its own caches.
struct Variant {
    std::string label;
    CacheMode mode = CacheMode::off;
    std::unique_ptr<raycache::embree::SceneCache> caches;
    std::vector<double> ms;                            // every timed frame
    raycache::embree::SceneCacheStatistics last_stats; // the caches' counters of the last frame
    rcx::embree::FrameStats last_frame;                // the tracer's counters of the last frame
    std::uint64_t texels_read = 0, lookups = 0, max_texels = 0; // summed over the timed frames
    Image last;
};

// Renders one frame of a variant; ends the caches' frame and keeps its statistics.
inline Image render(const rcx::embree::Tracer& tracer, Variant& v, const Camera& camera, int width, int height,
                    double* ms = nullptr) {
    rcx::embree::RenderSettings settings;
    settings.width = width;
    settings.height = height;
    settings.mode = v.mode;
    settings.caches = v.caches.get();
    Image image = tracer.render(camera, settings, &v.last_frame);
    double frame_ms = v.last_frame.milliseconds;
    if (v.caches) {
        // Ending the frame (stores made visible, cube sizes, confidence marks) is part of a cached frame's cost.
        const auto start = std::chrono::steady_clock::now();
        v.last_stats = rcx::embree::end_frame(*v.caches);
        frame_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    }
    if (ms) *ms = frame_ms;
    return image;
}

// Renders and times every variant once on `camera`, starting with variants[first % size] and going round,
// so that with first = 0, 1, 2, ... no variant always runs first. Keeps each variant's image and adds its
// time and CDCT texel counters to its totals.
inline void render_round(const rcx::embree::Tracer& tracer, const std::vector<Variant*>& variants, const Camera& camera,
                         int width, int height, std::size_t first) {
    for (std::size_t k = 0; k < variants.size(); ++k) {
        Variant& v = *variants[(k + first) % variants.size()];
        double ms = 0.0;
        v.last = render(tracer, v, camera, width, height, &ms);
        v.ms.push_back(ms);
        v.texels_read += v.last_stats.texels_read;
        v.lookups += v.last_stats.lookups;
        v.max_texels = std::max(v.max_texels, v.last_stats.max_texels_read);
    }
}

} // namespace rcx::bench
