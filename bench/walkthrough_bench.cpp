// raycache_walkthrough_bench: the project's headline measure. The camera walks a path through a scene (fixed,
// orbit, pan: 1 degree a frame) and every frame is rendered in each mode: the cache off, CCT, CDCT and the
// ceiling (every cached ray answered by a constant: what no cache can beat). The modes are interleaved frame
// by frame in this one process, on one Tracer, in an order that rotates every frame (so no mode always runs
// first); each caching mode keeps its own SceneCache along the whole path, so its later frames find what its
// earlier ones stored. Frame 0 is cold; the summaries are over the frames after it.
//
// A start-up section builds mirrors-1000 (1000 cached mirror spheres) and behind-32, and times the Tracer's
// construction, attaching the caches and the first frame, with no caches, CCT and CDCT. A warm-start section
// saves each caching mode's caches after an orbit, loads them into fresh ones, and compares the first frame.
//
// Writes into --out: walkthrough_frames.csv (a row per frame and mode), walkthrough_paths.csv (a row per
// scene, path and mode), walkthrough_startup.csv, walkthrough_warm_start.csv and walkthrough.md (the tables,
// also printed on stdout); bench/make_results.py plots the frames and puts walkthrough.md at the top of docs/RESULTS.md.
//
// Usage: raycache_walkthrough_bench [--quick] [--out DIR] [--size N] [--frames N] [--scenes LIST]
//        [--paths LIST] [--modes LIST] [--face-size N] [--rays-per-texel F] [--min-hit-rate F] [--startup LIST]
//        [--startup-budget-mib N] [--warm-start LIST]
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "bench_common.hpp"
#include "bench_embree.hpp"
#include "rcx/option_values.hpp"
#include "rcx/scene_hash.hpp"
#include "tracer.hpp"

namespace {

using raycache::embree::SceneCache;
using raycache::embree::SceneCacheStatistics;
using raycache::embree::Technique;
using rcx::CacheMode;
using rcx::bench::fmt;
using rcx::bench::median;
using rcx::bench::progress;
using rcx::bench::Report;
using rcx::bench::Variant;
using Clock = std::chrono::steady_clock;
using PathKind = rcx::CameraPath::Kind;

constexpr double mib = 1024.0 * 1024.0;

struct Options {
    bool quick = false;
    std::string out = "docs/results";
    int size = 1024;
    int frames = 30;
    float step_degrees = 1.0f;
    std::vector<std::string> scenes{"behind-32", "grid-32", "reflective-32"};
    std::vector<PathKind> paths{PathKind::fixed, PathKind::orbit, PathKind::pan};
    std::vector<CacheMode> modes{CacheMode::off, CacheMode::cct, CacheMode::cdct, CacheMode::ceiling};
    int face_size = rcx::Options{}.face_size; // the example tracer's default
    std::vector<std::string> startup{"mirrors-1000", "behind-32"};
    double startup_budget_mib = 8192.0;
    std::vector<std::string> warm_start{"behind-32"};
    std::optional<float> min_hit_rate; // SceneCacheSettings::min_hit_rate (unset: the technique's default)
    std::optional<float> rays_per_texel; // AdaptiveResolution::rays_per_texel (unset: its default)
};

const char* const usage =
    "usage: raycache_walkthrough_bench [--quick] [--out DIR] [--size N] [--frames N] [--scenes LIST] [--paths LIST]\n"
    "       [--modes LIST] [--face-size N] [--rays-per-texel F] [--min-hit-rate F] [--startup LIST]\n"
    "       [--startup-budget-mib N] [--warm-start LIST]\n"
    "  --size N             N x N pixels                                                [1024]\n"
    "  --frames N           frames per path, 1 degree apart                             [30]\n"
    "  --scenes LIST        comma-separated scenes            [behind-32,grid-32,reflective-32]\n"
    "  --paths LIST         fixed, orbit, pan                                [fixed,orbit,pan]\n"
    "  --modes LIST         off, cct, cdct, ceiling (off is always rendered: the reference)\n"
    "  --face-size N|auto   texels per cube face side; auto: adaptive (the tracer's default) [auto]\n"
    "  --rays-per-texel F   auto faces: a frame's leaving rays per covered texel [AdaptiveResolution's]\n"
    "  --min-hit-rate F     cubes answering fewer of their rays rest; 0: never\n"
    "                       [each cube's break-even from its rays' work (SceneCacheSettings::lookup_work)]\n"
    "  --startup LIST       scenes of the start-up section, or none    [mirrors-1000,behind-32]\n"
    "  --startup-budget-mib N  start-up rows whose cubes would need more are not allocated [8192]\n"
    "  --warm-start LIST    scenes whose caches are saved after an orbit and loaded back, or none [behind-32]\n"
    "  --quick              64 x 64 pixels, 3 frames: a smoke test, not results\n"
    "  --out DIR            where the CSV and Markdown files go                [docs/results]\n";

// The one place where the walkthrough's caches are made: the SceneCache of one mode, with a cube on every
// cached object of the tracer's scene; nullptr for the modes without caches. Cubes are adaptive (--face-size
// auto, the default) or of --face-size texels per edge. The CDCT searches over its depth pyramid and
// rejects crossings more than 0.5 behind the cached surface (our_relief, as in raycache_bench).
// first_face_size: where adaptive cubes start (0: AdaptiveResolution's default).
std::unique_ptr<SceneCache> make_scene_cache(const rcx::embree::Tracer& tracer, CacheMode mode, const Options& o,
                                             int first_face_size = 0) {
    if (!rcx::uses_caches(mode)) return nullptr;
    raycache::embree::SceneCacheSettings settings;
    settings.relief = rcx::bench::our_relief;
    settings.depth_pyramid = true;
    if (first_face_size > 0) settings.adaptive.first_face_size = first_face_size;
    settings.min_hit_rate = o.min_hit_rate;
    if (o.rays_per_texel) settings.adaptive.rays_per_texel = *o.rays_per_texel;
    auto caches = std::make_unique<SceneCache>(mode == CacheMode::cct ? Technique::cct : Technique::cdct, settings);
    tracer.attach_caches(*caches, o.face_size);
    return caches;
}

// The cube memory of a SceneCache: what its cubes hold (allocated tiles, tile tables), and the CDCT's pyramids.
std::size_t cube_bytes(const SceneCacheStatistics& s) { return s.allocated_bytes + s.pyramid_bytes; }

// "auto" for adaptive cubes, else the face size.
std::string face_label(int face_size) { return face_size > 0 ? std::to_string(face_size) : "auto"; }

// What make_scene_cache's cubes would take if every tile were allocated: one cube of --face-size per cached
// object (0 for adaptive cubes: they allocate on first store, within the SceneCache's budget). The start-up
// section uses it to stay inside --startup-budget-mib.
std::size_t planned_cube_bytes(const rcx::embree::Tracer& tracer, CacheMode mode, const Options& o) {
    if (!rcx::uses_caches(mode) || o.face_size == 0) return 0;
    const std::size_t objects = tracer.cached_geometries().size();
    const std::size_t per_texel = mode == CacheMode::cct ? raycache::CctCube(1).texel_bytes() / 6 : raycache::CdctCube(1).texel_bytes() / 6;
    const std::size_t pyramid = mode == CacheMode::cdct ? raycache::DepthPyramid(o.face_size).bytes() : 0;
    return objects * (std::size_t{6} * o.face_size * o.face_size * per_texel + pyramid);
}

// One mode's measurements on one frame.
struct FrameRecord {
    double ms = 0.0;
    rcx::ImageDifference diff; // against the frame's 'off' image
    SceneCacheStatistics stats;
    std::uint64_t rays = 0;
};

// One mode along one path.
struct ModeTrack {
    Variant variant;
    std::vector<FrameRecord> frames;
};

// The frames the summaries use: all after the cold frame 0 (frame 0 alone when there is no other).
std::vector<std::size_t> warm_frames(std::size_t count) {
    std::vector<std::size_t> frames;
    for (std::size_t f = count > 1 ? 1 : 0; f < count; ++f) frames.push_back(f);
    return frames;
}

double mean_of(const std::vector<double>& v) {
    double sum = 0.0;
    for (double x : v) sum += x;
    return v.empty() ? std::numeric_limits<double>::quiet_NaN() : sum / static_cast<double>(v.size());
}

// A mode's summary over the warm frames of a path.
struct PathSummary {
    double off_ms = 0.0, ms = 0.0;
    double speedup = 0.0;              // mean off ms / mean ms over the warm frames
    double median_ratio_speedup = 0.0; // median over the warm frames of off ms / ms (a check on noise)
    double psnr_mean = 0.0, psnr_min = 0.0;
    int identical_frames = 0;          // frames equal to 'off' in every 8-bit value (PSNR infinite)
    double hit_rate = 0.0;             // mean over the warm frames
    double texels_per_lookup = 0.0;    // texels read / rays looked up (resting ones left out), over the warm frames
    std::size_t cube_bytes = 0;
    // Hits and misses by raycache::MissReason as shares of all the warm frames' lookups together.
    double pooled_hit_rate = 0.0;
    std::array<double, raycache::miss_reason_count> miss_shares{};
};

// A frame's misses by reason as shares of its lookups (zeros without lookups).
std::array<double, raycache::miss_reason_count> miss_shares(const SceneCacheStatistics& s) {
    std::array<double, raycache::miss_reason_count> shares{};
    for (std::size_t k = 0; k < shares.size(); ++k) shares[k] = s.miss_share(static_cast<raycache::MissReason>(k));
    return shares;
}

PathSummary summarise(const ModeTrack& off, const ModeTrack& m) {
    PathSummary s;
    std::vector<double> off_ms, ms, ratios, psnrs, hits;
    std::uint64_t texels = 0, searched = 0, lookups = 0, hit_count = 0;
    std::array<std::uint64_t, raycache::miss_reason_count> misses_by{};
    s.psnr_min = std::numeric_limits<double>::infinity();
    for (std::size_t f : warm_frames(m.frames.size())) {
        const FrameRecord& r = m.frames[f];
        off_ms.push_back(off.frames[f].ms);
        ms.push_back(r.ms);
        ratios.push_back(off.frames[f].ms / r.ms);
        s.psnr_min = std::min(s.psnr_min, r.diff.psnr_db);
        if (std::isfinite(r.diff.psnr_db)) psnrs.push_back(r.diff.psnr_db);
        else ++s.identical_frames;
        hits.push_back(r.stats.hit_rate());
        texels += r.stats.texels_read;
        searched += r.stats.looked_up();
        lookups += r.stats.lookups;
        hit_count += r.stats.hits;
        for (std::size_t k = 0; k < misses_by.size(); ++k) misses_by[k] += r.stats.misses_by[k];
        s.cube_bytes = cube_bytes(r.stats);
    }
    s.off_ms = mean_of(off_ms);
    s.ms = mean_of(ms);
    s.speedup = s.off_ms / s.ms;
    s.median_ratio_speedup = median(ratios);
    s.psnr_mean = psnrs.empty() ? std::numeric_limits<double>::infinity() : mean_of(psnrs);
    s.hit_rate = mean_of(hits);
    s.texels_per_lookup = searched ? static_cast<double>(texels) / static_cast<double>(searched) : 0.0; // resting rays read none
    s.pooled_hit_rate = lookups ? static_cast<double>(hit_count) / static_cast<double>(lookups) : 0.0;
    for (std::size_t k = 0; k < misses_by.size(); ++k)
        s.miss_shares[k] = lookups ? static_cast<double>(misses_by[k]) / static_cast<double>(lookups) : 0.0;
    return s;
}

// (off/mode - 1) / (off/ceiling - 1): the share of the ceiling's gain a mode reaches; NaN without a ceiling gain.
double ceiling_share(double speedup, double ceiling_speedup) {
    return ceiling_speedup > 1.0 ? (speedup - 1.0) / (ceiling_speedup - 1.0) : std::numeric_limits<double>::quiet_NaN();
}

std::string or_dash(bool present, const std::string& text) { return present ? text : "-"; }

struct Outputs {
    Report report;
    std::ofstream frames_csv, paths_csv;
    std::vector<std::vector<std::string>> path_rows, miss_rows;
};

// Walks one path through a scene in every mode and writes its rows.
void walk(const Options& o, const rcx::embree::Tracer& tracer, PathKind kind, Outputs& out) {
    rcx::Scene scene = tracer.scene();
    scene.path.kind = kind;
    scene.path.frames = o.frames;
    scene.path.step_degrees = o.step_degrees;
    const std::string path = rcx::to_string(kind);

    std::vector<ModeTrack> tracks;
    for (CacheMode mode : o.modes) {
        ModeTrack t;
        t.variant.label = rcx::to_string(mode);
        t.variant.mode = mode;
        t.variant.caches = make_scene_cache(tracer, mode, o);
        tracks.push_back(std::move(t));
    }
    std::vector<Variant*> order;
    for (ModeTrack& t : tracks) order.push_back(&t.variant);
    const ModeTrack& off = tracks.front(); // parse_options puts off first

    const auto started = Clock::now();
    for (int f = 0; f < o.frames; ++f) {
        rcx::bench::render_round(tracer, order, scene.camera_at(f), o.size, o.size, static_cast<std::size_t>(f));
        for (ModeTrack& t : tracks) {
            FrameRecord r;
            r.ms = t.variant.ms.back();
            r.diff = rcx::compare(off.variant.last, t.variant.last);
            r.stats = t.variant.last_stats;
            r.rays = t.variant.last_frame.rays;
            const bool cached = rcx::uses_caches(t.variant.mode);
            out.frames_csv << scene.name << "," << path << "," << f << "," << t.variant.label << "," << r.ms << ","
                           << off.variant.ms.back() / r.ms << "," << r.diff.psnr_db << "," << r.diff.mean_abs_error << ","
                           << r.diff.max_abs_error << "," << (cached ? fmt(r.stats.hit_rate(), 6) : "") << ","
                           << (t.variant.mode == CacheMode::cdct ? fmt(r.stats.texels_per_lookup(), 3) : "") << ","
                           << (cached ? std::to_string(r.stats.max_texels_read) : "") << ","
                           << (cached ? fmt(r.stats.valid_fraction(), 6) : "") << "," << cube_bytes(r.stats) << "," << r.rays;
            for (double share : miss_shares(r.stats)) out.frames_csv << "," << (cached ? fmt(share, 6) : "");
            out.frames_csv << "\n";
            t.frames.push_back(r);
        }
        if ((f + 1) % 10 == 0 && f + 1 < o.frames)
            progress("  " + scene.name + ", " + path + ": frame " + std::to_string(f + 1) + "/" + std::to_string(o.frames));
    }
    progress("  " + scene.name + ", " + path + ": done in " +
             fmt(std::chrono::duration<double>(Clock::now() - started).count(), 0) + " s");

    std::optional<PathSummary> ceiling;
    for (const ModeTrack& t : tracks)
        if (t.variant.mode == CacheMode::ceiling) ceiling = summarise(off, t);
    for (const ModeTrack& t : tracks) {
        if (t.variant.mode == CacheMode::off) continue;
        const PathSummary s = summarise(off, t);
        const bool cached = rcx::uses_caches(t.variant.mode), cdct = t.variant.mode == CacheMode::cdct;
        const bool is_ceiling = t.variant.mode == CacheMode::ceiling;
        const double share = ceiling && !is_ceiling ? ceiling_share(s.speedup, ceiling->speedup) : std::numeric_limits<double>::quiet_NaN();
        out.paths_csv << scene.name << "," << path << "," << t.variant.label << "," << warm_frames(t.frames.size()).size() << ","
                      << s.off_ms << "," << s.ms << "," << s.speedup << "," << s.median_ratio_speedup << ","
                      << (std::isnan(share) ? "" : fmt(share, 4)) << "," << s.psnr_mean << "," << s.psnr_min << ","
                      << s.identical_frames << "," << (cached ? fmt(s.hit_rate, 6) : "") << ","
                      << (cdct ? fmt(s.texels_per_lookup, 3) : "") << "," << s.cube_bytes;
        for (double share : s.miss_shares) out.paths_csv << "," << (cached ? fmt(share, 6) : "");
        out.paths_csv << "\n";
        out.path_rows.push_back({scene.name, path, t.variant.label, fmt(s.off_ms, 1), fmt(s.ms, 1), fmt(s.speedup) + "x",
                                 std::isnan(share) ? "-" : fmt(100.0 * share, 0) + "%", fmt(s.psnr_mean, 1), fmt(s.psnr_min, 1), or_dash(cached, fmt(100.0 * s.hit_rate, 1) + "%"),
                                 or_dash(cdct, fmt(s.texels_per_lookup, 1)), or_dash(cached, fmt(s.cube_bytes / mib, 1))});
        if (!cached) continue;
        // What the hit rate alone would give if lookups and stores cost nothing and a miss cost what an average
        // leaving ray costs: the ceiling's time plus the missed share of what the ceiling saves.
        std::vector<std::string> row{scene.name, path, t.variant.label, fmt(100.0 * s.pooled_hit_rate, 1) + "%"};
        for (double share : s.miss_shares) row.push_back(fmt(100.0 * share, 1) + "%");
        if (ceiling) {
            const double free_ms = ceiling->ms + (1.0 - s.pooled_hit_rate) * (s.off_ms - ceiling->ms);
            row.push_back(fmt(s.off_ms / free_ms) + "x");
            row.push_back(fmt(s.ms - free_ms, 1));
        } else {
            row.push_back("-");
            row.push_back("-");
        }
        out.miss_rows.push_back(row);
    }
}

// A single image, nothing to reuse: the cache off, a cold CCT frame, and CCT frames with a warm-up pass over
// every 2nd and 4th pixel (RenderSettings::warm_up_stride), the last also with cubes starting at 64-texel
// faces instead of 256 (AdaptiveResolution::first_face_size: a cheaper first pass, coarser texels), each
// round with fresh caches, the variants in a rotating order; median times over the rounds, PSNR against
// the uncached image.
std::string single_image(const Options& o, const Report& report) {
    std::ofstream csv = report.csv("single_image.csv", "scene,variant,warm_up_stride,median_ms,speedup,psnr,hit_rate");
    std::vector<std::vector<std::string>> rows;
    const int rounds = o.quick ? 1 : 3;
    constexpr int variants = 5;
    const int strides[variants] = {0, 0, 2, 4, 4}; // off, cold CCT, warm-up 2, warm-up 4 (first faces 256, 64)
    const int first_faces[variants] = {0, 0, 0, 0, 64};
    const char* labels[variants] = {"off", "cct, cold", "cct, warm-up 2", "cct, warm-up 4", "cct, warm-up 4, first faces 64"};
    for (const std::string& name : o.scenes) {
        progress("single image: " + name);
        const rcx::Scene scene = rcx::make_scene(name);
        const rcx::embree::Tracer tracer(scene);
        std::vector<double> ms[variants];
        double hit_rate[variants] = {};
        rcx::Image images[variants];
        for (int round = 0; round < rounds; ++round)
            for (int k = 0; k < variants; ++k) {
                const int v = (k + round) % variants;
                const CacheMode mode = v == 0 ? CacheMode::off : CacheMode::cct;
                std::unique_ptr<SceneCache> caches = make_scene_cache(tracer, mode, o, first_faces[v]);
                rcx::embree::RenderSettings s;
                s.width = s.height = o.size;
                s.mode = mode;
                s.caches = caches.get();
                s.warm_up_stride = strides[v];
                rcx::embree::FrameStats stats;
                images[v] = tracer.render(scene.camera_at(0), s, &stats);
                const auto end_start = Clock::now();
                if (caches) hit_rate[v] = rcx::embree::end_frame(*caches).hit_rate();
                ms[v].push_back(stats.milliseconds + std::chrono::duration<double, std::milli>(Clock::now() - end_start).count());
            }
        const double off_ms = rcx::bench::median(ms[0]);
        for (int v = 0; v < variants; ++v) {
            const double median = rcx::bench::median(ms[v]);
            const double psnr = rcx::compare(images[v], images[0]).psnr_db;
            csv << name << "," << rcx::bench::csv_text(labels[v]) << "," << strides[v] << "," << median << ","
                << off_ms / median << "," << psnr << "," << hit_rate[v] << "\n";
            rows.push_back({name, labels[v], fmt(median, 1), fmt(off_ms / median) + "x", v == 0 ? "-" : fmt(psnr, 1),
                            v == 0 ? "-" : fmt(100.0 * hit_rate[v], 1) + "%"});
        }
    }
    std::ostringstream md;
    md << "### A single image\n\n"
       << "What a renderer that makes one image gets: a cache is filled by a frame's misses and read from the next "
       << "frame on, so a lone frame can only reuse what a warm-up pass over every S-th pixel stored before it "
       << "(`RenderSettings::warm_up_stride`, tracer `--warm-up S`). " << o.size << "x" << o.size << ", "
       << rounds << " rounds with fresh caches, medians; hit rate of the full pass.\n\n"
       << rcx::bench::markdown_table({"scene", "variant", "ms", "speed-up", "PSNR dB", "hit rate"}, rows);
    return md.str();
}

// Start-up: building the Tracer, attaching the caches and the first frame, with no caches, CCT and CDCT.
std::string startup(const Options& o, const Report& report) {
    std::ofstream csv = report.csv("walkthrough_startup.csv",
                                   "scene,cached_objects,mode,face_size,tracer_ms,attach_ms,cube_bytes,planned_cube_bytes,"
                                   "allocated,first_frame_ms");
    std::vector<std::vector<std::string>> rows;
    for (const std::string& name : o.startup) {
        progress("start-up: " + name);
        const rcx::Scene scene = rcx::make_scene(name);
        for (CacheMode mode : {CacheMode::off, CacheMode::cct, CacheMode::cdct}) {
            auto t0 = Clock::now();
            const rcx::embree::Tracer tracer(scene);
            const double tracer_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
            const std::size_t planned = planned_cube_bytes(tracer, mode, o);
            const bool cached = rcx::uses_caches(mode);
            const std::string label = cached ? rcx::to_string(mode) : "none";
            const std::string objects = std::to_string(tracer.cached_geometries().size());
            if (planned / mib > o.startup_budget_mib) {
                csv << name << "," << objects << "," << label << "," << face_label(o.face_size) << "," << tracer_ms << ",,," << planned << ",0,\n";
                rows.push_back({name, objects, label, face_label(o.face_size), fmt(tracer_ms, 1), "-",
                                "needs " + fmt(planned / mib, 0) + ", not allocated (over " + fmt(o.startup_budget_mib, 0) + ")", "-"});
                continue;
            }
            Variant v;
            v.mode = mode;
            t0 = Clock::now();
            v.caches = make_scene_cache(tracer, mode, o);
            const double attach_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
            const std::size_t bytes = v.caches ? cube_bytes(v.caches->statistics()) : 0;
            double first_ms = 0.0;
            rcx::bench::render(tracer, v, scene.camera_at(0), o.size, o.size, &first_ms);
            csv << name << "," << objects << "," << label << "," << (cached ? face_label(o.face_size) : "") << ","
                << tracer_ms << "," << (cached ? fmt(attach_ms, 3) : "") << "," << bytes << "," << planned << ",1," << first_ms << "\n";
            rows.push_back({name, objects, label, or_dash(cached, face_label(o.face_size)), fmt(tracer_ms, 1),
                            or_dash(cached, fmt(attach_ms, 1)), or_dash(cached, fmt(bytes / mib, 1)), fmt(first_ms, 1)});
        }
    }
    std::ostringstream md;
    md << "### Start-up\n\n"
       << "Building the Embree scene (`Tracer`), attaching a cube to every cached object (`SceneCache` construction and "
       << "`attach_caches`, which allocates and clears the texels) and the first, cold frame at " << o.size << "x" << o.size
       << ", each row with a Tracer of its own. Rows whose cubes would exceed " << fmt(o.startup_budget_mib, 0)
       << " MiB are not allocated (this machine is shared).\n\n"
       << rcx::bench::markdown_table({"scene", "cached objects", "caches", "face size", "build Tracer ms", "attach ms",
                                      "cube MiB", "first frame ms"},
                                     rows);
    return md.str();
}

// Warm start: along an orbit of --frames frames each caching mode warms its caches, saves them after the last
// frame (the "saved-from" frame) and a fresh SceneCache loads them; the loaded cache's first frame, at the
// saved-from camera, against that warm frame (hit rate, PSNR) and against the warm cache rendering that
// camera once more (which it should equal bit for bit), and the load's time per MiB of file (median of 3
// loads, the file in the page cache: parsing, checking and filling, not the disk).
std::string warm_start(const Options& o, const Report& report) {
    std::ofstream csv = report.csv("walkthrough_warm_start.csv",
                                   "scene,mode,frames,file_bytes,save_ms,load_ms,load_ms_per_mib,cold_hit_rate,warm_hit_rate,"
                                   "warm_psnr,loaded_hit_rate,loaded_psnr,loaded_equals_warm_cache");
    std::vector<std::vector<std::string>> rows;
    const std::string file = o.out + "/walkthrough_warm_start.rcc";
    auto ms_since = [](Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); };
    for (const std::string& name : o.warm_start) {
        progress("warm start: " + name);
        const rcx::embree::Tracer tracer(rcx::make_scene(name));
        rcx::Scene scene = tracer.scene();
        scene.path.kind = PathKind::orbit;
        scene.path.step_degrees = o.step_degrees;
        const raycache::SceneIdentity identity{rcx::scene_hash(scene), scene.name};
        const rcx::Camera saved_from = scene.camera_at(o.frames - 1);
        Variant off;
        const rcx::Image reference = rcx::bench::render(tracer, off, saved_from, o.size, o.size);
        for (CacheMode mode : o.modes) {
            if (!rcx::uses_caches(mode)) continue;
            Variant warm, loaded;
            warm.mode = loaded.mode = mode;
            warm.caches = make_scene_cache(tracer, mode, o);
            double cold_hits = 0.0;
            rcx::Image warm_image;
            for (int f = 0; f < o.frames; ++f) {
                warm_image = rcx::bench::render(tracer, warm, scene.camera_at(f), o.size, o.size);
                if (f == 0) cold_hits = warm.last_stats.hit_rate();
            }
            const SceneCacheStatistics warm_stats = warm.last_stats;
            auto t0 = Clock::now();
            warm.caches->save(file, identity);
            const double save_ms = ms_since(t0);
            const std::uintmax_t file_bytes = std::filesystem::file_size(file);
            const double file_mib = static_cast<double>(file_bytes) / mib;
            std::vector<double> load_ms;
            for (int k = 0; k < 3; ++k) {
                loaded.caches = make_scene_cache(tracer, mode, o);
                t0 = Clock::now();
                loaded.caches->load(file, identity);
                load_ms.push_back(ms_since(t0));
            }
            std::filesystem::remove(file);
            const rcx::Image first = rcx::bench::render(tracer, loaded, saved_from, o.size, o.size);
            const rcx::Image again = rcx::bench::render(tracer, warm, saved_from, o.size, o.size);
            const double warm_psnr = rcx::compare(reference, warm_image).psnr_db, loaded_psnr = rcx::compare(reference, first).psnr_db;
            const bool equal = !std::isfinite(rcx::compare(again, first).psnr_db) && loaded.last_stats.hits == warm.last_stats.hits;
            const double per_mib = median(load_ms) / file_mib;
            csv << name << "," << rcx::to_string(mode) << "," << o.frames << "," << file_bytes << "," << save_ms
                << "," << median(load_ms) << "," << per_mib << "," << cold_hits << "," << warm_stats.hit_rate() << "," << warm_psnr << ","
                << loaded.last_stats.hit_rate() << "," << loaded_psnr << "," << (equal ? 1 : 0) << "\n";
            rows.push_back({name, rcx::to_string(mode), fmt(100.0 * cold_hits, 1) + "%", fmt(100.0 * warm_stats.hit_rate(), 1) + "%",
                            fmt(warm_psnr, 1), fmt(100.0 * loaded.last_stats.hit_rate(), 1) + "%", fmt(loaded_psnr, 1),
                            equal ? "yes" : "NO", fmt(file_mib, 2), fmt(save_ms, 1), fmt(median(load_ms), 1), fmt(per_mib, 1)});
        }
    }
    std::ostringstream md;
    md << "### Warm start: caches saved and loaded back\n\n"
       << "Each caching mode renders an orbit of " << o.frames << " frames (" << o.size << "x" << o.size
       << "), saves its caches after the last one (`SceneCache::save`) and a fresh SceneCache loads them "
       << "(`SceneCache::load`). *Loaded first frame*: the loaded cache's first frame, at the camera of the last warm "
       << "frame; *same as warm cache*: it equals, in every pixel and hit, what the warm cache itself renders there next. "
       << "PSNR against the uncached frame. Load time: median of 3 loads, the file in the page cache.\n\n"
       << rcx::bench::markdown_table({"scene", "mode", "cold frame hits", "last warm frame hits", "its PSNR dB",
                                      "loaded first frame hits", "its PSNR dB", "same as warm cache", "file MiB", "save ms",
                                      "load ms", "load ms/MiB"},
                                     rows);
    return md.str();
}

// Each item of a comma-separated list through `parse`; an item it rejects is a UsageError naming the option.
template <class T, class Parse>
std::vector<T> parse_each(const std::string& option, const std::string& text, Parse parse, const char* valid) {
    std::vector<T> values;
    for (const std::string& item : rcx::bench::split_list(text)) {
        try {
            values.push_back(parse(item));
        } catch (const std::invalid_argument&) {
            throw rcx::UsageError(option + ": unknown '" + item + "'; use " + valid);
        }
    }
    return values;
}

int positive(const std::string& option, const std::string& text) {
    char* end = nullptr;
    const long value = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || value < 1 || value > 1 << 20)
        throw rcx::UsageError(option + ": '" + text + "' is not a positive whole number");
    return static_cast<int>(value);
}

Options parse_options(int argc, char** argv) {
    Options o;
    std::optional<int> size, frames, face;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw rcx::UsageError(a + " needs a value");
            return argv[++i];
        };
        if (a == "--quick") o.quick = true;
        else if (a == "--out") o.out = value();
        else if (a == "--size") size = positive(a, value());
        else if (a == "--frames") frames = positive(a, value());
        else if (a == "--face-size") {
            const std::string v = value();
            face = v == "auto" ? 0 : positive(a, v);
        }
        else if (a == "--min-hit-rate") {
            const std::string v = value();
            const float rate = rcx::parse_float_value(a, v, false); // as the tracer's option
            if (!(rate >= 0.0f)) throw rcx::UsageError(a + ": must be >= 0, got '" + v + "'");
            o.min_hit_rate = rate;
        }
        else if (a == "--rays-per-texel") {
            const std::string v = value();
            const float rays = rcx::parse_float_value(a, v, false);
            if (!(rays > 0.0f) || !std::isfinite(rays)) throw rcx::UsageError(a + ": must be a finite number > 0, got '" + v + "'");
            o.rays_per_texel = rays;
        }
        else if (a == "--scenes") o.scenes = rcx::bench::split_list(value());
        else if (a == "--paths") o.paths = parse_each<PathKind>(a, value(), rcx::parse_path_kind, "fixed, orbit, pan");
        else if (a == "--modes") o.modes = parse_each<CacheMode>(a, value(), rcx::parse_cache_mode, "off, cct, cdct, ceiling");
        else if (a == "--startup") {
            const std::string list = value();
            o.startup = list == "none" ? std::vector<std::string>{} : rcx::bench::split_list(list);
        } else if (a == "--startup-budget-mib") o.startup_budget_mib = positive(a, value());
        else if (a == "--warm-start") {
            const std::string list = value();
            o.warm_start = list == "none" ? std::vector<std::string>{} : rcx::bench::split_list(list);
        }
        else throw rcx::UsageError("unknown option '" + a + "'");
    }
    o.size = size.value_or(o.quick ? 64 : o.size);
    o.frames = frames.value_or(o.quick ? 3 : o.frames);
    o.face_size = face.value_or(o.face_size);
    // 'off' is the reference of every speed-up and PSNR: always rendered, listed first, each mode once.
    std::vector<CacheMode> modes{CacheMode::off};
    for (CacheMode m : o.modes)
        if (std::find(modes.begin(), modes.end(), m) == modes.end()) modes.push_back(m);
    o.modes = modes;
    if (o.scenes.empty() || o.paths.empty()) throw rcx::UsageError("--scenes and --paths need at least one entry");
    for (const std::string& name : o.scenes) rcx::make_scene(name); // unknown names fail here, before any work
    for (const std::string& name : o.startup) rcx::make_scene(name);
    for (const std::string& name : o.warm_start) rcx::make_scene(name);
    return o;
}

} // namespace

int main(int argc, char** argv) {
    Options o;
    try {
        for (int i = 1; i < argc; ++i)
            if (std::string(argv[i]) == "--help") {
                std::fputs(usage, stdout);
                return 0;
            }
        o = parse_options(argc, argv);
    } catch (const std::exception& e) { // rcx::UsageError, and std::invalid_argument for unknown scenes or paths
        std::fprintf(stderr, "raycache_walkthrough_bench: %s\n%s", e.what(), usage);
        return 2;
    }
    try {
        std::filesystem::create_directories(o.out);
        const auto started = Clock::now();
        Outputs out;
        out.report.dir = o.out;
        out.frames_csv = out.report.csv("walkthrough_frames.csv",
                                        "scene,path,frame,mode,ms,speedup,psnr,mean_abs_error,max_abs_error,hit_rate,"
                                        "texels_per_lookup,max_texels,valid_fraction,cube_bytes,rays,miss_empty,miss_fresh,"
                                        "miss_doubtful,miss_origin,miss_search,miss_outside,miss_resting");
        out.paths_csv = out.report.csv("walkthrough_paths.csv",
                                       "scene,path,mode,frames,off_ms,ms,speedup,median_ratio_speedup,ceiling_share,"
                                       "psnr_mean,psnr_min,identical_frames,hit_rate,texels_per_lookup,cube_bytes,miss_empty,"
                                       "miss_fresh,miss_doubtful,miss_origin,miss_search,miss_outside,miss_resting");
        for (const std::string& name : o.scenes) {
            progress("walkthrough: " + name + " (" + std::to_string(o.frames) + " frames x " + std::to_string(o.modes.size()) +
                     " modes per path)");
            const rcx::embree::Tracer tracer(rcx::make_scene(name));
            for (PathKind kind : o.paths) walk(o, tracer, kind, out);
        }
        const std::string startup_md = o.startup.empty() ? "" : startup(o, out.report);
        const std::string single_md = single_image(o, out.report);
        const std::string warm_start_md = o.warm_start.empty() ? "" : warm_start(o, out.report);
        const double seconds = std::chrono::duration<double>(Clock::now() - started).count();

        std::ostringstream md;
        md << "## Walkthrough: the camera moves, the caches persist\n\n"
           << "Machine: " << rcx::bench::machine_name() << ", " << std::thread::hardware_concurrency() << " hardware threads. "
           << (o.quick ? "QUICK MODE (tiny images, few frames): a smoke test, not results. " : "")
           << "Generated by `raycache_walkthrough_bench` in " << fmt(seconds, 0) << " s.\n\n"
           << o.size << "x" << o.size << " pixels, " << o.frames << " frames per path, " << fmt(o.step_degrees, 0)
           << " degree a frame (orbit: the eye around the target; pan: the view around the eye; fixed: no motion), "
           << (o.face_size > 0 ? std::to_string(o.face_size) + "-texel faces on every cached object"
                               : std::string("adaptive faces (each cube's size follows its object's rays") +
                                     (o.rays_per_texel ? ", " + fmt(*o.rays_per_texel) + " rays per texel" : std::string()) +
                                     "; nearest-texel CCT lookups)")
           << ", recursion depth 5. Every frame is rendered in every "
           << "mode, interleaved in one process in a rotating order, on one Tracer; each caching mode keeps its own "
           << "caches along the path (filled only by rendering, cold at frame 0). CCT: confidence test at 0.1 (texels at "
           << "colour edges are traced), origins within 0.1 of the cube's half-size and 0.01 rad of parallax of the ones a "
           << "tile was stored from. CDCT: secant search (at most 8 reads), max_gap 0.5.\n\n"
           << "Over frames 1.." << o.frames - 1 << " (frame 0 is cold): *speed-up* = mean ms with the cache off / mean ms "
           << "of the mode; *of ceiling's gain* = (speed-up - 1) / (ceiling's speed-up - 1); PSNR against the same "
           << "frame's uncached image (mean of the finite values, and the minimum); hit rate = mean of the frames' "
           << "rates; cube MiB = allocated texel tiles + CDCT depth pyramids. Per frame: `walkthrough_frames.csv`, plots "
           << "`walkthrough_<scene>.png`.\n\n"
           << rcx::bench::markdown_table({"scene", "path", "mode", "off ms", "ms", "speed-up", "of ceiling's gain",
                                          "PSNR mean dB", "PSNR min dB", "hit rate", "texels/lookup", "cube MiB"},
                                         out.path_rows)
           << "\n### Why lookups miss, and what they cost\n\n"
           << "Over the same frames, each miss counted under what caused it, as a share of all their lookups "
           << "together (so the hit rate here is pooled too, and the row sums to 100%): *empty* (the "
           << "texel held nothing: never stored, or dropped with a stale tile), *fresh* (stored this frame, visible from "
           << "the next), *doubtful* (at a colour edge: the confidence test traces it), *origin* (CCT: the ray left too far "
           << "from its tile's origins; the tile is dropped and refills), *search* (CDCT: no consistent crossing within "
           << "the reads), *outside* (not answerable), *resting* (the cube rested: it had answered too few of its rays, "
           << "so its rays were traced, but for a sixteenth of the directions or fewer, which kept measuring it). *Free lookups* is the speed-up the hit rate alone would give if "
           << "lookups and stores cost nothing and a missed ray cost what an average leaving ray costs (the ceiling's ms "
           << "plus the missed share of what the ceiling saves); *ms beyond* is the mode's mean ms minus that time: what "
           << "looking up, storing and ending frames cost, and what the missed rays cost above the average. A rough "
           << "split: the lookups include those of rays leaving cached objects inside a missed ray's trace, which "
           << "the ceiling never makes, so where cached objects reflect each other it is approximate.\n\n"
           << rcx::bench::markdown_table({"scene", "path", "mode", "hit rate", "empty", "fresh", "doubtful", "origin",
                                          "search", "outside", "resting", "free lookups", "ms beyond"},
                                         out.miss_rows)
           << "\n"
           << startup_md << "\n" << single_md << (warm_start_md.empty() ? "" : "\n") << warm_start_md;
        std::ofstream file(o.out + "/walkthrough.md");
        file << md.str();
        if (!file) throw std::runtime_error("cannot write " + o.out + "/walkthrough.md");
        std::printf("%s", md.str().c_str());
        std::fprintf(stderr, "[bench] walkthrough done in %.0f s; tables in %s/walkthrough.md\n", seconds, o.out.c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raycache_walkthrough_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
