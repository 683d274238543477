// raycache_bench: reproduces the thesis's experiments (Tables 5.2-5.3, Figure 5.9, the quality figures) on
// the Embree Whitted tracer and writes docs/RESULTS.md's tables (table_5_2.md, tables.md), CSV files for
// plotting and the difference images. Every speed-up is a ratio of medians of renders interleaved in this one process
// (off, CCT, CDCT, ceiling, off, ...), on the same frames, so machine noise hits all modes alike.
//
// Usage: raycache_bench [--quick] [--out DIR] [--rounds N] [--only LIST] [--ns LIST] [--size S]
//   --quick   small images, few rounds: a smoke test that every experiment runs and writes its files
//   --rounds  interleaved rounds of Table 5.2 (default 9; Table 5.3's 1080p frames always take 3)
//   --only    comma-separated experiments: table_5_2, table_5_3, figure_5_9, quality, memory (default: all)
//   --ns      comma-separated N for table_5_2 (default 1,2,4,8,16,32; grid-N skips 0)
//   --size    Table 5.2's image side in pixels (default 1024, the thesis's)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "bench_common.hpp"
#include "bench_embree.hpp"
#include "tracer.hpp"

namespace fs = std::filesystem;
using raycache::embree::SceneCache;
using raycache::embree::SceneCacheStatistics;
using raycache::embree::Technique;
using rcx::CacheMode;
using rcx::Image;
using rcx::bench::csv_text;
using rcx::bench::fmt;
using rcx::bench::machine_name;
using rcx::bench::median;
using rcx::bench::our_relief;
using rcx::bench::progress;
using rcx::bench::render;
using rcx::bench::Report;
using rcx::bench::Variant;

namespace {

struct Config : rcx::bench::CommonOptions {
    Config() { rounds = 9; } // Table 5.2: medians that hold on a shared 2-core machine, in about 4 minutes
    std::string only; // empty: every experiment
    int size = 0;     // Table 5.2's image side; 0: 1024 (128 with --quick)
    bool wants(const std::string& name) const { return only.empty() || ("," + only + ",").find("," + name + ",") != std::string::npos; }
};

// A variant with its own caches; `prefill` traces every texel first (Tracer::prefill).
Variant make_variant(const rcx::embree::Tracer& tracer, std::string label, CacheMode mode, int face_size,
                     raycache::ReliefParameters relief = {}, bool pyramid = true, bool prefill = false) {
    Variant v;
    v.label = std::move(label);
    v.mode = mode;
    if (rcx::uses_caches(mode)) {
        // The thesis's caches: every cube answers every frame (SceneCacheSettings::min_hit_rate 0, no resting).
        raycache::embree::SceneCacheSettings settings;
        settings.relief = relief;
        settings.depth_pyramid = pyramid;
        settings.min_hit_rate = 0.0f;
        v.caches = std::make_unique<SceneCache>(mode == CacheMode::cct ? Technique::cct : Technique::cdct, settings);
        tracer.attach_caches(*v.caches, face_size);
        if (prefill) {
            tracer.prefill(*v.caches);
            v.caches->begin_frame();
        }
    }
    return v;
}

// Times every variant `rounds` times on the same camera, interleaved, in a rotating order.
void time_interleaved(const rcx::embree::Tracer& tracer, const std::vector<Variant*>& variants, const rcx::Camera& camera,
                      int width, int height, int rounds) {
    for (int r = 0; r < rounds; ++r) rcx::bench::render_round(tracer, variants, camera, width, height, static_cast<std::size_t>(r));
}

// One row of Table 5.2: a scene's speed-ups over the cache off (for the side-by-side table).
struct Speedups {
    double cct = 0.0, cdct = 0.0, ceiling = 0.0;
};

// Table 5.2 on one family of scenes ("grid" or "behind"), N cached mirror spheres each, warm caches: its
// CSV lines (the family in the first column), its markdown table into `md`, speed-ups by N.
std::map<int, Speedups> table_5_2_family(const Config& c, const Report& out, std::ostream& csv, std::ostream& md,
                                         const std::string& family, const std::vector<int>& ns, int size, int face) {
    const std::map<int, double> thesis = {{1, 1.02}, {2, 1.07}, {4, 1.15}, {8, 1.32}, {16, 1.95}, {32, 2.68}};
    std::map<int, Speedups> result;
    md << "| N | off ms | CCT ms | CDCT ms | ceiling ms | CCT speed-up | CDCT speed-up | "
          "ceiling | CCT ms / ceiling ms | CCT PSNR dB | CDCT PSNR dB | CDCT texels/lookup | thesis CCT |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (int n : ns) {
        const std::string name = family + "-" + std::to_string(n);
        progress("Table 5.2: " + name);
        const rcx::Scene scene = rcx::make_scene(name);
        rcx::embree::Tracer tracer(scene);
        Variant off = make_variant(tracer, "off", CacheMode::off, face);
        Variant cct = make_variant(tracer, "cct", CacheMode::cct, face);
        Variant cdct = make_variant(tracer, "cdct", CacheMode::cdct, face, our_relief);
        Variant ceiling = make_variant(tracer, "ceiling", CacheMode::ceiling, face);
        const rcx::Camera camera = scene.camera_at(0);
        for (int warm = 0; warm < 2; ++warm) {
            render(tracer, cct, camera, size, size);
            render(tracer, cdct, camera, size, size);
        }
        time_interleaved(tracer, {&off, &cct, &cdct, &ceiling}, camera, size, size, c.rounds);
        const double off_ms = median(off.ms), cct_ms = median(cct.ms), cdct_ms = median(cdct.ms), ceil_ms = median(ceiling.ms);
        const double cct_psnr = rcx::compare(off.last, cct.last).psnr_db, cdct_psnr = rcx::compare(off.last, cdct.last).psnr_db;
        const double tpl = cdct.lookups ? double(cdct.texels_read) / cdct.lookups : 0.0;
        result[n] = {off_ms / cct_ms, off_ms / cdct_ms, off_ms / ceil_ms};
        const auto t = thesis.find(n);
        csv << family << "," << n << "," << off_ms << "," << cct_ms << "," << cdct_ms << "," << ceil_ms << "," << off_ms / cct_ms << ","
            << off_ms / cdct_ms << "," << off_ms / ceil_ms << "," << cct_psnr << "," << cdct_psnr << ","
            << cct.last_stats.hit_rate() << "," << cdct.last_stats.hit_rate() << "," << tpl << ","
            << (t == thesis.end() ? std::string("") : fmt(t->second)) << "\n";
        md << "| " << n << " | " << fmt(off_ms, 1) << " | " << fmt(cct_ms, 1) << " | " << fmt(cdct_ms, 1) << " | "
           << fmt(ceil_ms, 1) << " | " << fmt(off_ms / cct_ms) << "x | " << fmt(off_ms / cdct_ms) << "x | "
           << fmt(off_ms / ceil_ms) << "x | " << fmt(cct_ms / ceil_ms) << " | " << fmt(cct_psnr, 1) << " | "
           << fmt(cdct_psnr, 1) << " | " << fmt(tpl, 1) << " | "
           << (t == thesis.end() ? std::string("-") : fmt(t->second) + "x") << " |\n";
        if (n == ns.back()) {
            out.png(name + "_off.png", off.last);
            out.png(name + "_cct.png", cct.last);
            out.png(name + "_cct_diff.png", rcx::difference_image(off.last, cct.last));
            out.png(name + "_cdct_diff.png", rcx::difference_image(off.last, cdct.last));
        }
    }
    md << "\nImages of the last row: `" << family << "-" << ns.back() << "_off.png`, `_cct.png`, and the difference images "
       << "`_cct_diff.png`, `_cdct_diff.png` (blue = equal, red = completely different).\n\n";
    return result;
}

// Table 5.2: conventional ray tracing with warm caches on grid-N, the thesis's scene (N cached mirror
// spheres in front of the camera, Figure 1.1), and on behind-N (Table 5.1's scene), side by side.
void table_5_2(const Config& c, Report& out) {
    const int size = c.size > 0 ? c.size : c.quick ? 128 : 1024, face = c.quick ? 64 : 512;
    const std::vector<int> ns = !c.ns.empty() ? c.ns : c.quick ? std::vector<int>{1, 32} : std::vector<int>{1, 2, 4, 8, 16, 32};
    const std::map<int, double> thesis = {{1, 1.02}, {2, 1.07}, {4, 1.15}, {8, 1.32}, {16, 1.95}, {32, 2.68}};
    std::ofstream csv = out.csv("table_5_2.csv",
                                "scene,n,off_ms,cct_ms,cdct_ms,ceiling_ms,cct_speedup,cdct_speedup,ceiling_speedup,"
                                "cct_psnr,cdct_psnr,cct_hit_rate,cdct_hit_rate,cdct_texels_per_lookup,thesis_cct_speedup");
    std::ostringstream grid_md, behind_md;
    std::vector<int> grid_ns;
    std::copy_if(ns.begin(), ns.end(), std::back_inserter(grid_ns), [](int n) { return n >= 1; }); // no grid-0
    const std::map<int, Speedups> grid = grid_ns.empty() ? std::map<int, Speedups>{}
                                                         : table_5_2_family(c, out, csv, grid_md, "grid", grid_ns, size, face);
    const std::map<int, Speedups> behind = table_5_2_family(c, out, csv, behind_md, "behind", ns, size, face);

    out.md << "## Table 5.2: conventional ray tracing, grid-N (the thesis's scene) and behind-N\n\n"
           << "The thesis's Table 5.2 times a conventional ray tracer (OptiX) with and without the CCT on \"a group of "
           << "spheres with our technique, arranged like a grid in front of the camera\" (its section 5.1, Figure 1.1). "
           << "Here: *grid-N*, N of grid-32's 8 x 4 cached mirror spheres, nearest the grid's centre first, seen by "
           << "grid-32's camera; *behind-N*, Table 5.1's main mirror sphere facing the camera with N cached mirror spheres "
           << "behind the camera. Embree tracer, " << size << "x" << size << " pixels, " << face
           << "-texel faces, every reflective sphere cached, warm caches (filled by rendering the same view first), "
           << "recursion depth 5. Speed-up = median ms with the cache off / median ms of the technique, " << c.rounds
           << " interleaved rounds. Ceiling: every cached secondary ray answered by a constant (no cache can be faster). "
           << "PSNR against the uncached frame. The thesis's speed-ups are its fps with the CCT / its fps without.\n\n"
           << "| N | grid-N CCT | grid-N ceiling | grid-N CDCT | behind-N CCT | behind-N ceiling | behind-N CDCT | thesis CCT (grid, OptiX) |\n"
           << "|---|---|---|---|---|---|---|---|\n";
    const auto cell = [](const std::map<int, Speedups>& m, int n, double Speedups::*field) {
        const auto it = m.find(n);
        return it == m.end() ? std::string("-") : fmt(it->second.*field) + "x";
    };
    for (int n : ns) {
        const auto t = thesis.find(n);
        out.md << "| " << n << " | " << cell(grid, n, &Speedups::cct) << " | " << cell(grid, n, &Speedups::ceiling) << " | "
               << cell(grid, n, &Speedups::cdct) << " | " << cell(behind, n, &Speedups::cct) << " | "
               << cell(behind, n, &Speedups::ceiling) << " | " << cell(behind, n, &Speedups::cdct) << " | "
               << (t == thesis.end() ? std::string("-") : fmt(t->second) + "x") << " |\n";
    }
    out.md << "\nPlot: `table_5_2.png`.\n\n"
           << "CDCT: pyramid search, max_gap 0.5, caches filled by rendering the view twice (as the thesis; the CDCT "
           << "pre-filled by tracing every texel is in Table 5.3 and the quality section). Hit rates in `table_5_2.csv`.\n\n"
           << "### grid-N\n\n" << grid_md.str() << "### behind-N\n\n" << behind_md.str();
}

// Table 5.3: the CDCT's parameters on diffuse-31 and reflective-32.
void table_5_3(const Config& c, Report& out) {
    const int width = c.quick ? 160 : 1920, height = c.quick ? 90 : 1080, face = c.quick ? 64 : 512;
    const int rounds = c.quick ? 1 : 3;
    struct Setting {
        std::string label;
        raycache::ReliefParameters relief;
        bool pyramid;
    };
    const std::vector<Setting> settings = {
        {"thesis (2, 0.2)", {2.0f, 0.2f, 2048, 100.0f}, false},
        {"thesis (0.4, 0.05)", {0.4f, 0.05f, 2048, 100.0f}, false},
        {"thesis (0.2, 0.02)", {0.2f, 0.02f, 2048, 100.0f}, false},
        {"thesis (0.02, 0.002)", {0.02f, 0.002f, 2048, 100.0f}, false},
        {"pyramid, eps 0.02", {0.2f, 0.02f, 1024, 100.0f}, true},
        {"pyramid, eps 0.02, max_gap 0.5", our_relief, true},
    };
    const std::map<std::string, std::vector<double>> thesis_fps = {
        {"diffuse-31", {76.0, 69.6, 49.5, 35.3, 30.7, 19.0}}, {"reflective-32", {68.2, 30.1, 13.5, 12.7, 12.1, 9.5}}};
    std::ofstream csv = out.csv("table_5_3.csv", "scene,setting,ms,speedup,texels_per_lookup,max_texels,hit_rate,psnr,thesis_speedup");
    out.md << "## Table 5.3: the CDCT's search parameters\n\n"
           << width << "x" << height << " pixels, " << face << "-texel faces, depths up to 100 units, warm caches "
           << "(two filling frames of the same view). (delta, epsilon) as in the thesis; the linear walk is capped at "
           << "2048 steps (a longer walk is a miss, traced). Pyramid: our search over a min-depth pyramid. max_gap: "
           << "crossings more than 0.5 units behind the cached surface are misses. Thesis speed-up = its fps / its plain RT fps.\n\n"
           << "| scene | technique | ms | speed-up | texels/lookup | max texels | hit rate | PSNR dB | thesis speed-up |\n"
           << "|---|---|---|---|---|---|---|---|---|\n";
    for (const std::string name : {"diffuse-31", "reflective-32"}) {
        progress("Table 5.3: " + name);
        const rcx::Scene scene = rcx::make_scene(name);
        rcx::embree::Tracer tracer(scene);
        const rcx::Camera camera = scene.camera_at(0);
        std::vector<Variant> variants;
        variants.push_back(make_variant(tracer, "off", CacheMode::off, face));
        variants.push_back(make_variant(tracer, "CCT", CacheMode::cct, face));
        for (const Setting& s : settings)
            variants.push_back(make_variant(tracer, "CDCT " + s.label, CacheMode::cdct, face, s.relief, s.pyramid));
        variants.push_back(make_variant(tracer, "CDCT pyramid, max_gap 0.5, prefilled", CacheMode::cdct, face, our_relief, true, true));
        std::vector<Variant*> all;
        for (Variant& v : variants) {
            for (int warm = 0; warm < 2 && v.caches; ++warm) render(tracer, v, camera, width, height);
            all.push_back(&v);
        }
        time_interleaved(tracer, all, camera, width, height, rounds);
        const double off_ms = median(variants[0].ms);
        const std::vector<double>& fps = thesis_fps.at(name);
        for (std::size_t i = 0; i < variants.size(); ++i) {
            Variant& v = variants[i];
            const double ms = median(v.ms);
            const double tpl = v.lookups ? double(v.texels_read) / v.lookups : 0.0;
            const double psnr = rcx::compare(variants[0].last, v.last).psnr_db;
            // Thesis columns: CCT, RT, then the four CDCT settings.
            std::string thesis = "-";
            if (i == 0) thesis = "1.00x";
            if (i == 1) thesis = fmt(fps[0] / fps[1]) + "x";
            if (i >= 2 && i < 6) thesis = fmt(fps[i] / fps[1]) + "x";
            csv << name << "," << csv_text(v.label) << "," << ms << "," << off_ms / ms << "," << tpl << "," << v.max_texels << ","
                << v.last_stats.hit_rate() << "," << psnr << "," << (thesis == "-" ? "" : thesis.substr(0, thesis.size() - 1)) << "\n";
            out.md << "| " << name << " | " << v.label << " | " << fmt(ms, 1) << " | " << fmt(off_ms / ms) << "x | "
                   << (v.mode == CacheMode::cdct ? fmt(tpl, 1) : "-") << " | "
                   << (v.mode == CacheMode::cdct ? std::to_string(v.max_texels) : "-") << " | "
                   << (v.caches ? fmt(100.0 * v.last_stats.hit_rate(), 1) + "%" : "-") << " | " << fmt(psnr, 1) << " | "
                   << thesis << " |\n";
        }
    }
    out.md << "\n";
}

// Figure 5.9: share of the texels a frame needs that are outdated (missing) before it, while panning.
void figure_5_9(const Config& c, Report& out) {
    const int size = c.quick ? 128 : 1024;
    const int frames = 10; // frame 0 and nine pans of 10/3 degrees
    std::ofstream csv = out.csv("figure_5_9.csv", "face_size,frame,outdated_percent,valid_percent");
    out.md << "## Figure 5.9: update rate while panning\n\n"
           << "behind-0 (one reflective sphere facing the camera), " << size << "x" << size << " pixels, CCT, the camera "
           << "pans nine times by 10/3 degrees. Outdated = lookups of the frame that found no valid texel (the rays "
           << "that must be traced and stored), before each frame. Thesis after frame 1: 3% (128), 31% (256), 73% (512).\n\n"
           << "| face size | frame 1 | frame 2 | frame 3 | frame 4 | frame 5 | frame 6 | frame 7 | frame 8 | frame 9 |\n"
           << "|---|---|---|---|---|---|---|---|---|---|\n";
    rcx::Scene scene = rcx::make_scene("behind-0");
    scene.path.kind = rcx::CameraPath::Kind::pan;
    scene.path.step_degrees = 10.0f / 3.0f;
    rcx::embree::Tracer tracer(scene);
    for (int face : {128, 256, 512}) {
        progress("Figure 5.9: faces of " + std::to_string(face));
        Variant cct = make_variant(tracer, "cct", CacheMode::cct, face);
        out.md << "| " << face << " |";
        for (int f = 0; f < frames; ++f) {
            render(tracer, cct, scene.camera_at(f), size, size);
            const double outdated = 100.0 * (1.0 - cct.last_stats.hit_rate());
            csv << face << "," << f << "," << outdated << "," << 100.0 * cct.last_stats.valid_fraction() << "\n";
            if (f > 0) out.md << " " << fmt(outdated, 1) << "% |";
        }
        out.md << "\n";
    }
    out.md << "\nPlot: `figure_5_9.png`.\n\n";
}

// Quality at the filling viewpoints and after the camera moved away (the parallax test).
void quality(const Config& c, Report& out) {
    const int size = c.quick ? 128 : 768, face = c.quick ? 64 : 512;
    const int fill_frames = c.quick ? 3 : 8, moved_frames = 6; // orbit 2 degrees a frame
    std::ofstream csv = out.csv("quality.csv", "scene,technique,viewpoint,psnr,mean_abs_error,max_abs_error,hit_rate");
    out.md << "## Quality: at the filling viewpoints and after moving away\n\n"
           << size << "x" << size << " pixels, " << face << "-texel faces. The caches fill while the camera orbits "
           << fill_frames << " frames of 2 degrees; (a) is the last filling frame, (b) a frame " << moved_frames * 2
           << " degrees further along the orbit, rendered from the caches as they are. Errors on tone-mapped 8-bit "
           << "values, 0..1.\n\n"
           << "| scene | technique | viewpoint | PSNR dB | mean abs error | max abs error | hit rate |\n"
           << "|---|---|---|---|---|---|---|\n";
    for (const std::string name : {"grid-32", "reflective-32"}) {
        progress("Quality: " + name);
        rcx::Scene scene = rcx::make_scene(name);
        scene.path.kind = rcx::CameraPath::Kind::orbit;
        scene.path.step_degrees = 2.0f;
        rcx::embree::Tracer tracer(scene);
        Variant off = make_variant(tracer, "off", CacheMode::off, face);
        std::vector<Variant> techniques;
        techniques.push_back(make_variant(tracer, "CCT", CacheMode::cct, face));
        techniques.push_back(make_variant(tracer, "CDCT thesis (0.2, 0.02)", CacheMode::cdct, face, {0.2f, 0.02f, 2048, 100.0f}, false));
        techniques.push_back(make_variant(tracer, "CDCT pyramid + max_gap", CacheMode::cdct, face, our_relief, true));
        techniques.push_back(make_variant(tracer, "CDCT pyramid + max_gap, prefilled", CacheMode::cdct, face,
                                          our_relief, true, true));
        for (int f = 0; f < fill_frames; ++f)
            for (Variant& v : techniques) v.last = render(tracer, v, scene.camera_at(f), size, size);
        const Image filled_reference = render(tracer, off, scene.camera_at(fill_frames - 1), size, size);
        const int moved = fill_frames - 1 + moved_frames;
        const Image moved_reference = render(tracer, off, scene.camera_at(moved), size, size);
        for (Variant& v : techniques) {
            const double filled_hits = v.last_stats.hit_rate();
            const rcx::ImageDifference a = rcx::compare(filled_reference, v.last);
            const Image at_moved = render(tracer, v, scene.camera_at(moved), size, size);
            const rcx::ImageDifference b = rcx::compare(moved_reference, at_moved);
            for (int k = 0; k < 2; ++k) {
                const rcx::ImageDifference& d = k ? b : a;
                const char* where = k ? "moved" : "filling";
                const double hits = k ? v.last_stats.hit_rate() : filled_hits;
                csv << name << "," << csv_text(v.label) << "," << where << "," << d.psnr_db << "," << d.mean_abs_error << ","
                    << d.max_abs_error << "," << hits << "\n";
                out.md << "| " << name << " | " << v.label << " | " << (k ? "(b) moved" : "(a) filling") << " | "
                       << fmt(d.psnr_db, 1) << " | " << fmt(d.mean_abs_error, 4) << " | " << fmt(d.max_abs_error, 3)
                       << " | " << fmt(100.0 * hits, 1) << "% |\n";
            }
            std::string file = name + "_moved_" + v.label + "_diff.png";
            std::replace_if(file.begin(), file.end(), [](char ch) { return !std::isalnum(static_cast<unsigned char>(ch)) && ch != '.' && ch != '-' && ch != '_'; }, '_');
            out.png(file, rcx::difference_image(moved_reference, at_moved));
        }
        out.png(name + "_moved_off.png", moved_reference);
    }
    out.md << "\nDifference images at the moved viewpoint: `*_moved_*_diff.png` (blue = equal, red = completely different).\n\n";
}

void memory(Report& out) {
    std::ofstream csv = out.csv("memory.csv", "face_size,cct_bytes,cdct_bytes,pyramid_bytes");
    out.md << "## Memory per cube\n\n"
           << "Texel storage is 6 N^2 x 4 bytes for the CCT (RGB9E5) and 6 N^2 x 8 bytes for the CDCT (RGB9E5 + "
           << "float distance); the thesis used 16 bytes (RGBA float). The CDCT's optional depth pyramid adds about "
           << "a third of a float per texel; a cube also keeps one bit per texel for the frame's stores.\n\n"
           << "| face size | CCT | CDCT | CDCT pyramid | thesis (16 B/texel) |\n|---|---|---|---|---|\n";
    for (int n : {128, 256, 512, 1024}) {
        const raycache::CctCube cct(n);
        const raycache::CdctCube cdct(n);
        const raycache::DepthPyramid pyramid(n);
        const auto mib = [](std::size_t b) { return fmt(b / 1048576.0, 2) + " MiB"; };
        csv << n << "," << cct.texel_bytes() << "," << cdct.texel_bytes() << "," << pyramid.bytes() << "\n";
        out.md << "| " << n << " | " << mib(cct.texel_bytes()) << " | " << mib(cdct.texel_bytes()) << " | "
               << mib(pyramid.bytes()) << " | " << mib(std::size_t{6} * n * n * 16) << " |\n";
    }
    out.md << "\n";
}

} // namespace

int main(int argc, char** argv) {
    Config c;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (rcx::bench::parse_common_option(argc, argv, i, c)) continue;
        if (a == "--only" && i + 1 < argc) {
            c.only = argv[++i];
        } else if (a == "--size" && i + 1 < argc) {
            c.size = std::max(16, std::atoi(argv[++i]));
        } else {
            std::fprintf(stderr, "usage: raycache_bench [--quick] [--out DIR] [--rounds N] [--only LIST] [--ns LIST] [--size S]\n");
            return a == "--help" ? 0 : 2;
        }
    }
    try {
        fs::create_directories(c.out);
        // Table 5.2 goes to table_5_2.md, the rest to tables.md; a file is written only when one of its
        // experiments ran, so `--only table_5_2` re-measures that table and keeps the others' files.
        const auto write_md = [&](const std::string& file, const Report& report, double seconds) {
            std::ofstream md(c.out + "/" + file);
            md << "Machine: " << machine_name() << ", " << std::thread::hardware_concurrency() << " hardware threads. "
               << (c.quick ? "QUICK MODE (small images, one round): smoke test, not results. " : "")
               << "Generated by `raycache_bench` in " << fmt(seconds, 0) << " s.\n\n"
               << report.md.str();
            if (!md) throw std::runtime_error("cannot write " + c.out + "/" + file);
            std::printf("%s", report.md.str().c_str());
        };
        const auto seconds_since = [](std::chrono::steady_clock::time_point t) {
            return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
        };
        const auto started = std::chrono::steady_clock::now();
        if (c.wants("table_5_2")) {
            Report t52;
            t52.dir = c.out;
            table_5_2(c, t52);
            write_md("table_5_2.md", t52, seconds_since(started));
        }
        const auto rest_started = std::chrono::steady_clock::now();
        Report out;
        out.dir = c.out;
        const bool rest = c.wants("table_5_3") || c.wants("figure_5_9") || c.wants("quality") || c.wants("memory");
        if (c.wants("table_5_3")) table_5_3(c, out);
        if (c.wants("figure_5_9")) figure_5_9(c, out);
        if (c.wants("quality")) quality(c, out);
        if (c.wants("memory")) memory(out);
        if (rest) write_md("tables.md", out, seconds_since(rest_started));
        std::fprintf(stderr, "[bench] done in %.0f s; tables in %s/table_5_2.md, tables.md\n", seconds_since(started), c.out.c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raycache_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
