// Command-line parsing shared by the example tracers.
#include "rcx/options.hpp"

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>
#ifdef __linux__
#include <linux/magic.h>
#include <sys/vfs.h>
#endif

namespace rcx {

const char* to_string(CacheMode mode) {
    switch (mode) {
    case CacheMode::off: return "off";
    case CacheMode::cct: return "cct";
    case CacheMode::cdct: return "cdct";
    case CacheMode::ceiling: return "ceiling";
    }
    return "?";
}

CacheMode parse_cache_mode(const std::string& text) {
    if (text == "off") return CacheMode::off;
    if (text == "cct") return CacheMode::cct;
    if (text == "cdct") return CacheMode::cdct;
    if (text == "ceiling") return CacheMode::ceiling;
    throw UsageError("--cache: unknown mode '" + text + "'; use off, cct, cdct or ceiling");
}

const char* to_string(InvalidationPolicy policy) {
    switch (policy) {
    case InvalidationPolicy::none: return "none";
    case InvalidationPolicy::all: return "all";
    case InvalidationPolicy::exact: return "exact";
    }
    return "?";
}

InvalidationPolicy parse_invalidation(const std::string& text) {
    if (text == "none") return InvalidationPolicy::none;
    if (text == "all") return InvalidationPolicy::all;
    if (text == "exact") return InvalidationPolicy::exact;
    throw UsageError("--invalidate: unknown policy '" + text + "'; use none, all or exact");
}

namespace {

long parse_int(const std::string& option, const std::string& text, long min, long max) {
    errno = 0;
    char* end = nullptr;
    const long v = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || errno == ERANGE)
        throw UsageError(option + ": '" + text + "' is not an integer");
    if (v < min || v > max)
        throw UsageError(option + ": " + text + " is out of range " + std::to_string(min) + ".." + std::to_string(max));
    return v;
}

// A finite float, 0 or of normal size (subnormals are refused: too small to compute with); `positive`
// additionally requires > 0.
float parse_float(const std::string& option, const std::string& text, bool positive) {
    errno = 0;
    char* end = nullptr;
    const float v = std::strtof(text.c_str(), &end);
    const bool out_of_range = errno == ERANGE;
    if (text.empty() || end == text.c_str() || *end != '\0') throw UsageError(option + ": '" + text + "' is not a number");
    if (std::isnan(v) || (std::isinf(v) && !out_of_range))
        throw UsageError(option + ": '" + text + "' is not a finite number");
    auto shortest = [](float limit) {
        char digits[32];
        std::snprintf(digits, sizeof digits, "%g", static_cast<double>(limit));
        return std::string(digits);
    };
    if (std::isinf(v))
        throw UsageError(option + ": " + text + " is too large for a float (the largest is " +
                         shortest(std::numeric_limits<float>::max()) + ")");
    if (out_of_range || (v != 0.0f && !std::isnormal(v)))
        throw UsageError(option + ": " + text + " is too small: below the smallest normal float (" +
                         shortest(std::numeric_limits<float>::min()) + "), it would be a subnormal number or 0");
    if (positive && !(v > 0.0f)) throw UsageError(option + ": must be > 0, got " + text);
    return v;
}

constexpr long max_image_side = 16384;

void parse_size(const std::string& text, Options& o) {
    const std::size_t x = text.find_first_of("xX");
    if (x == std::string::npos) throw UsageError("--size: '" + text + "' is not WIDTHxHEIGHT (for example 512x512)");
    o.width = static_cast<int>(parse_int("--size (width)", text.substr(0, x), 1, max_image_side));
    o.height = static_cast<int>(parse_int("--size (height)", text.substr(x + 1), 1, max_image_side));
}

} // namespace

Options parse_options(int argc, const char* const argv[]) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        std::string arg = argv[i];
        std::string value;
        bool has_inline_value = false;
        if (arg.rfind("--", 0) == 0) {
            const std::size_t eq = arg.find('=');
            if (eq != std::string::npos) {
                value = arg.substr(eq + 1);
                arg = arg.substr(0, eq);
                has_inline_value = true;
            }
        }
        auto flag = [&]() {
            if (has_inline_value) throw UsageError(arg + " takes no value");
        };
        auto next = [&]() -> std::string {
            if (has_inline_value) return value;
            if (i + 1 >= argc) throw UsageError(arg + " needs a value (see --help)");
            return argv[++i];
        };
        if (arg == "--help" || arg == "-h") { flag(); o.help = true; }
        else if (arg == "--scene") o.scene = next();
        else if (arg == "--mesh") {
            o.mesh = next();
            if (o.mesh.empty()) throw UsageError("--mesh: the file name is empty");
        }
        else if (arg == "--size") parse_size(next(), o);
        else if (arg == "--width") o.width = static_cast<int>(parse_int(arg, next(), 1, max_image_side));
        else if (arg == "--height") o.height = static_cast<int>(parse_int(arg, next(), 1, max_image_side));
        else if (arg == "--cache") o.cache = parse_cache_mode(next());
        else if (arg == "--face-size") {
            const std::string v = next();
            o.face_size = v == "auto" ? 0 : static_cast<int>(parse_int(arg, v, 1, 4096));
        }
        else if (arg == "--rays-per-texel") o.rays_per_texel = parse_float(arg, next(), true);
        else if (arg == "--filtered") { flag(); o.filtered = true; }
        else if (arg == "--warm-up") o.warm_up = static_cast<int>(parse_int(arg, next(), 0, 64));
        else if (arg == "--edge-threshold") o.edge_threshold = parse_float(arg, next(), false);
        else if (arg == "--origin-drift") o.origin_drift = parse_float(arg, next(), false);
        else if (arg == "--origin-parallax") {
            const std::string text = next();
            o.origin_parallax = text == "inf" ? std::numeric_limits<float>::infinity() : parse_float(arg, text, true);
        }
        else if (arg == "--invalidate") o.invalidate = parse_invalidation(next());
        else if (arg == "--delta") o.delta = parse_float(arg, next(), true);
        else if (arg == "--epsilon") o.epsilon = parse_float(arg, next(), true);
        else if (arg == "--max-steps") o.max_steps = static_cast<int>(parse_int(arg, next(), 1, 1 << 24));
        else if (arg == "--max-gap") {
            o.max_gap = parse_float(arg, next(), false);
            if (o.max_gap < 0.0f) throw UsageError("--max-gap: must be >= 0 (0 turns it off)");
        }
        else if (arg == "--no-pyramid") { flag(); o.pyramid = false; }
        else if (arg == "--cdct-search") {
            const std::string v = next();
            if (v != "secant" && v != "relief") throw UsageError("--cdct-search: '" + v + "' is not secant or relief");
            o.secant = v == "secant";
        }
        else if (arg == "--max-reads") o.max_reads = static_cast<int>(parse_int(arg, next(), 1, 64));
        else if (arg == "--prefill") { flag(); o.prefill = true; }
        else if (arg == "--load-cache" || arg == "--save-cache") {
            std::string& file = arg == "--load-cache" ? o.load_cache : o.save_cache;
            file = next();
            if (file.empty()) throw UsageError(arg + ": the file name is empty");
        }
        else if (arg == "--frames") o.frames = static_cast<int>(parse_int(arg, next(), 1, 1000000));
        else if (arg == "--step") o.step_degrees = parse_float(arg, next(), false);
        else if (arg == "--path") {
            const std::string v = next();
            try {
                o.path = parse_path_kind(v);
            } catch (const std::invalid_argument&) {
                throw UsageError("--path: unknown path '" + v + "'; use orbit, pan or fixed");
            }
        }
        else if (arg == "--depth") o.depth = static_cast<int>(parse_int(arg, next(), 0, 64));
        else if (arg == "--threads") o.threads = static_cast<int>(parse_int(arg, next(), 0, 4096));
        else if (arg == "--out") {
            o.out = next();
            if (o.out.empty()) throw UsageError("--out: the folder name is empty");
        }
        else if (arg == "--compare") { flag(); o.compare = true; }
        else if (arg == "--quiet" || arg == "-q") { flag(); o.quiet = true; }
        else if (arg == "--progress") { flag(); o.progress = true; }
        else throw UsageError("unknown option '" + std::string(argv[i]) + "' (see --help)");
    }
    if ((!o.load_cache.empty() || !o.save_cache.empty()) && !uses_caches(o.cache))
        throw UsageError(std::string(o.load_cache.empty() ? "--save-cache" : "--load-cache") + " needs --cache cct or cdct, not " +
                         to_string(o.cache));
    return o;
}

std::string help_text(const std::string& program) {
    return "Usage: " + program + " [options]\n"
        "Renders a scene's camera path frame by frame, one PNG per frame, caching the rays that leave\n"
        "reflective and refractive objects in per-object caching cubes (Ruff 2013).\n"
        "\n"
        "Scene and camera\n"
        "  --scene NAME        behind-N (N = 0..32), grid-N (N = 1..32), diffuse-31, reflective-32,\n"
        "                      cone-cylinder, concave, glass, mirrors-1000, dynamic-N (N = 1..256\n"
        "                      moving spheres and a moving mesh among mirrors)       [behind-32]\n"
        "  --mesh FILE         the concave object of scene concave (any format Assimp reads)\n"
        "                      [/usr/share/assimp/models/PLY/Wuson.ply, Debian: assimp-testmodels]\n"
        "  --size WxH          image size (or --width W --height H)                  [512x512]\n"
        "  --frames N          frames to render                      [the scene's path: 10]\n"
        "  --step DEGREES      camera rotation per frame             [the scene's path: 1]\n"
        "  --path KIND         orbit (eye around the target), pan (view around the eye), fixed\n"
        "  --depth N           maximum recursion depth (primary rays are depth 0)     [5]\n"
        "Cache\n"
        "  --cache MODE        off, cct (colour), cdct (colour + depth), ceiling (constant colour,\n"
        "                      no tracing: the best any cache could do)               [cct]\n"
        "  --face-size N|auto  texels per cube face side, 1..4096; auto: each cube's size\n"
        "                      follows the rays its object receives (Vulkan: the largest\n"
        "                      up to 512 whose cubes fit one storage buffer)          [auto]\n"
        "  --rays-per-texel F  auto: a frame's leaving rays per covered texel; smaller\n"
        "                      is sharper and fills more slowly (Embree tracer)       [1]\n"
        "  --filtered          CCT: bilinear lookups instead of the nearest texel (Embree tracer)\n"
        "  --edge-threshold F  CCT: texels differing from a neighbour by more than F are\n"
        "                      traced, not answered; negative: off (Embree tracer)   [0.1]\n"
        "  --origin-drift F    CCT: a tile met by a ray leaving further than F x the cube's\n"
        "                      half-size from its stores' origins refills; negative:\n"
        "                      off (Embree tracer)                                    [0.1]\n"
        "  --origin-parallax F CCT: ... or further than F x the distance to the nearest\n"
        "                      surface its rays hit (radians); inf: off (Embree)    [0.01]\n"
        "  --invalidate P      dynamic scenes (dynamic-N), when objects move: none (keep\n"
        "                      every texel), all (empty every cube) or exact (only the\n"
        "                      texels the moves can have changed; Embree tracer, CCT) [exact]\n"
        "  --cdct-search S     secant (a few texel reads, then a consistency test) or\n"
        "                      relief (the thesis's walk, over a depth pyramid)       [secant]\n"
        "  --max-reads N       CDCT secant: texel reads before a miss, 1..64          [8]\n"
        "  --delta F           CDCT relief search step, world units                   [0.2]\n"
        "  --epsilon F         CDCT: a hit lies within F of the cached surface        [0.02]\n"
        "  --max-steps N       CDCT relief: linear steps (or pyramid nodes) before a miss [1024]\n"
        "  --no-pyramid        CDCT relief: the thesis's fixed-step walk, no min-depth pyramid\n"
        "  --max-gap F         CDCT: a crossing F behind the cached surface is a miss  [0.5; 0 = off]\n"
        "  --prefill           trace every cube texel once before the first frame\n"
        "  --load-cache FILE   start warm: load the cubes saved in FILE before the first frame (the\n"
        "                      scene, objects and technique must match; Embree tracer)\n"
        "  --save-cache FILE   save the cubes to FILE after the last frame (Embree tracer)\n"
        "  --warm-up S         first frame: a pass over every S-th pixel in x and y first,\n"
        "                      whose stores the full pass reads (for single images;\n"
        "                      Embree tracer); 0: off                                 [0]\n"
        "Run\n"
        "  --threads N         worker threads, 0 = all cores                          [0]\n"
        "  --out DIR           folder for the PNGs (created when missing)             [out]\n"
        "  --compare           also render every frame with the cache off: speed-up, PSNR, mean/max\n"
        "                      error, and a difference PNG (blue = equal ... red = different)\n"
        "  --quiet             only the summary; no progress bar\n"
        "  --progress          draw the progress bar even when stderr is not a terminal\n"
        "  --help              this text\n"
        "Options take their value as '--name value' or '--name=value'. Exit status: 0 done, 2 bad input\n"
        "(including a run that needs more memory than is available: MemAvailable, or the environment's\n"
        "RCX_AVAILABLE_MEMORY=BYTES).\n";
}

SceneParams scene_params(const Options& options) {
    SceneParams p;
    if (!options.mesh.empty()) p.mesh_path = options.mesh;
    return p;
}

void apply_options(Scene& scene, const Options& options) {
    if (options.frames) scene.path.frames = *options.frames;
    if (options.step_degrees) scene.path.step_degrees = *options.step_degrees;
    if (options.path) scene.path.kind = *options.path;
    if (options.depth) scene.max_depth = *options.depth;
}

Scene scene_from_options(const Options& options) {
    Scene scene = make_scene(options.scene, scene_params(options));
    apply_options(scene, options);
    ensure_writable_directory(options.out);
    return scene;
}

namespace {

// Why a file or folder could not be created in the existing folder `folder` (errno `error`), in words a
// user can act on: the system's message alone misleads on virtual file systems, where creating a file in
// a folder that exists fails with "No such file or directory".
std::string why_nothing_can_be_created(const std::string& folder, int error) {
    const std::string system = std::strerror(error);
#ifdef __linux__
    struct statfs fs{};
    if (statfs(folder.c_str(), &fs) == 0) {
        const char* kind = nullptr;
        switch (static_cast<unsigned long>(fs.f_type)) {
        case PROC_SUPER_MAGIC: kind = "proc"; break;
        case SYSFS_MAGIC: kind = "sysfs"; break;
        case DEBUGFS_MAGIC: kind = "debugfs"; break;
        case TRACEFS_MAGIC: kind = "tracefs"; break;
        case CGROUP_SUPER_MAGIC: case CGROUP2_SUPER_MAGIC: kind = "cgroup"; break;
        default: break;
        }
        if (kind)
            return "'" + folder + "' is on the kernel's " + kind +
                   " file system, which only shows kernel state: no files can be created there (the system says: " +
                   system + ")";
    }
#endif
    switch (error) {
    case EACCES:
    case EPERM: return "no permission to create files in '" + folder + "' (" + system + ")";
    case EROFS: return "'" + folder + "' is on a read-only file system";
    case ENOSPC: return "the file system of '" + folder + "' is full";
    case EDQUOT: return "the disk quota for '" + folder + "' is used up";
    case ENOENT: return "the file system of '" + folder + "' does not let files be created there (" + system + ")";
    default: return "creating a file in '" + folder + "' failed: " + system;
    }
}

// The nearest folder that exists on the way to `path` (`path` itself when it exists).
std::filesystem::path nearest_existing(std::filesystem::path path) {
    std::error_code ec;
    path = std::filesystem::absolute(path, ec);
    while (!path.empty() && !std::filesystem::exists(path, ec) && path.has_relative_path()) path = path.parent_path();
    return path;
}

} // namespace

void ensure_writable_directory(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::exists(path, ec) && !fs::is_directory(path, ec))
        throw std::runtime_error("output folder '" + path + "' is a file, not a folder; choose another --out");
    fs::create_directories(path, ec);
    if (ec) {
        const fs::path parent = nearest_existing(path);
        throw std::runtime_error("cannot create output folder '" + path + "': " +
                                 (fs::is_directory(parent) ? why_nothing_can_be_created(parent.string(), ec.value())
                                                           : ec.message()) +
                                 "; choose another --out");
    }
    // Probe with a real file: permissions alone do not tell (read-only mounts, ACLs, root, virtual file systems).
    const fs::path probe = fs::path(path) / (".rcx-write-test-" + std::to_string(
        std::chrono::steady_clock::now().time_since_epoch().count()));
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0)
        throw std::runtime_error("cannot write into output folder '" + path + "': " + why_nothing_can_be_created(path, errno) +
                                 "; choose another --out");
    const bool written = ::write(fd, "x", 1) == 1;
    const int write_error = errno;
    ::close(fd);
    fs::remove(probe, ec);
    if (!written)
        throw std::runtime_error("cannot write into output folder '" + path + "': " +
                                 why_nothing_can_be_created(path, write_error) + "; choose another --out");
}

} // namespace rcx
