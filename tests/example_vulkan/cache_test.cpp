// The Vulkan tracer with its caches on, against its own uncached frames and against the Embree tracer's
// caches: a cold frame equals the uncached frame bit for bit (stores become visible only after the
// end-frame pass), a second frame from the same viewpoint is answered by the cubes (hit rate) and stays
// close to the uncached frame (PSNR floors set below what was measured), the warm CCT and CDCT frames
// (CDCT: the secant search, the default, and the relief walk) are close to the Embree tracer's warm
// frames made with the same settings (the two implement the same store rule and, in C++ and GLSL, the
// same searches), and two tracers fed the same frames give the same pixels (no dependence on the
// driver's thread timing); with the confidence test on, the warm frames still match the Embree tracer's made
// with the same threshold. Adaptive face sizes: the cold frame is still the uncached one, every cube shrinks
// after it and keeps answering, two tracers agree; a byte budget holds them. Cubes saved to a cache file and
// loaded into a fresh tracer make the saving tracer's next frame. No validation error.
// Exit 77 (CTest: skipped) only when there is no Vulkan device.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

#include <raycache/embree/scene_cache.hpp>
#include <rcx/vulkan.hpp>

#include "gpu_tracer.hpp"
#include "rcx/image.hpp"
#include "simd_groups.hpp"
#include "rcx/options.hpp"
#include "rcx/scene.hpp"
#include "tracer.hpp"

namespace {

int failures = 0;

void check(bool ok, const std::string& what) {
    std::printf("%s %s\n", ok ? "ok  " : "FAIL", what.c_str());
    if (!ok) ++failures;
}

std::string format(const char* pattern, double a, double b = 0.0) {
    char text[160];
    std::snprintf(text, sizeof text, pattern, a, b);
    return text;
}

// The Embree tracer's caches with the GPU tracer's settings. CCT: nearest texels, as the GPU tracer reads
// them (it has no filtered lookups yet). CDCT: the same search and parameters; the relief walk without a
// pyramid (GLSL has none).
raycache::embree::SceneCacheSettings embree_settings(const rcx::gpu::TracerSettings& gpu) {
    raycache::embree::SceneCacheSettings same; // stated: the comparison depends on it
    same.filtered = false;
    same.edge_threshold = gpu.edge_threshold; // the confidence test: the GPU's mark pass marks as C++ does
    same.origin_drift = gpu.origin_drift;     // the origin test (CCT): the GPU's tiles keep origins as C++'s do
    same.origin_parallax = gpu.origin_parallax;
    same.depth_pyramid = false;
    same.relief.step = gpu.delta;
    same.relief.epsilon = gpu.epsilon;
    same.relief.max_steps = gpu.max_steps;
    same.relief.max_gap = gpu.max_gap > 0.0f ? gpu.max_gap : std::numeric_limits<float>::infinity();
    same.relief.search = gpu.secant ? raycache::DepthSearch::secant : raycache::DepthSearch::relief;
    same.relief.max_reads = gpu.max_reads;
    if (gpu.min_hit_rate >= 0.0f) same.min_hit_rate = gpu.min_hit_rate; // resting cubes: the same rule
    return same;
}

raycache::embree::Technique technique_of(rcx::CacheMode mode) {
    return mode == rcx::CacheMode::cct ? raycache::embree::Technique::cct : raycache::embree::Technique::cdct;
}

// The Embree tracer's warm frame: one frame to fill the cubes, a second from the same camera, with the GPU
// tracer's settings; or, warm_up_stride > 1, a single frame with a warm-up pass over every stride-th pixel.
rcx::Image embree_warm(const rcx::Scene& scene, int size, const rcx::gpu::TracerSettings& gpu, int warm_up_stride = 0) {
    const rcx::embree::Tracer tracer(scene);
    raycache::embree::SceneCache caches(technique_of(gpu.mode), embree_settings(gpu));
    tracer.attach_caches(caches, gpu.face_size);
    rcx::embree::RenderSettings s;
    s.width = s.height = size;
    s.mode = gpu.mode;
    s.caches = &caches;
    if (warm_up_stride > 1) {
        s.warm_up_stride = warm_up_stride;
        return tracer.render(scene.camera, s);
    }
    tracer.render(scene.camera, s);
    caches.begin_frame();
    return tracer.render(scene.camera, s);
}

// Floors, each set below what was measured at 64 x 64, CCT faces of 128 and CDCT faces of 64 texels:
struct Case {
    const char* scene;
    double cct_min_psnr;           // warm CCT frame against the uncached frame, dB
    double cct_min_embree_psnr;    // warm CCT frame against the Embree tracer's warm CCT frame, dB
    double cdct_min_hit_rate;      // warm CDCT frame (filled by one rendered frame, linear search)
    double cdct_min_psnr;          // dB
    double secant_min_hit_rate;    // warm CDCT frame, secant search (the default)
    double secant_min_psnr;        // dB
    double cdct_min_embree_psnr;   // warm CDCT frames (either search) against the Embree tracer's, dB
};

void run_case(rcx::vk::Context& context, const Case& c) {
    const int size = 64;
    const rcx::Scene scene = rcx::make_scene(c.scene);
    const std::string spirv = rcx::gpu::default_spirv_dir();
    rcx::gpu::TracerSettings plain;
    rcx::gpu::Tracer reference(context, scene, spirv, plain);
    rcx::gpu::FrameStats uncached_stats;
    const rcx::Image uncached = reference.render(scene.camera, size, size, &uncached_stats);
    check(uncached_stats.end_frame_milliseconds == 0.0, std::string(c.scene) + ": an uncached frame has no end-of-frame passes to time");
    check(uncached_stats.warps.with_lookups == 0, std::string(c.scene) + ": an uncached frame counts no SIMD groups with lookups");

    // CCT; CDCT with the relief walk; CDCT with the secant search.
    for (int run = 0; run < 3; ++run) {
        const rcx::CacheMode mode = run == 0 ? rcx::CacheMode::cct : rcx::CacheMode::cdct;
        const bool secant = run == 2;
        const std::string name = std::string(c.scene) + " " + rcx::to_string(mode) +
                                 (mode == rcx::CacheMode::cdct ? (secant ? " secant" : " relief") : "");
        rcx::gpu::TracerSettings settings;
        settings.mode = mode;
        settings.secant = secant;
        settings.face_size = mode == rcx::CacheMode::cct ? 128 : 64;
        settings.edge_threshold = -1.0f; // the floors below were measured without the confidence test
        rcx::gpu::Tracer a(context, scene, spirv, settings), b(context, scene, spirv, settings);
        rcx::gpu::FrameStats cold_stats, warm_stats, twin_stats;
        const rcx::Image cold = a.render(scene.camera, size, size, &cold_stats);
        const std::uint64_t submissions_before = context.submissions();
        const rcx::Image warm = a.render(scene.camera, size, size, &warm_stats);
        const std::uint64_t submissions = context.submissions() - submissions_before;
        // The end-of-frame passes are recorded after the tracing dispatch, so the host waits once a frame.
        check(submissions == 1, name + format(": a frame takes one submission (%.0f)", double(submissions)));
        // GPU times lie within the host's wait for the submission; with timestamps (lavapipe has them) the
        // end-of-frame passes take some, and the uncached reference's, which has none, reads 0.
        check(warm_stats.gpu_trace_milliseconds + warm_stats.end_frame_milliseconds <= warm_stats.milliseconds,
              name + format(": GPU times %.3f ms within the submission's %.3f ms",
                            warm_stats.gpu_trace_milliseconds + warm_stats.end_frame_milliseconds, warm_stats.milliseconds));
        if (warm_stats.gpu_trace_milliseconds > 0.0)
            check(warm_stats.end_frame_milliseconds > 0.0, name + ": timestamps time the end-of-frame passes");
        b.render(scene.camera, size, size);
        const rcx::Image twin = b.render(scene.camera, size, size, &twin_stats);

        const rcx::ImageDifference cold_difference = rcx::compare(cold, uncached);
        check(rcx::bit_identical(cold, uncached), name + ": the cold frame equals the uncached frame bit for bit" +
                                                 format(" (%.0f pixels differ, PSNR %.2f dB)", double(cold_difference.differing_pixels), cold_difference.psnr_db));
        check(cold_stats.lookups > 0 && cold_stats.hits == 0, name + ": the cold frame looked up and hit nothing");
        // Each pixel's alpha says what its lookups met: 64 x 64 pixels are 128 groups of 8 x 4.
        check(cold_stats.warps.with_lookups > 0 && cold_stats.warps.with_lookups <= 128 && cold_stats.warps.all_hit == 0,
              name + format(": the cold frame's %.0f groups with lookups had a miss each (%.0f all hit)",
                            double(cold_stats.warps.with_lookups), double(cold_stats.warps.all_hit)));
        // The same camera sends leaving rays from the same pixels; hits come in groups too (the CCT's warm
        // frame hits over 95% of its lookups).
        check(warm_stats.warps.with_lookups == cold_stats.warps.with_lookups && warm_stats.warps.all_hit <= warm_stats.warps.with_lookups &&
                  (mode != rcx::CacheMode::cct || warm_stats.warps.all_hit > 0),
              name + format(": the warm frame looks up in the same groups, %.0f of them hit alone", double(warm_stats.warps.all_hit)));
        const double hit_rate = warm_stats.lookups > 0 ? double(warm_stats.hits) / double(warm_stats.lookups) : 0.0;
        const double psnr = rcx::compare(warm, uncached).psnr_db;
        if (mode == rcx::CacheMode::cct) {
            check(hit_rate > 0.95, name + format(": warm hit rate %.4f > 0.95", hit_rate));
            check(psnr >= c.cct_min_psnr, name + format(": warm PSNR %.2f dB >= %.0f dB", psnr, c.cct_min_psnr));
            const double embree_psnr = rcx::compare(warm, embree_warm(scene, size, settings)).psnr_db;
            check(embree_psnr >= c.cct_min_embree_psnr,
                  name + format(": warm frame against the Embree tracer's warm frame %.2f dB >= %.0f dB", embree_psnr, c.cct_min_embree_psnr));
        } else {
            const double min_hit_rate = secant ? c.secant_min_hit_rate : c.cdct_min_hit_rate;
            const double min_psnr = secant ? c.secant_min_psnr : c.cdct_min_psnr;
            check(hit_rate >= min_hit_rate, name + format(": warm hit rate %.4f >= %.2f", hit_rate, min_hit_rate));
            check(psnr >= min_psnr, name + format(": warm PSNR %.2f dB >= %.0f dB", psnr, min_psnr));
            const double embree_psnr = rcx::compare(warm, embree_warm(scene, size, settings)).psnr_db;
            check(embree_psnr >= c.cdct_min_embree_psnr,
                  name + format(": warm frame against the Embree tracer's warm frame %.2f dB >= %.0f dB", embree_psnr, c.cdct_min_embree_psnr));
        }
        check(rcx::bit_identical(warm, twin) && warm_stats.hits == twin_stats.hits,
              name + ": two tracers fed the same frames give the same warm pixels and hits");
        // With the confidence test (the tracers' default threshold) the warm frame still matches the Embree
        // tracer's made with the same threshold: the GPU's mark pass marks the texels C++ marks.
        rcx::gpu::TracerSettings marked = settings;
        marked.edge_threshold = rcx::gpu::TracerSettings{}.edge_threshold;
        rcx::gpu::Tracer m(context, scene, spirv, marked);
        m.render(scene.camera, size, size);
        const double marked_psnr = rcx::compare(m.render(scene.camera, size, size), embree_warm(scene, size, marked)).psnr_db;
        const double min_marked = mode == rcx::CacheMode::cct ? c.cct_min_embree_psnr : c.cdct_min_embree_psnr;
        check(marked_psnr >= min_marked,
              name + format(": with --edge-threshold 0.1, warm frame against the Embree tracer's %.2f dB >= %.0f dB", marked_psnr, min_marked));
        if (!rcx::bit_identical(cold, uncached) || psnr < 10.0) {
            rcx::write_png("vulkan-cache-" + std::string(c.scene) + "-" + rcx::to_string(mode) +
                               (secant ? "-secant" : "") + "-warm.png", warm);
            rcx::write_png("vulkan-cache-" + std::string(c.scene) + "-uncached.png", uncached);
        }
    }
}

// Adaptive face sizes (raycache/gpu_adaptive.hpp) along an orbit: the cubes start at 256-texel faces; the
// cold frame still equals the uncached frame bit for bit; after it, each cube that rays reached takes a
// smaller size (a 96 x 96 image sends a few thousand rays to a mirror: far fewer than 6 * 256^2 texels) and
// keeps the texels resampled into it, so the next frame hits; two tracers choose the same sizes and pixels.
void run_adaptive_case(rcx::vk::Context& context, const char* scene_name, rcx::CacheMode mode, double min_hit_rate,
                       double min_psnr) {
    const int size = 96;
    const rcx::Scene scene = rcx::make_scene(scene_name);
    const std::string spirv = rcx::gpu::default_spirv_dir();
    rcx::gpu::Tracer reference(context, scene, spirv, rcx::gpu::TracerSettings{});
    rcx::gpu::TracerSettings settings;
    settings.mode = mode;
    settings.adaptive = true;
    settings.face_size = settings.adaptive_resolution.first_face_size;
    settings.min_hit_rate = 0.0f; // every cube answers: the hit rates below are the cubes' own (run_resting_case rests them)
    const std::string name = std::string(scene_name) + " " + rcx::to_string(mode) + " adaptive";
    rcx::gpu::Tracer a(context, scene, spirv, settings), b(context, scene, spirv, settings);
    const std::vector<int> first = a.face_sizes();
    check(!first.empty() && std::all_of(first.begin(), first.end(), [](int n) { return n == 256; }),
          name + ": every cube starts at 256-texel faces");
    const double start_bytes = static_cast<double>(a.cube_bytes());
    double psnr_min = std::numeric_limits<double>::infinity(), hit_min = 1.0;
    for (int f = 0; f < 4; ++f) {
        const rcx::Camera camera = scene.camera_at(f);
        rcx::gpu::FrameStats stats, twin_stats;
        const rcx::Image image = a.render(camera, size, size, &stats);
        const rcx::Image twin = b.render(camera, size, size, &twin_stats);
        const rcx::Image uncached = reference.render(camera, size, size);
        check(rcx::bit_identical(image, twin) && a.face_sizes() == b.face_sizes(),
              name + format(": frame %.0f: two tracers give the same pixels and face sizes", f));
        if (f == 0) {
            check(rcx::bit_identical(image, uncached), name + ": the cold frame equals the uncached frame bit for bit");
            // Every cube shrinks: the mirror its rays reached to their size, the ones no ray reached to 8.
            const std::vector<int> sized = a.face_sizes();
            std::size_t smaller = 0, waiting = 0;
            for (int n : sized) smaller += n < 256, waiting += n == 8;
            check(stats.resized_cubes == sized.size() && smaller == sized.size() && waiting > 0 && waiting < sized.size(),
                  name + format(": after the cold frame every cube shrank, %.0f of them unreached to 8 texels (%.0f reported resized)",
                                double(waiting), double(stats.resized_cubes)));
            check(a.cube_bytes() < start_bytes / 8,
                  name + format(": cubes %.2f MiB, from %.2f", a.cube_bytes() / 1048576.0, start_bytes / 1048576.0));
            continue;
        }
        hit_min = std::min(hit_min, stats.lookups ? double(stats.hits) / double(stats.lookups) : 0.0);
        psnr_min = std::min(psnr_min, rcx::compare(image, uncached).psnr_db);
    }
    check(hit_min >= min_hit_rate, name + format(": frames 1-3 hit at least %.3f of their lookups (>= %.2f)", hit_min, min_hit_rate));
    check(psnr_min >= min_psnr, name + format(": frames 1-3 at least %.2f dB against the uncached frames (>= %.0f)", psnr_min, min_psnr));
}

// A single image with a warm-up pass over every 4th pixel (render's warm_up_stride): the warm-up's stores are
// published (and tested for edges) before the full pass, so the one frame hits; the image is the Embree
// tracer's single image with the same warm-up and settings (the two share the store rule, the end of a frame
// and the confidence test); two tracers agree; adaptive cubes resized to the warm-up's rays answer more of the
// full pass than cubes left at their first size. Without a warm-up nothing hits.
void run_warm_up_case(rcx::vk::Context& context, const char* scene_name, rcx::CacheMode mode, int face_size,
                      double min_hit_rate, double min_psnr, double min_embree_psnr) {
    const int size = 64, stride = 4;
    const rcx::Scene scene = rcx::make_scene(scene_name);
    const std::string spirv = rcx::gpu::default_spirv_dir();
    rcx::gpu::Tracer reference(context, scene, spirv, rcx::gpu::TracerSettings{});
    const rcx::Image uncached = reference.render(scene.camera, size, size);
    rcx::gpu::TracerSettings settings;
    settings.mode = mode;
    settings.face_size = face_size;
    const std::string name = std::string(scene_name) + " " + rcx::to_string(mode) + " warm-up 4";
    rcx::gpu::Tracer a(context, scene, spirv, settings), b(context, scene, spirv, settings);
    rcx::gpu::FrameStats stats, twin_stats;
    const std::uint64_t submissions_before = context.submissions();
    const rcx::Image image = a.render(scene.camera, size, size, &stats, stride);
    const std::uint64_t submissions = context.submissions() - submissions_before;
    check(submissions == 2, name + format(": the warm-up and the full pass take one submission each (%.0f)", double(submissions)));
    const rcx::Image twin = b.render(scene.camera, size, size, &twin_stats, stride);
    check(stats.warm_up_stored_texels > 0 && stats.warm_up_milliseconds > 0.0,
          name + format(": the warm-up pass stored %.0f texels", double(stats.warm_up_stored_texels)));
    const double hit_rate = stats.lookups ? double(stats.hits) / double(stats.lookups) : 0.0;
    check(hit_rate >= min_hit_rate, name + format(": the single frame hits %.3f of its lookups (>= %.3f)", hit_rate, min_hit_rate));
    const double psnr = rcx::compare(image, uncached).psnr_db;
    check(psnr >= min_psnr, name + format(": %.2f dB against the uncached frame (>= %.0f)", psnr, min_psnr));
    const double embree_psnr = rcx::compare(image, embree_warm(scene, size, settings, stride)).psnr_db;
    check(embree_psnr >= min_embree_psnr,
          name + format(": against the Embree tracer's single image with the same warm-up %.2f dB >= %.0f dB", embree_psnr, min_embree_psnr));
    check(rcx::bit_identical(image, twin) && stats.hits == twin_stats.hits, name + ": two tracers give the same pixels and hits");

    rcx::gpu::Tracer cold(context, scene, spirv, settings);
    rcx::gpu::FrameStats cold_stats;
    check(rcx::bit_identical(cold.render(scene.camera, size, size, &cold_stats, 0), uncached) && cold_stats.hits == 0 &&
              cold_stats.warm_up_stored_texels == 0,
          name + ": stride 0, no warm-up: the frame is the uncached one and hits nothing");
    // Every leaving ray looks up once, hit or miss, in the pass that traces its pixel: the warm-up's pixels
    // are final, so the full pass traces the others, and the two passes' counts add up to the cold frame's
    // (the frame buffer was started again between the passes, so neither counts the other's).
    check(stats.warm_up_lookups > 0 && stats.lookups < cold_stats.lookups && stats.lookups + stats.warm_up_lookups == cold_stats.lookups,
          name + format(": the full pass counts its own %.0f lookups and the warm-up ", double(stats.lookups)) +
              format("%.0f (cold frame: %.0f)", double(stats.warm_up_lookups), double(cold_stats.lookups)));

    // Hybrid: the warm-up records the raster pass, the full pass reads the same G-buffer.
    rcx::gpu::TracerSettings hybrid = settings;
    hybrid.hybrid = true;
    rcx::gpu::Tracer h(context, scene, spirv, hybrid), h_cold(context, scene, spirv, hybrid);
    rcx::gpu::FrameStats hybrid_stats, hybrid_cold;
    const rcx::Image hybrid_image = h.render(scene.camera, size, size, &hybrid_stats, stride);
    h_cold.render(scene.camera, size, size, &hybrid_cold, 0);
    const double hybrid_psnr = rcx::compare(hybrid_image, image).psnr_db;
    check(hybrid_psnr >= 40.0 && hybrid_stats.hits > 0 && hybrid_stats.lookups + hybrid_stats.warm_up_lookups == hybrid_cold.lookups,
          name + format(": hybrid, %.2f dB against compute (>= 40), %.0f hits", hybrid_psnr, double(hybrid_stats.hits)));

    // Adaptive cubes from 64-texel faces: resized to the warm-up's rays (tens a mirror), their texels
    // answer more of the full pass's rays than 64-texel faces do (measured: CCT 0.062 against 0.000, CDCT 0.017
    // against 0.000; the same rates and PSNR as fixed 16-texel faces; at 64 texels a face a warm-up texel answers
    // little more than the ray that filled it, whose pixel the full pass does not trace again).
    rcx::gpu::TracerSettings adaptive = settings, first = settings;
    adaptive.adaptive = true;
    adaptive.adaptive_resolution.first_face_size = first.face_size = 64;
    rcx::gpu::Tracer c(context, scene, spirv, adaptive), d(context, scene, spirv, adaptive), e(context, scene, spirv, first);
    rcx::gpu::FrameStats adaptive_stats, adaptive_twin, first_stats;
    const rcx::Image adaptive_image = c.render(scene.camera, size, size, &adaptive_stats, stride);
    const rcx::Image adaptive_twin_image = d.render(scene.camera, size, size, &adaptive_twin, stride);
    e.render(scene.camera, size, size, &first_stats, stride);
    const double adaptive_rate = adaptive_stats.lookups ? double(adaptive_stats.hits) / double(adaptive_stats.lookups) : 0.0;
    const double first_rate = first_stats.lookups ? double(first_stats.hits) / double(first_stats.lookups) : 0.0;
    check(adaptive_stats.resized_cubes > 0 && adaptive_rate >= 1.5 * first_rate && adaptive_rate > min_hit_rate,
          name + format(": adaptive cubes resized to the warm-up's rays hit %.3f, fixed 64-texel faces %.3f", adaptive_rate, first_rate));
    check(rcx::bit_identical(adaptive_image, adaptive_twin_image) && c.face_sizes() == d.face_sizes(),
          name + ": two adaptive tracers give the same pixels and face sizes");
    const double adaptive_psnr = rcx::compare(adaptive_image, uncached).psnr_db;
    check(adaptive_psnr >= min_psnr - 6.0, name + format(": adaptive %.2f dB against the uncached frame (>= %.0f)", adaptive_psnr, min_psnr - 6.0));
}

} // namespace

// A byte budget (TracerSettings::budget_bytes, raycache::gpu_texel_bytes_within): behind-8's 9 cubes in
// 1 MiB with the CCT and its origin test hold at most 114,912 texels (texels, pending, doubtful bits and
// origin records at one byte a texel), so 256-texel first faces are lowered to 46 (9 x 6 x 46^2 = 114,264
// texels; 47 would take 119,286), and after every frame the adaptive cubes stay within it; a budget too
// small for a texel a cube is refused.
void run_budget_case(rcx::vk::Context& context) {
    const int size = 96;
    const rcx::Scene scene = rcx::make_scene("behind-8");
    const std::string spirv = rcx::gpu::default_spirv_dir();
    rcx::gpu::TracerSettings settings;
    settings.mode = rcx::CacheMode::cct;
    settings.adaptive = true;
    settings.face_size = settings.adaptive_resolution.first_face_size;
    settings.budget_bytes = 1u << 20;
    rcx::gpu::Tracer a(context, scene, spirv, settings);
    const std::vector<int> first = a.face_sizes();
    check(first.size() == 9 && std::all_of(first.begin(), first.end(), [](int n) { return n == 46; }),
          format("budget 1 MiB: behind-8's 9 cubes start at 46-texel faces (first %.0f)", first.empty() ? 0.0 : first[0]));
    bool within = true;
    for (int f = 0; f < 3; ++f) {
        a.render(scene.camera_at(f), size, size);
        std::uint64_t texels = 0, tiles = 0;
        for (int n : a.face_sizes()) texels += 6ull * n * n, tiles += 6ull * ((n + 15) / 16) * ((n + 15) / 16);
        within = within && 2 * 4 * texels + 4 * ((texels + 31) / 32) + 64 * tiles <= settings.budget_bytes;
    }
    check(within, "budget 1 MiB: after each of 3 frames the cubes' texel, pending, doubtful and origin bytes stay within it");
    settings.budget_bytes = 100; // 9 cubes of one texel a face: 2 x 4 x 54 bytes and 2 words of bits, 440 bytes
    bool refused = false;
    try {
        rcx::gpu::Tracer tiny(context, scene, spirv, settings);
    } catch (const std::invalid_argument&) {
        refused = true;
    }
    check(refused, "a budget of 100 bytes, below one texel a face for 9 cubes, is refused");
}

// Whether tracer.load_caches(path, identity) throws CacheFileError whose message contains `names`.
bool load_refused(rcx::gpu::Tracer& tracer, const std::string& path, const raycache::SceneIdentity& identity,
                  const std::string& names = "") {
    try {
        tracer.load_caches(path, identity);
    } catch (const raycache::CacheFileError& e) {
        return std::string(e.what()).find(names) != std::string::npos;
    }
    return false;
}

// Warm start: cubes saved after three orbit frames and loaded into a fresh tracer make the same next frame,
// pixel for pixel and hit for hit, as the tracer that saved them, adaptive (the file's face sizes taken) and
// fixed; a fixed face size the file does not have, or another scene, is refused and leaves the cubes.
void run_cache_file_case(rcx::vk::Context& context, rcx::CacheMode mode) {
    const int size = 96;
    const rcx::Scene scene = rcx::make_scene("behind-8");
    const std::string spirv = rcx::gpu::default_spirv_dir();
    const std::string name = std::string("cache file, ") + rcx::to_string(mode);
    const std::string path = "/tmp/raycache-vulkan-cache-test-" + std::to_string(::getpid()) + "-" + rcx::to_string(mode) + ".rcc";
    const raycache::SceneIdentity identity{0xbe8, "behind-8"};
    for (const bool adaptive : {true, false}) {
        rcx::gpu::TracerSettings settings;
        settings.mode = mode;
        settings.adaptive = adaptive;
        settings.face_size = adaptive ? settings.adaptive_resolution.first_face_size : 48;
        settings.min_hit_rate = 0.0f; // a file holds texels, not which cubes rest: no cube rests here
        rcx::gpu::Tracer saved(context, scene, spirv, settings);
        for (int f = 0; f < 3; ++f) saved.render(scene.camera_at(f), size, size);
        saved.save_caches(path, identity);
        rcx::gpu::Tracer loaded(context, scene, spirv, settings);
        loaded.load_caches(path, identity);
        const std::string variant = name + (adaptive ? ", adaptive" : ", fixed faces");
        check(loaded.face_sizes() == saved.face_sizes(), variant + ": the loaded cubes have the saved cubes' face sizes");
        rcx::gpu::FrameStats a, b;
        const rcx::Image warm = saved.render(scene.camera_at(3), size, size, &a);
        const rcx::Image from_file = loaded.render(scene.camera_at(3), size, size, &b);
        check(a.hits > 0 && rcx::bit_identical(warm, from_file) && a.hits == b.hits && a.lookups == b.lookups,
              variant + format(": the loaded tracer's next frame equals the saving tracer's (hits %.0f and %.0f)", double(a.hits),
                               double(b.hits)));
        if (adaptive) {
            // A tracer whose budget holds less than the file's cubes refuses it, naming the budget, and keeps
            // its own cubes (cold here: its next frame still renders, and hits nothing).
            rcx::gpu::TracerSettings tight = settings;
            tight.budget_bytes = 64u << 10;
            rcx::gpu::Tracer small(context, scene, spirv, tight);
            const bool refused = load_refused(small, path, identity, "--budget-mib");
            rcx::gpu::FrameStats cold;
            small.render(scene.camera_at(3), size, size, &cold);
            check(refused && cold.hits == 0, variant + ": a tracer with a 64 KiB budget refuses the file's larger cubes and stays cold");
            continue;
        }
        rcx::gpu::TracerSettings other = settings;
        other.face_size = 32;
        rcx::gpu::Tracer smaller(context, scene, spirv, other);
        check(load_refused(smaller, path, identity, "48"),
              variant + ": a tracer of 32-texel faces refuses the file's 48-texel cubes, naming the size");
        const bool refused = load_refused(loaded, path, raycache::SceneIdentity{1, "another scene"});
        // Kept as they were: the next frame equals the saving tracer's next frame (both went through frame 3,
        // whose stores, and tiles dropped by the origin test, changed the cubes alike).
        rcx::gpu::FrameStats c, d;
        const rcx::Image kept = loaded.render(scene.camera_at(4), size, size, &c);
        const rcx::Image twin = saved.render(scene.camera_at(4), size, size, &d);
        check(refused && c.hits > 0 && c.hits == d.hits && rcx::bit_identical(kept, twin),
              variant + ": a file for another scene is refused and the cubes stay as they were");
    }
    std::remove(path.c_str());
}

// Resting cubes (raycache/gpu_resting.hpp), forced by a threshold no cube meets (min_hit_rate 2), from a
// fixed camera: the cold frame decides nothing (its cubes started empty), the warm frame sends every cube
// that looked up at least 32 rays to rest, and the third frame looks up only those cubes' probe directions
// and traces their other rays alone. The Embree tracer, with the same settings over the same three frames,
// applies the same rule and probes, and its third frame matches the GPU's as the warm frames do. It also
// looks up the leaving rays nested in a missed ray's trace, which the GLSL tracer traces without a lookup,
// so a cube seen only in reflections can be judged, and rest, there alone: it rests at least the GPU's
// cubes, and with the CCT (warm hit rate above 95%, so few nested lookups) exactly as many, letting through
// as many rays (from its own float directions: within 1%). Two tracers agree; with min_hit_rate 0 no cube
// rests.
void run_resting_case(rcx::vk::Context& context, rcx::CacheMode mode, double min_embree_psnr) {
    const int size = 64;
    const rcx::Scene scene = rcx::make_scene("behind-8");
    const std::string spirv = rcx::gpu::default_spirv_dir();
    const std::string name = std::string("resting, ") + rcx::to_string(mode);
    rcx::gpu::TracerSettings settings;
    settings.mode = mode;
    settings.face_size = 32;
    settings.min_hit_rate = 2.0f;
    rcx::gpu::TracerSettings never = settings;
    never.min_hit_rate = 0.0f;
    rcx::gpu::Tracer a(context, scene, spirv, settings), b(context, scene, spirv, settings), c(context, scene, spirv, never);
    rcx::gpu::FrameStats stats[3], twin, working;
    rcx::Image image, twin_image;
    for (int f = 0; f < 3; ++f) {
        image = a.render(scene.camera, size, size, &stats[f]);
        twin_image = b.render(scene.camera, size, size, &twin);
        c.render(scene.camera, size, size, &working);
    }
    check(stats[0].resting_cubes == 0 && stats[0].rested == 0 && stats[1].resting_cubes == 0 && stats[1].rested == 0,
          name + ": no cube rests in the cold frame, nor in the warm frame after it (a frame started empty decides nothing)");
    check(stats[2].resting_cubes > 0 && stats[2].rested > 0 && stats[2].rested < stats[2].lookups,
          name + format(": the third frame rests %.0f cubes, whose probes still look up (%.0f rays let through)",
                        double(stats[2].resting_cubes), double(stats[2].rested)));
    check(rcx::bit_identical(image, twin_image) && stats[2].hits == twin.hits && stats[2].rested == twin.rested,
          name + ": two tracers give the same pixels, hits and rested rays");
    check(working.resting_cubes == 0 && working.rested == 0 && working.hits > 0, name + ": min_hit_rate 0: no cube rests");
    // A tracer loaded from these cubes works (a file holds texels, not resting); its first frame starts with
    // the file's texels, so it decides, and the frame after rests as many cubes.
    const std::string path = "/tmp/raycache-vulkan-resting-test-" + std::to_string(::getpid()) + "-" + rcx::to_string(mode) + ".rcc";
    const raycache::SceneIdentity identity{0xbe8, "behind-8"};
    a.save_caches(path, identity);
    rcx::gpu::Tracer loaded(context, scene, spirv, settings);
    loaded.load_caches(path, identity);
    std::remove(path.c_str());
    rcx::gpu::FrameStats first_loaded, next_loaded;
    loaded.render(scene.camera, size, size, &first_loaded);
    loaded.render(scene.camera, size, size, &next_loaded);
    check(first_loaded.resting_cubes == 0 && first_loaded.rested == 0 && first_loaded.hits > 0 &&
              next_loaded.resting_cubes == stats[2].resting_cubes,
          name + format(": a tracer loaded from a cache file works a frame, then rests %.0f cubes (%.0f)",
                        double(next_loaded.resting_cubes), double(stats[2].resting_cubes)));

    const rcx::embree::Tracer tracer(scene);
    raycache::embree::SceneCache caches(technique_of(mode), embree_settings(settings));
    tracer.attach_caches(caches, settings.face_size);
    rcx::embree::RenderSettings s;
    s.width = s.height = size;
    s.mode = mode;
    s.caches = &caches;
    tracer.render(scene.camera, s);
    caches.begin_frame();
    tracer.render(scene.camera, s);
    const raycache::embree::SceneCacheStatistics warm = caches.begin_frame();
    const rcx::Image embree = tracer.render(scene.camera, s);
    const raycache::embree::SceneCacheStatistics third = caches.statistics();
    const double embree_rested = static_cast<double>(third.misses_by[static_cast<std::size_t>(raycache::MissReason::resting)]);
    if (mode == rcx::CacheMode::cct) {
        check(warm.resting_cubes == stats[2].resting_cubes,
              name + format(": the Embree tracer rests as many cubes (%.0f and %.0f)", double(warm.resting_cubes), double(stats[2].resting_cubes)));
        check(std::abs(embree_rested - double(stats[2].rested)) <= 0.01 * embree_rested,
              name + format(": ... and lets through as many rays (%.0f and %.0f)", embree_rested, double(stats[2].rested)));
    } else {
        check(warm.resting_cubes >= stats[2].resting_cubes,
              name + format(": the Embree tracer rests at least the GPU's cubes (%.0f and %.0f)", double(warm.resting_cubes),
                            double(stats[2].resting_cubes)));
        check(embree_rested >= 0.99 * double(stats[2].rested),
              name + format(": ... and lets through at least its rays, within 1%% (%.0f and %.0f)", embree_rested, double(stats[2].rested)));
    }
    const double psnr = rcx::compare(image, embree).psnr_db;
    check(psnr >= min_embree_psnr, name + format(": the third frame against the Embree tracer's %.2f dB >= %.0f dB", psnr, min_embree_psnr));
}

// simd_group_statistics over hand-placed pixel bits: a 16 x 10 image is two 8 x 8 workgroups across and
// two (cut at row 10) down; a group of 32 lanes is rows 0-3 or 4-7 of a workgroup, of 8 lanes one row.
void run_simd_group_case() {
    std::vector<std::uint32_t> bits(16 * 10, 0u);
    auto at = [&](int x, int y) -> std::uint32_t& { return bits[static_cast<std::size_t>(y) * 16 + x]; };
    at(0, 0) = rcx::gpu::lookup_hit;      // workgroup (0, 0), rows 0-3: a hit and a miss
    at(7, 3) = rcx::gpu::lookup_missed;
    at(3, 5) = rcx::gpu::lookup_hit;      // workgroup (0, 0), rows 4-7: hits alone
    at(4, 7) = rcx::gpu::lookup_hit;
    at(10, 2) = rcx::gpu::lookup_rested;  // workgroup (1, 0), rows 0-3: a ray let through
    at(9, 9) = rcx::gpu::lookup_hit | rcx::gpu::lookup_missed; // workgroup (1, 1), row 9 (rows 8-9 exist)
    const rcx::gpu::SimdGroupStatistics g32 = rcx::gpu::simd_group_statistics(bits, 16, 10, 32);
    check(g32.with_lookups == 4 && g32.all_hit == 1, format("32 lanes: 4 groups with lookups (%.0f), 1 all hit (%.0f)",
                                                            double(g32.with_lookups), double(g32.all_hit)));
    const rcx::gpu::SimdGroupStatistics g64 = rcx::gpu::simd_group_statistics(bits, 16, 10, 64);
    check(g64.with_lookups == 3 && g64.all_hit == 0, format("64 lanes: 3 groups with lookups (%.0f), none all hit (%.0f)",
                                                            double(g64.with_lookups), double(g64.all_hit)));
    const rcx::gpu::SimdGroupStatistics g8 = rcx::gpu::simd_group_statistics(bits, 16, 10, 8);
    check(g8.with_lookups == 6 && g8.all_hit == 3, format("8 lanes (rows): 6 with lookups (%.0f), 3 all hit (%.0f)",
                                                          double(g8.with_lookups), double(g8.all_hit)));
    bool refused = false;
    try {
        rcx::gpu::simd_group_statistics(bits, 16, 10, 24);
    } catch (const std::invalid_argument&) {
        refused = true;
    }
    check(refused, "24 lanes (not a power of two) are refused");
}

int main() {
    run_simd_group_case();
    std::unique_ptr<rcx::vk::Context> context;
    try {
        rcx::vk::ContextOptions options;
        options.require_int64_atomics = true; // the CDCT's stores
        context = std::make_unique<rcx::vk::Context>(options);
    } catch (const rcx::vk::NoDeviceError& e) {
        std::printf("skipped: %s\n", e.what());
        return 77;
    }
    std::printf("device %s, validation %s\n", context->device_name().c_str(), context->validation_enabled() ? "on" : "off");
    const Case cases[] = {
        // Measured on lavapipe: CCT 64.81 dB, against Embree's warm CCT frame inf (every 8-bit pixel equal);
        // CDCT hit rate 0.108 (one frame from the camera fills few texels a search from another origin
        // meets; the thesis's CDCT had the same weakness), 79.5 dB.
        // Secant search: hit rate 0.156, 76.98 dB. Warm CDCT frames against the Embree tracer's: inf with
        // either search (every 8-bit pixel equal: C++ and GLSL search alike, bit for bit).
        {"behind-8", 55.0, 60.0, 0.08, 60.0, 0.12, 60.0, 60.0},
        // CCT 34.49 dB (refracted rays leaving from different points share direction texels), against
        // Embree inf; CDCT hit rate 0.165, 34.43 dB.
        // Secant: hit rate 0.248, 32.94 dB; against Embree inf with either search.
        {"glass", 30.0, 60.0, 0.12, 30.0, 0.20, 30.0, 60.0},
    };
    for (const Case& c : cases) run_case(*context, c);
    // Adaptive sizes, measured on lavapipe (96 x 96, orbit frames 1-3): CCT hits >= 0.400, >= 31.13 dB (with
    // the origin test, which traces rays from origins its tiles were not stored from: 0.556 and 32.60 dB
    // without it); CDCT (secant) hits >= 0.313, >= 38.49 dB.
    run_adaptive_case(*context, "behind-8", rcx::CacheMode::cct, 0.33, 28.0);
    run_adaptive_case(*context, "behind-8", rcx::CacheMode::cdct, 0.25, 33.0);
    run_budget_case(*context);
    run_cache_file_case(*context, rcx::CacheMode::cct);
    run_cache_file_case(*context, rcx::CacheMode::cdct);
    run_resting_case(*context, rcx::CacheMode::cct, 60.0);
    run_resting_case(*context, rcx::CacheMode::cdct, 60.0);
    // A single image with a warm-up over every 4th pixel, measured on lavapipe (64 x 64, 16-texel faces): CCT
    // hits 0.122 at 30.68 dB, CDCT 0.028 at 38.59 dB; against the Embree tracer's image (the same origin
    // test) 89.03 dB for the CCT (one 8-bit value differs), inf for the CDCT. Few hits: the
    // warm-up traces 1/16 of the pixels, and a full-pass ray hits only when a warm-up ray filled the texel of
    // its direction (the CDCT: and its search meets the stored surface there).
    run_warm_up_case(*context, "behind-8", rcx::CacheMode::cct, 16, 0.05, 27.0, 60.0);
    run_warm_up_case(*context, "behind-8", rcx::CacheMode::cdct, 16, 0.012, 34.0, 60.0);
    context.reset();
    const std::uint64_t errors = rcx::vk::validation_errors_in_process();
    check(errors == 0, format("validation errors: %.0f", double(errors)));
    return failures == 0 ? 0 : 1;
}
