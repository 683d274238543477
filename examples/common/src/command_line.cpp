// The example tracers' command line on CLI11 (rcx/command_line.hpp): the shared options, --help, and
// CLI11's errors in the words of UsageError.
#include "rcx/command_line.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <system_error>
#include <thread>
#include <utility>

#include <CLI/CLI.hpp>

#include "rcx/option_values.hpp"

namespace rcx {

namespace {

// CLI11's layout with the usage line first and the description under it (CLI11 puts the description
// above the usage line), and one blank line between sections (CLI11 puts two); the rest (sections
// "Heading:", a 22-character name column) is CLI11's.
class HelpLayout : public CLI::Formatter {
public:
    HelpLayout() { column_width(22); }
    std::string make_description(const CLI::App*) const override { return ""; }
    std::string make_usage(const CLI::App* app, std::string name) const override {
        return CLI::Formatter::make_usage(app, std::move(name)) + app->get_description() + "\n\n";
    }
    std::string make_group(std::string group, bool is_positional, std::vector<const CLI::Option*> options) const override {
        const std::string text = CLI::Formatter::make_group(std::move(group), is_positional, std::move(options));
        return text.substr(text.find_first_not_of('\n'));
    }
};

// The --help section of the options that tune the cubes.
const char* const cache_section = "Cache";

// A value from `names` for messages: its long name ("--quiet" for "-q,--quiet").
std::string long_name(const CLI::Option& option) { return option.get_name(false, false); }

// CLI11's argument-count errors begin with the option's name: "--frames: 1 required N missing" (no value)
// and "compare was given a disallowed flag override" (a value for a flag; the name without dashes).
// They become the messages this command line always gave; anything else keeps CLI11's words.
UsageError in_our_words(const CLI::ArgumentMismatch& error, const CLI::App& app) {
    const std::string what = error.what();
    auto starts_with = [&](const std::string& prefix) { return what.rfind(prefix, 0) == 0; };
    for (const CLI::Option* option : app.get_options()) {
        const std::string name = long_name(*option);
        if (starts_with(name + ": ") && what.find(" missing") != std::string::npos)
            return UsageError(name + " needs a value (see --help)");
        for (const std::string& spelling : option->get_lnames())
            if (starts_with(spelling + " was given a disallowed flag override")) return UsageError(name + " takes no value");
        for (const std::string& spelling : option->get_snames())
            if (starts_with(spelling + " was given a disallowed flag override")) return UsageError(name + " takes no value");
    }
    return UsageError(what);
}

// Arguments CLI11 matched to no option (it is told to keep them, so that the first can be named).
UsageError unexpected(const std::string& argument) {
    if (argument.size() > 1 && argument[0] == '-') return UsageError("unknown option '" + argument + "' (see --help)");
    return UsageError("unexpected argument '" + argument + "': the tracers take options only, each starting with -- (see --help)");
}

} // namespace

std::string shown_default(const std::string& value) { return "[" + value + "]"; }

std::string shown_default(float value) {
    char digits[32];
    std::snprintf(digits, sizeof digits, "%g", static_cast<double>(value));
    return shown_default(std::string(digits));
}

CommandLine::CommandLine(const std::string& program)
    : app_(std::make_unique<CLI::App>(
          "Renders a scene's camera path frame by frame, one PNG per frame, caching the rays that leave\n"
          "reflective and refractive objects in per-object caching cubes (Ruff 2013).",
          program)) {
    CLI::App& app = *app_;
    app.formatter(std::make_shared<HelpLayout>());
    app.set_help_flag(); // --help is an option like the others: parse() reports it in Options::help
    app.allow_extras();  // unknown arguments are reported by parse(), by name
    add_note(""); // the closing lines

    Options& o = options_;
    const Options d; // the defaults --help shows
    auto integer = [](const char* option, int& target, long min, long max) {
        return [option, &target, min, max](const std::string& text) {
            target = static_cast<int>(parse_int_value(option, text, min, max));
        };
    };
    auto number = [](const char* option, float& target, bool positive) {
        return [option, &target, positive](const std::string& text) { target = parse_float_value(option, text, positive); };
    };
    auto file = [](const char* option, std::string& target, const char* what) {
        return [option, &target, what](const std::string& text) {
            if (text.empty()) throw UsageError(std::string(option) + ": the " + what + " name is empty");
            target = text;
        };
    };

    section("Scene and camera");
    add_option("--scene", "NAME",
               "behind-N (N = 0..32), grid-N (N = 1..32), diffuse-31, reflective-32,\n"
               "cone-cylinder, concave, glass, mirrors-1000, dynamic-N (N = 1..256\n"
               "moving spheres and a moving mesh among mirrors) " + shown_default(d.scene),
               [&o](const std::string& text) { o.scene = text; });
    add_option("--mesh", "FILE",
               "the concave object of scene concave (any format Assimp reads)\n" +
                   shown_default(SceneParams{}.mesh_path + ", Debian: assimp-testmodels"),
               file("--mesh", o.mesh, "file"));
    add_option("--size", "WxH",
               "image size (or --width W --height H) " +
                   shown_default(std::to_string(d.width) + "x" + std::to_string(d.height)),
               [&o](const std::string& text) {
                   const ImageSize size = parse_image_size("--size", text);
                   o.width = size.width;
                   o.height = size.height;
               });
    add_option("--width", "W", "image width, 1.." + std::to_string(max_image_side),
               integer("--width", o.width, 1, max_image_side));
    add_option("--height", "H", "image height, 1.." + std::to_string(max_image_side),
               integer("--height", o.height, 1, max_image_side));
    add_option("--frames", "N", "frames to render [the scene's path: 10]", [&o](const std::string& text) {
        o.frames = static_cast<int>(parse_int_value("--frames", text, 1, 1000000));
    });
    add_option("--step", "DEGREES", "camera rotation per frame, -360..360 [the scene's path: 1]", [&o](const std::string& text) {
        const float step = parse_float_value("--step", text, false);
        // Larger steps repeat these; and a frame's angle, step x frame, must stay finite.
        if (!(std::abs(step) <= 360.0f)) throw UsageError("--step: " + text + " is out of range -360..360");
        o.step_degrees = step;
    });
    add_option("--path", "KIND", "orbit (eye around the target), pan (view around the eye), fixed",
               [&o](const std::string& text) {
                   try {
                       o.path = parse_path_kind(text);
                   } catch (const std::invalid_argument&) {
                       throw UsageError("--path: unknown path '" + text + "'; use orbit, pan or fixed");
                   }
               });
    add_option("--depth", "N", "maximum recursion depth (primary rays are depth 0) [5]",
               [&o](const std::string& text) { o.depth = static_cast<int>(parse_int_value("--depth", text, 0, 64)); });
    add_option("--light-samples", "N",
               "soft shadows: N shadow rays per shaded hit to a disc-shaped light,\n"
               "1..256; makes every traced ray costlier (Embree tracer) " + shown_default(std::to_string(d.light_samples)),
               integer("--light-samples", o.light_samples, 1, 256));
    add_option("--light-radius", "F", "the light's disc radius with --light-samples > 1 " + shown_default(d.light_radius),
               number("--light-radius", o.light_radius, true));

    section(cache_section);
    add_option("--cache", "MODE",
               "off, cct (colour), cdct (colour + depth), ceiling (constant colour,\n"
               "no tracing: the best any cache could do) " + shown_default(to_string(d.cache)),
               [&o](const std::string& text) { o.cache = parse_cache_mode(text); });
    add_option("--face-size", "N|auto",
               "texels per cube face side, 1..4096; auto: each cube's size follows\n"
               "the rays its object receives (Vulkan: within one storage buffer) [auto]",
               [&o](const std::string& text) {
                   o.face_size = text == "auto" ? 0 : static_cast<int>(parse_int_value("--face-size", text, 1, 4096));
               });
    add_option("--rays-per-texel", "F",
               "auto: a frame's leaving rays per covered texel; smaller is sharper\n"
               "and fills more slowly " + shown_default(d.rays_per_texel),
               number("--rays-per-texel", o.rays_per_texel, true));
    add_option("--still-rays-per-texel", "F",
               "auto: the same once a cube's rays hold still (a still camera: the same\n"
               "rays come back to its texels); >= --rays-per-texel: off " + shown_default(d.still_rays_per_texel),
               number("--still-rays-per-texel", o.still_rays_per_texel, true));
    add_option("--first-face-size", "N",
               "auto: the face size cubes start at, 8..1024 (the sizes adaptive cubes\n"
               "take); smaller makes a first frame cheaper and its cubes coarser [" + std::to_string(d.first_face_size) + "]",
               [&o](const std::string& text) {
                   // raycache::AdaptiveResolution's min_face_size and max_face_size, which it must lie within.
                   o.first_face_size = static_cast<int>(parse_int_value("--first-face-size", text, 8, 1024));
               });
    add_option("--budget-mib", "N",
               "memory all cubes may take, 1..1048576 MiB; when they reach it, the\n"
               "Embree tracer keeps no new tiles that frame, the Vulkan tracer lowers\n"
               "the largest cubes' faces [" + std::to_string(d.budget_mib) + "]",
               [&o](const std::string& text) { o.budget_mib = static_cast<int>(parse_int_value("--budget-mib", text, 1, 1l << 20)); });
    add_flag("--filtered", o.filtered, "CCT: bilinear lookups instead of the nearest texel (Embree tracer)");
    add_flag("--trace-hits", o.trace_hits,
             "diagnostics: rays the cubes answer are traced anyway, so frames\n"
             "equal uncached ones and what a frame takes beyond an uncached one\n"
             "is the cache's own work (Embree tracer)");
    add_option("--min-hit-rate", "F",
               "a cube whose rays found fewer hits than this share in a frame\n"
               "rests: its rays are traced, but for a sixteenth of the directions\n"
               "(down to 1 in 256 while they find it still does not pay), which\n"
               "keep measuring it; 0: cubes never rest [Embree tracer: each\n"
               "cube's break-even, --lookup-work / the rays its traced rays took;\n"
               "Vulkan tracer: CCT 0.5, CDCT 0.6]",
               [&o](const std::string& text) {
                   o.min_hit_rate = parse_float_value("--min-hit-rate", text, false);
                   if (!(o.min_hit_rate >= 0.0f)) throw UsageError("--min-hit-rate: must be >= 0, got '" + text + "'");
               });
    add_option("--lookup-work", "F",
               "what a lookup costs, in rays traced: a cube pays when its hits save\n"
               "more than its lookups cost; <= 0: CCT 0.5, CDCT 0.6 whatever rays\n"
               "cost (Embree tracer) [CCT 1, CDCT 2]",
               [&o](const std::string& text) { o.lookup_work = parse_float_value("--lookup-work", text, false); });
    add_option("--edge-threshold", "F",
               "texels differing in colour from a neighbour by more than F are\n"
               "traced, not answered (CCT and CDCT); negative: off " + shown_default(d.edge_threshold),
               number("--edge-threshold", o.edge_threshold, false));
    add_option("--origin-drift", "F",
               "CCT: a tile met by a ray leaving further than F x the cube's\n"
               "half-size from its stores' origins refills; negative: off " + shown_default(d.origin_drift),
               number("--origin-drift", o.origin_drift, false));
    add_option("--origin-parallax", "F",
               "CCT: ... or further than F x the distance to the nearest surface\n"
               "its rays hit (radians); inf: off " + shown_default(d.origin_parallax),
               [&o](const std::string& text) {
                   o.origin_parallax = text == "inf" ? std::numeric_limits<float>::infinity()
                                                     : parse_float_value("--origin-parallax", text, true);
               });
    add_option("--invalidate", "P",
               "dynamic scenes (dynamic-N), when objects move: none (keep every\n"
               "texel), all (empty every cube) or exact (only the texels the moves\n"
               "can have changed; Embree tracer, CCT) " + shown_default(to_string(d.invalidate)),
               [&o](const std::string& text) { o.invalidate = parse_invalidation(text); });
    add_option("--cdct-search", "S",
               "secant (a few texel reads, then a consistency test) or relief (the\n"
               "thesis's walk, over a depth pyramid) " + shown_default(d.secant ? "secant" : "relief"),
               [&o](const std::string& text) {
                   if (text != "secant" && text != "relief")
                       throw UsageError("--cdct-search: '" + text + "' is not secant or relief");
                   o.secant = text == "secant";
               });
    add_option("--max-reads", "N", "CDCT secant: texel reads before a miss, 1..64 " + shown_default(std::to_string(d.max_reads)),
               integer("--max-reads", o.max_reads, 1, 64));
    add_option("--delta", "F", "CDCT relief search step, world units " + shown_default(d.delta),
               number("--delta", o.delta, true));
    add_option("--epsilon", "F", "CDCT: a hit lies within F of the cached surface " + shown_default(d.epsilon),
               number("--epsilon", o.epsilon, true));
    add_option("--max-steps", "N",
               "CDCT relief: linear steps (or pyramid nodes) before a miss " + shown_default(std::to_string(d.max_steps)),
               integer("--max-steps", o.max_steps, 1, 1 << 24));
    add_flag("--no-pyramid", no_pyramid_, "CDCT relief: the thesis's fixed-step walk, no min-depth pyramid");
    add_option("--max-gap", "F",
               "CDCT: a crossing F behind the cached surface is a miss; 0: off " + shown_default(d.max_gap),
               [&o](const std::string& text) {
                   o.max_gap = parse_float_value("--max-gap", text, false);
                   if (o.max_gap < 0.0f) throw UsageError("--max-gap: must be >= 0 (0 turns it off)");
               });
    add_flag("--prefill", o.prefill, "trace every cube texel once before the first frame");
    add_option("--load-cache", "FILE",
               "start warm: load the cubes saved in FILE before the first frame (the\n"
               "scene, objects and technique must match)",
               file("--load-cache", o.load_cache, "file"));
    add_option("--save-cache", "FILE", "save the cubes to FILE after the last frame",
               file("--save-cache", o.save_cache, "file"));
    add_option("--warm-up", "S",
               "first frame: a pass over every S-th pixel in x and y first, whose\n"
               "stores the full pass reads (for single images);\n"
               "0: off " + shown_default(std::to_string(d.warm_up)),
               integer("--warm-up", o.warm_up, 0, 64));

    section("Run");
    add_option("--threads", "N", "worker threads, 0 = all cores " + shown_default(std::to_string(d.threads)),
               integer("--threads", o.threads, 0, 4096));
    add_option("--out", "DIR", "folder for the PNGs (created when missing) " + shown_default(d.out),
               file("--out", o.out, "folder"));
    add_flag("--compare", o.compare,
             "also render every frame with the cache off: speed-up, PSNR, mean/max\n"
             "error, and a difference PNG (blue = equal ... red = different)");
    add_flag("-q,--quiet", o.quiet, "only the summary; no progress bar");
    add_flag("--progress", o.progress, "draw the progress bar even when stderr is not a terminal");
    add_flag("-h,--help", o.help, "this text");
}

CommandLine::~CommandLine() = default;

void CommandLine::section(const std::string& heading) { section_ = heading; }

void CommandLine::add_option(const std::string& names, const std::string& value, const std::string& description,
                             std::function<void(const std::string& text)> store) {
    app_->add_option_function<std::string>(names, std::move(store), description)
        ->type_name(value)
        ->group(section_)
        ->trigger_on_parse() // stored as met, so "--size 8x8 --width 9" means what it says
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
}

void CommandLine::ignore_threads(const std::string& why) { threads_ignored_ = why; }

void CommandLine::add_note(const std::string& paragraph) {
    if (!paragraph.empty()) notes_ += paragraph + "\n\n";
    app_->footer(notes_ + "Options take their value as '--name value' or '--name=value'. Exit status: 0 done, 2 bad input\n"
                          "(including a run that needs more memory than is available: MemAvailable, or the environment's\n"
                          "RCX_AVAILABLE_MEMORY=BYTES).");
}

void CommandLine::add_flag(const std::string& names, bool& target, const std::string& description) {
    app_->add_flag(names, target, description)->group(section_)->disable_flag_override();
}

Options CommandLine::parse(int argc, const char* const argv[]) {
    // CLI11 reads "--name=" as "--name" and takes the next argument as the value; refuse it instead.
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg.size() > 3 && arg.rfind("--", 0) == 0 && arg.find('=') == arg.size() - 1)
            throw UsageError(arg.substr(0, arg.size() - 1) + ": nothing after '='");
    }
    try {
        app_->parse(argc, argv);
    } catch (const CLI::ArgumentMismatch& e) {
        throw in_our_words(e, *app_);
    } catch (const CLI::ParseError& e) {
        throw UsageError(e.what());
    }
    if (!app_->remaining().empty()) throw unexpected(app_->remaining().front());
    Options& o = options_;
    o.pyramid = !no_pyramid_;
    // The cache section's options tune cubes: a mode that keeps none (off, ceiling) runs as if they were not given.
    if (!uses_caches(o.cache))
        for (const CLI::Option* option : app_->get_options())
            if (option->get_group() == cache_section && option->count() > 0 && long_name(*option) != "--cache")
                o.notes.push_back(long_name(*option) + " has no effect with --cache " + to_string(o.cache));
    // A thread arena wider than the cores gets no more workers (TBB says so in a warning of its own): the
    // run takes the cores, and its frames are the same with any number of threads. A tracer that chooses
    // no threads says so instead.
    const unsigned cores = std::thread::hardware_concurrency();
    if (!threads_ignored_.empty()) {
        if (app_->get_option("--threads")->count() > 0) o.notes.push_back("--threads has no effect: " + threads_ignored_);
    } else if (cores > 0 && o.threads > static_cast<int>(cores)) {
        o.notes.push_back("--threads " + std::to_string(o.threads) + ": this machine has " + std::to_string(cores) +
                          " hardware threads; running " + std::to_string(cores));
        o.threads = static_cast<int>(cores);
    }
    const std::string cache_file = o.load_cache.empty() ? "--save-cache" : "--load-cache";
    if ((!o.load_cache.empty() || !o.save_cache.empty()) && !uses_caches(o.cache))
        throw UsageError(cache_file + " needs --cache cct or cdct, not " + to_string(o.cache));
    // A dynamic scene's cubes are saved where its objects are after the last frame, and a run starts them
    // where its first frame puts them: no file would load back.
    if ((!o.load_cache.empty() || !o.save_cache.empty()) && o.scene.rfind("dynamic-", 0) == 0)
        throw UsageError(cache_file + " does not work with the moving objects of " + o.scene);
    // Saving renames a new file over the old one: a folder, a device or a pipe there must not be replaced.
    std::error_code error;
    if (!o.save_cache.empty() && std::filesystem::exists(o.save_cache, error) && !std::filesystem::is_regular_file(o.save_cache, error))
        throw UsageError("--save-cache: '" + o.save_cache + "' exists and is not a regular file");
    return o;
}

std::string CommandLine::help() const { return app_->help(); }

Options parse_options(int argc, const char* const argv[]) { return CommandLine("tracer").parse(argc, argv); }

std::string help_text(const std::string& program) { return CommandLine(program).help(); }

} // namespace rcx
