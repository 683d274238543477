// rcx/options.hpp: the options shared by the example tracers (same options, same meaning, whatever the
// renderer), and parse_options/help_text, their command line (parsed by rcx/command_line.hpp on CLI11).
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "rcx/output_folder.hpp"
#include "rcx/scene.hpp"

namespace rcx {

// How secondary rays leaving a cached object are answered.
enum class CacheMode {
    off,     // never touch a cache: every ray is traced
    cct,     // colour caching cube (thesis ch. 3)
    cdct,    // colour and depth caching cube with the relief search (thesis ch. 4)
    ceiling, // every cached leaving ray answered by a constant colour, no tracing: no cache can beat it
};

// "off", "cct", "cdct", "ceiling"; parse_cache_mode throws UsageError for anything else.
const char* to_string(CacheMode mode);
// True for the modes that read and write caching cubes (cct, cdct).
inline bool uses_caches(CacheMode mode) { return mode == CacheMode::cct || mode == CacheMode::cdct; }
CacheMode parse_cache_mode(const std::string& text);

// What the caches do when objects of a dynamic scene move between frames (SceneCache::scene_changed).
enum class InvalidationPolicy { none, all, exact };
// "none", "all", "exact"; parse_invalidation throws UsageError for anything else.
const char* to_string(InvalidationPolicy policy);
InvalidationPolicy parse_invalidation(const std::string& text);

// A command line that cannot be run as given; what() says what to change. main() prints it and exits 2.
class UsageError : public std::invalid_argument {
public:
    using std::invalid_argument::invalid_argument;
};

struct Options {
    std::string scene = "behind-32";
    std::string mesh;                 // the concave object of scene "concave"; empty: SceneParams' default
    int width = 512;
    int height = 512;
    CacheMode cache = CacheMode::cct;
    int face_size = 0;                // texels per cube face side; 0 = auto (adaptive, see --help)
    float rays_per_texel = 1.0f;      // auto face sizes: leaving rays of a frame per covered texel
    float still_rays_per_texel = 0.1f; // auto face sizes, once a cube's rays hold still (AdaptiveResolution's default)
    int first_face_size = 256;        // auto face sizes: before a cube's first frame (AdaptiveResolution's default)
    int budget_mib = 256;             // bytes all cubes may take, MiB (SceneCacheSettings::budget_bytes's default;
                                      // Vulkan: raycache::gpu_texel_bytes_within)
    bool filtered = false;            // CCT: bilinear lookups instead of the nearest texel
    bool trace_hits = false;          // diagnostics: answered rays traced anyway (SceneCacheSettings::trace_hits)
    float min_hit_rate = -1.0f;       // cubes answering fewer of their rays rest (SceneCacheSettings::min_hit_rate);
                                      // negative: unset (Embree tracer: each cube's break-even from the rays
                                      // its traced rays took; Vulkan: the technique's default); 0: never
    std::optional<float> lookup_work; // Embree: what a lookup costs in rays (SceneCacheSettings::lookup_work)
    int warm_up = 0;                  // warm-up pass over every warm_up-th pixel before the first frame; 0: off
    float edge_threshold = 0.1f;      // CCT confidence test: neighbours differing by more are traced; < 0 off
    InvalidationPolicy invalidate = InvalidationPolicy::exact; // dynamic scenes: texels dropped when objects move
    float origin_drift = 0.1f;        // CCT: tiles met from origins further than this x half-size away refill; < 0 off
    float origin_parallax = 0.01f;    // CCT: ... or further than this x the distance to the tile's nearest hit; inf off
    float delta = 0.2f;               // CDCT relief search step, world units
    float epsilon = 0.02f;            // CDCT binary refinement threshold
    int max_steps = 1024;             // CDCT linear steps (or pyramid nodes) before a miss
    bool secant = true;               // CDCT search: secant (a few reads) or, false, the thesis's relief walk
    int max_reads = 8;                // CDCT secant search: reads before a miss
    bool pyramid = true;              // CDCT searches over a min-depth pyramid (false: the thesis's linear walk)
    float max_gap = 0.5f;             // CDCT: a crossing this far behind the cached surface is a miss (0 = off)
    bool prefill = false;             // trace every cube texel once before the first frame
    std::string load_cache;           // cache file to load before the first frame (empty: none)
    std::string save_cache;           // cache file to save after the last frame (empty: none)
    std::optional<int> frames;        // unset: the scene's camera path decides
    std::optional<float> step_degrees;
    std::optional<CameraPath::Kind> path;
    std::optional<int> depth;         // max recursion depth; unset: the scene's (5)
    int light_samples = 1;            // shadow rays per shaded hit (> 1: soft shadows, Embree tracer only)
    float light_radius = 1.0f;        // the light's disc radius when light_samples > 1, world units
    int threads = 0;                  // 0 = all cores
    std::string out = "out";          // folder for the PNGs
    bool compare = false;             // also render each frame uncached: speed-up, PSNR, difference PNG
    bool quiet = false;               // no progress bar, no per-frame lines (summary only)
    bool progress = false;            // force the progress bar even when stderr is not a terminal
    bool help = false;
    // What the command line asked for that the run does otherwise, in words for the user (tracer_main
    // prints them): cache options with a mode that keeps no cubes, more threads than the machine has.
    std::vector<std::string> notes;
};

// Parses argv[1..argc-1]; accepts "--name value" and "--name=value", in any order (a repeated option:
// the last wins). Validates ranges, not the scene name (make_scene does) nor the output folder
// (ensure_writable_directory does). Throws UsageError naming the option for unknown options, missing
// values, bad numbers, out of range. A tracer with options of its own uses rcx::CommandLine instead.
Options parse_options(int argc, const char* const argv[]);

// The --help text of the shared options; `program` is argv[0]'s file name.
std::string help_text(const std::string& program);

// The SceneParams the options ask for (--mesh).
SceneParams scene_params(const Options& options);

// Applies --frames/--step/--path/--depth to a scene built by make_scene.
void apply_options(Scene& scene, const Options& options);

// What every example tracer does first: builds the scene the options name (make_scene, scene_params),
// applies the options to it, then checks the output folder (ensure_writable_directory(options.out)) and
// the folder of a --save-cache file.
// Throws what those throw: each message names the bad input.
Scene scene_from_options(const Options& options);

} // namespace rcx
