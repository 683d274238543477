// raycache_dynamic_bench: caches in dynamic scenes. Along dynamic-N's orbit (objects moving every frame)
// every frame is rendered with the cache off and with CCT and CDCT caches under the three invalidation
// policies each (none, all, exact: SceneCache::scene_changed), interleaved in one process in a rotating
// order, one Tracer moved once per frame for all of them. Per frame: fraction of the valid texels kept by the invalidation,
// hit rate, speed-up over the cache off (a cached frame's time includes its invalidation and begin_frame()),
// PSNR against the uncached frame, invalidation time; and what the move really changed: the stale-texel
// oracle (stale_oracle.hpp) over every 4th valid texel of the `none` caches, whose changed fraction bounds
// from below what any exact invalidation must drop. Scenarios: every object moving, one object moving,
// and behind-32 with one of its spheres moving (the invalidation time for behind-32-sized caches).
//
// Writes dynamic_frames.csv, dynamic_summary.csv and dynamic.md into --out; bench/make_results.py puts
// dynamic.md into docs/RESULTS.md.
//
// Usage: raycache_dynamic_bench [--quick] [--out DIR] [--size N] [--frames N] [--scene NAME]
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
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_common.hpp"
#include "bench_embree.hpp"
#include "stale_oracle.hpp"
#include "tracer.hpp"

namespace {

using raycache::embree::Invalidation;
using raycache::embree::InvalidationStatistics;
using raycache::embree::SceneCache;
using rcx::bench::fmt;
using Clock = std::chrono::steady_clock;

struct Options {
    bool quick = false;
    std::string out = "docs/results";
    int size = 512;
    int frames = 30;
    std::string scene = "dynamic-32";
    int invalidation_threads = 0; // SceneCache::scene_changed's passes over this many threads (0: every core)
};

struct Policy {
    const char* label;
    Invalidation policy;
};
constexpr Policy policies[] = {{"none", Invalidation::none}, {"all", Invalidation::all}, {"exact", Invalidation::exact}};

struct Technique {
    const char* label;
    raycache::embree::Technique technique;
    rcx::CacheMode mode;
};
constexpr Technique techniques[] = {{"CCT", raycache::embree::Technique::cct, rcx::CacheMode::cct},
                                    {"CDCT", raycache::embree::Technique::cdct, rcx::CacheMode::cdct}};

// Why exact invalidation emptied texels (raycache::embree::InvalidationStatistics): the summary CSV's
// column and dynamic.md's words for each count.
struct DropReason {
    const char* column;
    const char* words;
    std::size_t InvalidationStatistics::*count;
};
constexpr DropReason drop_reasons[] = {
    {"dropped_moved_cubes", "with the moved objects' own cubes", &InvalidationStatistics::dropped_with_moved_cubes},
    {"dropped_cone", "by their rays' cones", &InvalidationStatistics::dropped_by_cone},
    {"dropped_path", "with blocks whose paths met the move", &InvalidationStatistics::dropped_by_path},
    {"dropped_transitively", "through cached mirrors whose cubes changed", &InvalidationStatistics::dropped_transitively},
    {"dropped_unrecorded", "stored without a record", &InvalidationStatistics::dropped_unrecorded}};
constexpr std::size_t reason_count = std::size(drop_reasons);

struct Track {
    rcx::bench::Variant variant;
    std::size_t technique_index = 0; // in techniques[]
    const Policy* policy = nullptr;
    std::vector<double> kept, hit, speedup, psnr, inval_ms, ms_per_moved;
    std::vector<double> why[reason_count]; // per drop reason, the share of the valid texels a move emptied
};

// Every how many valid texels the oracle retraces (a sample: all of them would take minutes a frame).
constexpr std::size_t oracle_stride = 4;

double mean(const std::vector<double>& v) {
    double s = 0.0;
    int n = 0;
    for (double x : v)
        if (std::isfinite(x)) s += x, ++n;
    return n ? s / n : std::numeric_limits<double>::quiet_NaN();
}
// The mean PSNR of the frames that differ from the uncached ones; infinite when none does (every frame
// identical, as `all` makes them).
double mean_psnr(const std::vector<double>& v) {
    const bool all_identical = !v.empty() && std::all_of(v.begin(), v.end(), [](double x) { return x == std::numeric_limits<double>::infinity(); });
    return all_identical ? std::numeric_limits<double>::infinity() : mean(v);
}
double minimum(const std::vector<double>& v) {
    double m = std::numeric_limits<double>::infinity();
    for (double x : v) m = std::min(m, x);
    return m;
}
double maximum(const std::vector<double>& v) {
    double m = -std::numeric_limits<double>::infinity();
    for (double x : v) m = std::max(m, x);
    return m;
}

struct Outputs {
    std::ofstream frames_csv, summary_csv;
    std::vector<std::vector<std::string>> rows;
    std::string exact_vs_all; // per scenario and technique: frames where exact's PSNR is more than 0.5 dB under all's
    std::string exact_why;    // per scenario and technique: what exact emptied, by reason
};

// What the stale-texel oracle found over one technique's caches along the frames.
struct OracleRun {
    double mean_fraction = 0.0;   // stale share of the checked texels, mean over frames 1..
    std::size_t stale = 0, checked = 0; // summed over the frames
};

// What each move of `scene` left stale, per technique, on caches invalidated with `policy`: under `none`
// (every texel kept) the stale-texel oracle's fraction is what the move really changed; under `exact` it
// must find nothing (the soundness of exact invalidation on the benchmark's own scenes). A pass of its own,
// after the timed one, so that the retracing cannot slow what is timed; frames are deterministic, so its
// caches hold what the timed pass's caches of that policy held.
std::vector<OracleRun> stale_after_moves(const Options& o, const rcx::Scene& scene, Invalidation policy) {
    rcx::embree::Tracer tracer(scene);
    std::vector<rcx::bench::Variant> variants(std::size(techniques));
    std::vector<rcx::bench::Variant*> order;
    for (std::size_t i = 0; i < std::size(techniques); ++i) {
        variants[i].label = techniques[i].label;
        variants[i].mode = techniques[i].mode;
        variants[i].caches = rcx::bench::dynamic_scene_cache(techniques[i].technique);
        tracer.attach_caches(*variants[i].caches, 0);
        order.push_back(&variants[i]);
    }
    std::vector<std::vector<double>> changed(std::size(techniques));
    std::vector<OracleRun> runs(std::size(techniques));
    for (int f = 0; f < o.frames; ++f) {
        if (f > 0) {
            const rcx::embree::Tracer before(scene.at_frame(f - 1));
            const raycache::embree::SceneChange change = tracer.move_to(scene.at_frame(f));
            for (std::size_t i = 0; i < std::size(techniques); ++i) {
                SceneCache& caches = *variants[i].caches;
                rcx::embree::scene_changed(caches, change, policy, o.invalidation_threads);
                const rcx::embree::StaleCount c = techniques[i].technique == raycache::embree::Technique::cct
                                                      ? rcx::embree::stale_cct_texels(caches, before, tracer, oracle_stride)
                                                      : rcx::embree::stale_cdct_texels(caches, before, tracer, oracle_stride);
                changed[i].push_back(c.fraction());
                runs[i].stale += c.stale;
                runs[i].checked += c.checked;
            }
        }
        rcx::bench::render_round(tracer, order, scene.camera_at(f), o.size, o.size, static_cast<std::size_t>(f));
    }
    for (std::size_t i = 0; i < std::size(techniques); ++i) runs[i].mean_fraction = mean(changed[i]);
    return runs;
}

// One scenario: `scene` along its orbit, off and each technique under the three policies.
void scenario(const Options& o, const std::string& label, const rcx::Scene& scene, Outputs& out) {
    rcx::bench::progress("dynamic: " + label);
    rcx::embree::Tracer tracer(scene);
    constexpr std::size_t per_technique = std::size(policies);
    std::vector<Track> tracks(1 + std::size(techniques) * per_technique);
    tracks[0].variant.label = "off";
    for (std::size_t i = 0; i < std::size(techniques); ++i)
        for (std::size_t k = 0; k < per_technique; ++k) {
            Track& t = tracks[1 + i * per_technique + k];
            t.variant.label = std::string(techniques[i].label) + " " + policies[k].label;
            t.variant.mode = techniques[i].mode;
            t.technique_index = i;
            t.policy = &policies[k];
            t.variant.caches = rcx::bench::dynamic_scene_cache(techniques[i].technique); // the tracer's search
            tracer.attach_caches(*t.variant.caches, 0);
        }
    std::vector<rcx::bench::Variant*> order;
    for (Track& t : tracks) order.push_back(&t.variant);
    std::vector<int> below(std::size(techniques), 0);
    int compared = 0;
    std::vector<double> worst_gap(std::size(techniques), -std::numeric_limits<double>::infinity());
    for (int f = 0; f < o.frames; ++f) {
        std::vector<double> kept(tracks.size(), 1.0), inval(tracks.size(), 0.0);
        std::vector<std::array<double, reason_count>> why(tracks.size(), std::array<double, reason_count>{});
        std::size_t moved = 0;
        if (f > 0) {
            const raycache::embree::SceneChange change = tracer.move_to(scene.at_frame(f));
            moved = change.moved.size();
            for (std::size_t k = 1; k < tracks.size(); ++k) {
                const InvalidationStatistics s = rcx::embree::scene_changed(*tracks[k].variant.caches, change, tracks[k].policy->policy, o.invalidation_threads);
                kept[k] = s.kept_fraction();
                inval[k] = s.milliseconds;
                const double valid = static_cast<double>(std::max<std::size_t>(1, s.valid_before));
                for (std::size_t r = 0; r < reason_count; ++r) why[k][r] = static_cast<double>(s.*drop_reasons[r].count) / valid;
            }
        }
        rcx::bench::render_round(tracer, order, scene.camera_at(f), o.size, o.size, static_cast<std::size_t>(f));
        const double off_ms = tracks[0].variant.ms.back();
        std::vector<double> psnr_all(std::size(techniques), 0.0), psnr_exact(std::size(techniques), 0.0);
        for (std::size_t k = 1; k < tracks.size(); ++k) {
            Track& t = tracks[k];
            const double ms = t.variant.ms.back() + inval[k];
            const double psnr = rcx::compare(tracks[0].variant.last, t.variant.last).psnr_db;
            const double hit = t.variant.last_stats.hit_rate();
            out.frames_csv << label << "," << f << "," << techniques[t.technique_index].label << "," << t.policy->label << "," << moved << "," << kept[k] << "," << hit << "," << ms
                           << "," << off_ms << "," << off_ms / ms << "," << psnr << "," << inval[k] << "\n";
            if (f == 0) continue; // cold for everyone
            t.kept.push_back(kept[k]);
            t.hit.push_back(hit);
            t.speedup.push_back(off_ms / ms);
            t.psnr.push_back(psnr);
            t.inval_ms.push_back(inval[k]);
            for (std::size_t r = 0; r < reason_count; ++r) t.why[r].push_back(why[k][r]);
            if (moved) t.ms_per_moved.push_back(inval[k] / static_cast<double>(moved));
            if (t.policy->policy == Invalidation::all) psnr_all[t.technique_index] = psnr;
            if (t.policy->policy == Invalidation::exact) psnr_exact[t.technique_index] = psnr;
        }
        if (f > 0) {
            ++compared;
            for (std::size_t i = 0; i < std::size(techniques); ++i) {
                // Infinite PSNR (identical to uncached) compares as very high.
                const double a = std::isfinite(psnr_all[i]) ? psnr_all[i] : 200.0, e = std::isfinite(psnr_exact[i]) ? psnr_exact[i] : 200.0;
                below[i] += e < a - 0.5 ? 1 : 0;
                worst_gap[i] = std::max(worst_gap[i], a - e);
            }
        }
    }
    rcx::bench::progress("dynamic: " + label + ", what the moves changed (oracle)");
    const std::vector<OracleRun> changed = stale_after_moves(o, scene, Invalidation::none);
    rcx::bench::progress("dynamic: " + label + ", what exact invalidation left stale (oracle)");
    const std::vector<OracleRun> left = stale_after_moves(o, scene, Invalidation::exact);
    for (std::size_t k = 1; k < tracks.size(); ++k) {
        const Track& t = tracks[k];
        const double must_drop = changed[t.technique_index].mean_fraction;
        const OracleRun& exact_left = left[t.technique_index];
        out.summary_csv << label << "," << techniques[t.technique_index].label << "," << t.policy->label << "," << mean(t.kept) << "," << minimum(t.kept) << "," << mean(t.hit) << ","
                        << mean(t.speedup) << "," << mean_psnr(t.psnr) << "," << minimum(t.psnr) << "," << mean(t.inval_ms) << ","
                        << maximum(t.inval_ms) << "," << mean(t.ms_per_moved) << "," << must_drop << ","
                        << (t.policy->policy == Invalidation::exact ? std::to_string(exact_left.stale) : "") << ","
                        << (t.policy->policy == Invalidation::exact ? std::to_string(exact_left.checked) : "");
        for (const std::vector<double>& w : t.why) out.summary_csv << "," << mean(w);
        out.summary_csv << "\n";
        if (t.policy->policy == Invalidation::exact) {
            out.exact_why += "- " + label + ", " + techniques[t.technique_index].label + ", exact: of the valid texels a move, it emptied ";
            for (std::size_t r = 0; r < reason_count; ++r)
                out.exact_why += fmt(100.0 * mean(t.why[r]), 1) + "% " + drop_reasons[r].words +
                                 (r + 2 < reason_count ? ", " : r + 1 < reason_count ? " and " : ".\n");
        }
        out.rows.push_back({label, techniques[t.technique_index].label, t.policy->label, fmt(100.0 * mean(t.kept), 1) + "%", fmt(100.0 * minimum(t.kept), 1) + "%",
                            fmt(100.0 * mean(t.hit), 1) + "%", fmt(mean(t.speedup)) + "x", fmt(mean_psnr(t.psnr), 1), fmt(minimum(t.psnr), 1),
                            fmt(mean(t.inval_ms), 3), fmt(maximum(t.inval_ms), 3), fmt(mean(t.ms_per_moved), 3),
                            t.policy->policy == Invalidation::exact ? fmt(100.0 * (1.0 - must_drop), 1) + "%" : "-",
                            t.policy->policy == Invalidation::exact
                                ? std::to_string(exact_left.stale) + " of " + std::to_string(exact_left.checked)
                                : "-"});
    }
    for (std::size_t i = 0; i < std::size(techniques); ++i)
        out.exact_vs_all += "- " + label + ", " + techniques[i].label + ": exact's PSNR is more than 0.5 dB under all's on " +
                            std::to_string(below[i]) + " of " + std::to_string(compared) + " frames (largest shortfall " +
                            fmt(worst_gap[i], 2) + " dB; 200 dB stands for identical).\n";
}

} // namespace

int main(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "raycache_dynamic_bench: %s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--quick") o.quick = true;
        else if (a == "--out") o.out = value();
        else if (a == "--size") o.size = std::atoi(value().c_str());
        else if (a == "--frames") o.frames = std::atoi(value().c_str());
        else if (a == "--scene") o.scene = value();
        else if (a == "--invalidation-threads") o.invalidation_threads = std::atoi(value().c_str());
        else if (a == "--help") {
            std::puts("usage: raycache_dynamic_bench [--quick] [--out DIR] [--size N] [--frames N] [--scene dynamic-N] [--invalidation-threads N]");
            return 0;
        } else {
            std::fprintf(stderr, "raycache_dynamic_bench: unknown option '%s'\n", a.c_str());
            return 2;
        }
    }
    if (o.quick) o.size = std::min(o.size, 64), o.frames = std::min(o.frames, 3);
    if (o.size < 1 || o.frames < 2) {
        std::fprintf(stderr, "raycache_dynamic_bench: --size >= 1 and --frames >= 2\n");
        return 2;
    }
    try {
        std::filesystem::create_directories(o.out);
        const auto started = Clock::now();
        Outputs out;
        out.frames_csv.open(o.out + "/dynamic_frames.csv");
        out.frames_csv << "scenario,frame,technique,policy,moved_objects,kept_fraction,hit_rate,ms,off_ms,speedup,psnr,invalidate_ms\n";
        out.summary_csv.open(o.out + "/dynamic_summary.csv");
        out.summary_csv << "scenario,technique,policy,kept_mean,kept_min,hit_rate,speedup,psnr_mean,psnr_min,invalidate_ms_mean,"
                           "invalidate_ms_max,invalidate_ms_per_moved_object,oracle_changed_fraction,exact_stale_texels,exact_checked_texels";
        for (const DropReason& r : drop_reasons) out.summary_csv << "," << r.column;
        out.summary_csv << "\n";

        const rcx::Scene all = rcx::make_scene(o.scene);
        scenario(o, o.scene + ", every object moves", all, out);
        rcx::Scene one = all;
        one.motions.resize(1); // sphere 0, a cached mirror, circling; the other objects stand still
        scenario(o, o.scene + ", one object moves", one, out);
        scenario(o, "behind-32, one sphere moves", rcx::bench::behind_with_one_mover(), out);

        std::ostringstream md;
        md << "## Dynamic scenes: invalidation when objects move\n\n"
           << "Machine: " << rcx::bench::machine_name() << ", " << std::thread::hardware_concurrency() << " hardware threads. "
           << (o.quick ? "QUICK MODE (tiny images, few frames): a smoke test, not results. " : "")
           << "Generated by `raycache_dynamic_bench` in "
           << fmt(std::chrono::duration<double>(Clock::now() - started).count(), 0) << " s.\n\n"
           << o.size << "x" << o.size << " pixels, " << o.frames << " frames of an orbit (1 degree a frame), objects moving along "
           << "their paths every frame; the cache off, and CCT and CDCT caches (adaptive faces) under each of the three "
           << "policies of `SceneCache::scene_changed`, rendered every frame, interleaved in one process (one Tracer, moved once a frame, "
           << "its BVH rebuilt). Over frames 1.." << o.frames - 1 << ": *kept* = valid texels the invalidation kept (mean, "
           << "minimum), hit rate of the frame's leaving rays, *speed-up* = mean over frames of off ms / ms (a cached frame's "
           << "ms includes its invalidation and `begin_frame()`), PSNR against the uncached frame (the mean over the frames that "
           << "differ from it; inf: every frame identical), invalidation time of the "
           << "frame and per moved object (each pass's cubes spread over "
           << (o.invalidation_threads > 0 ? std::to_string(o.invalidation_threads) + " thread(s)" : std::string("every core"))
           << ", `SceneCache::scene_changed` with a parallel_for); *could keep* = the valid texels the move did not change, by the stale-texel oracle "
           << "(rays the texels answer retraced uncached before and after the move, on every " << oracle_stride
           << "th valid texel of the `none` caches, mean over frames): an upper bound for any exact invalidation, since a texel "
           << "counts as changed only when one of its sampled rays changed; *stale after exact* = the same oracle on the `exact` caches "
           << "after each move, summed over frames (texels found stale of those checked): 0 when exact invalidation is sound there. "
           << "Per frame: `dynamic_frames.csv`.\n\n"
           << rcx::bench::markdown_table({"scenario", "technique", "policy", "kept mean", "kept min", "hit rate", "speed-up", "PSNR mean dB",
                                          "PSNR min dB", "invalidate ms", "max ms", "ms per moved object", "could keep (oracle)",
                                          "stale after exact (oracle)"},
                                         out.rows)
           << "\n" << out.exact_vs_all << "\nWhat exact emptied, by the first reason that caught each texel (`InvalidationStatistics`), "
           << "mean over frames:\n\n" << out.exact_why;
        std::ofstream file(o.out + "/dynamic.md");
        file << md.str();
        std::printf("%s", md.str().c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raycache_dynamic_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
