// The example tracers' shared command line (rcx/options.hpp, rcx/command_line.hpp on CLI11): values,
// defaults, --help, and errors a user can act on.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "rcx/command_line.hpp"
#include "rcx/option_values.hpp"
#include "rcx/options.hpp"
#include "rcx/tracer_main.hpp"

#include <raycache/adaptive_resolution.hpp>

#include <unistd.h>

namespace {

rcx::Options parse(std::vector<const char*> args) {
    args.insert(args.begin(), "tracer");
    return rcx::parse_options(static_cast<int>(args.size()), args.data());
}

} // namespace

TEST_CASE("options parse in both spellings and keep their defaults otherwise") {
    const rcx::Options d = parse({});
    CHECK(d.scene == "behind-32");
    CHECK(d.width == 512);
    CHECK(d.height == 512);
    CHECK(d.cache == rcx::CacheMode::cct);
    CHECK_FALSE(d.frames.has_value());
    CHECK_FALSE(d.compare);

    const rcx::Options o = parse({"--scene", "glass", "--size=640x360", "--cache", "cdct", "--face-size", "128",
                                  "--delta=0.4", "--epsilon", "0.05", "--max-steps", "64", "--frames", "3", "--step",
                                  "-2.5", "--path", "pan", "--depth", "2", "--threads", "1", "--out", "somewhere",
                                  "--compare", "--quiet", "--progress"});
    CHECK(o.scene == "glass");
    CHECK(o.width == 640);
    CHECK(o.height == 360);
    CHECK(o.cache == rcx::CacheMode::cdct);
    CHECK(o.face_size == 128);
    CHECK(o.delta == doctest::Approx(0.4f));
    CHECK(o.epsilon == doctest::Approx(0.05f));
    CHECK(o.max_steps == 64);
    CHECK(*o.frames == 3);
    CHECK(*o.step_degrees == doctest::Approx(-2.5f));
    CHECK(*o.path == rcx::CameraPath::Kind::pan);
    CHECK(*o.depth == 2);
    CHECK(o.threads == 1);
    CHECK(o.out == "somewhere");
    CHECK(o.compare);
    CHECK(o.quiet);
    CHECK(o.progress);
    CHECK(parse({"--width", "7", "--height", "9"}).width == 7);
    CHECK(parse({"--help"}).help);

    rcx::Scene scene = rcx::make_scene("behind-1");
    rcx::apply_options(scene, o);
    CHECK(scene.path.frames == 3);
    CHECK(scene.path.kind == rcx::CameraPath::Kind::pan);
    CHECK(scene.max_depth == 2);
    CHECK(scene.light.samples == 1); // a point light unless asked
    CHECK(scene.light.radius == 0.0f);

    CHECK_FALSE(d.lookup_work.has_value());
    CHECK(*parse({"--lookup-work", "2.5"}).lookup_work == 2.5f);
    CHECK(*parse({"--lookup-work=-1"}).lookup_work == -1.0f); // thresholds ignore work

    const rcx::Options soft = parse({"--light-samples", "16", "--light-radius=0.5"});
    rcx::apply_options(scene, soft);
    CHECK(scene.light.samples == 16);
    CHECK(scene.light.radius == 0.5f);
    rcx::apply_options(scene, parse({"--light-radius", "0.5"})); // a radius alone keeps the point light
    CHECK(scene.light.samples == 1);
    CHECK(scene.light.radius == 0.0f);
}

TEST_CASE("bad command lines throw UsageError naming the option") {
    auto fails = [](std::vector<const char*> args, const char* mentioned) {
        CAPTURE(mentioned);
        CHECK_THROWS_WITH_AS(parse(args), doctest::Contains(mentioned), rcx::UsageError);
    };
    fails({"--bogus"}, "--bogus");
    fails({"--light-samples", "0"}, "--light-samples");
    fails({"--light-samples", "257"}, "--light-samples");
    fails({"--light-radius", "0"}, "--light-radius");
    fails({"--lookup-work", "nan"}, "--lookup-work");
    fails({"--frames"}, "--frames");
    fails({"--frames", "ten"}, "ten");
    fails({"--frames", "0"}, "--frames");
    fails({"--size", "512"}, "--size");
    fails({"--size", "512x"}, "--size");
    fails({"--size", "0x4"}, "--size");
    fails({"--face-size", "5000"}, "--face-size");
    fails({"--delta", "-1"}, "--delta");
    fails({"--epsilon", "nan"}, "--epsilon");
    fails({"--cache", "lru"}, "lru");
    fails({"--path", "spiral"}, "orbit");
    fails({"--threads", "1.5"}, "--threads");
    fails({"--compare=yes"}, "--compare");
    fails({"positional"}, "positional");
    CHECK(rcx::help_text("tracer").find("--face-size") != std::string::npos);
}

TEST_CASE("an output folder is created, and one that cannot be written throws with its path") {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "raycache-test-options-out" / "nested";
    std::filesystem::remove_all(dir.parent_path());
    rcx::ensure_writable_directory(dir.string());
    CHECK(std::filesystem::is_directory(dir));
    CHECK(std::filesystem::is_empty(dir)); // the probe file is gone
    std::filesystem::remove_all(dir.parent_path());
    CHECK_THROWS_WITH_AS(rcx::ensure_writable_directory("/proc/raycache-out"), doctest::Contains("/proc/raycache-out"),
                         std::runtime_error);
    CHECK_THROWS_WITH_AS(rcx::ensure_writable_directory("/etc/hostname"), doctest::Contains("not a folder"),
                         std::runtime_error);
}

TEST_CASE("--load-cache and --save-cache take a file name and need a caching mode") {
    const rcx::Options o = parse({"--cache", "cdct", "--load-cache", "in.rcc", "--save-cache=out.rcc"});
    CHECK(o.load_cache == "in.rcc");
    CHECK(o.save_cache == "out.rcc");
    CHECK(parse({}).load_cache.empty());
    CHECK(parse({}).save_cache.empty());
    CHECK_THROWS_WITH_AS(parse({"--load-cache", ""}), doctest::Contains("--load-cache: the file name is empty"), rcx::UsageError);
    CHECK_THROWS_WITH_AS(parse({"--save-cache"}), doctest::Contains("--save-cache needs a value"), rcx::UsageError);
    CHECK_THROWS_WITH_AS(parse({"--cache", "off", "--save-cache", "x.rcc"}),
                         doctest::Contains("--save-cache needs --cache cct or cdct, not off"), rcx::UsageError);
    CHECK_THROWS_WITH_AS(parse({"--cache", "ceiling", "--load-cache", "x.rcc"}),
                         doctest::Contains("--load-cache needs --cache cct or cdct, not ceiling"), rcx::UsageError);
    CHECK(rcx::help_text("tracer").find("--save-cache FILE") != std::string::npos);
    // A dynamic scene's cubes end where its objects moved to: refused before a frame is rendered.
    CHECK_THROWS_WITH_AS(parse({"--scene", "dynamic-4", "--save-cache", "x.rcc"}),
                         doctest::Contains("--save-cache does not work with the moving objects of dynamic-4"), rcx::UsageError);
    CHECK_THROWS_WITH_AS(parse({"--scene", "dynamic-4", "--load-cache", "x.rcc"}), doctest::Contains("--load-cache"), rcx::UsageError);
    // Saving renames a new file over the target: a folder or a device there is refused, a regular file taken.
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "raycache-test-options-save";
    std::filesystem::create_directories(dir);
    CHECK_THROWS_WITH_AS(parse({"--save-cache", dir.c_str()}), doctest::Contains("exists and is not a regular file"), rcx::UsageError);
    CHECK_THROWS_WITH_AS(parse({"--save-cache", "/dev/null"}), doctest::Contains("exists and is not a regular file"), rcx::UsageError);
    const std::string file = (dir / "old.rcc").string();
    std::ofstream(file) << "an earlier save";
    CHECK(parse({"--save-cache", file.c_str()}).save_cache == file);
    std::filesystem::remove_all(dir);
}

TEST_CASE("numbers too small or too large for a float are called that, not 'not a finite number'") {
    auto message = [](std::vector<const char*> args) -> std::string {
        try {
            parse(args);
        } catch (const rcx::UsageError& e) {
            return e.what();
        }
        return "(accepted)";
    };
    const std::string tiny = message({"--delta", "1e-45"}); // a subnormal float
    CHECK(tiny.find("--delta") != std::string::npos);
    CHECK(tiny.find("too small") != std::string::npos);
    CHECK(tiny.find("subnormal") != std::string::npos);
    CHECK(tiny.find("finite") == std::string::npos);
    CHECK(message({"--epsilon", "1e-50"}).find("too small") != std::string::npos); // below every float
    CHECK(message({"--step", "-1e-40"}).find("too small") != std::string::npos);
    CHECK(message({"--delta", "1e39"}).find("too large") != std::string::npos);
    CHECK(message({"--epsilon", "nan"}).find("not a finite number") != std::string::npos);
    CHECK(message({"--delta", "inf"}).find("not a finite number") != std::string::npos);
    CHECK(message({"--delta", "fast"}).find("'fast' is not a number") != std::string::npos);
    CHECK(parse({"--delta", "1e-30"}).delta == doctest::Approx(1e-30f).epsilon(1e-6)); // small but normal
    CHECK(parse({"--step", "0"}).step_degrees == 0.0f);
}

TEST_CASE("an output folder on the kernel's proc file system is refused as such, not as 'no such file'") {
    for (const char* path : {"/proc/sys", "/proc/raycache-out"}) {
        CAPTURE(path);
        CHECK_THROWS_WITH_AS(rcx::ensure_writable_directory(path), doctest::Contains("proc file system"), std::runtime_error);
        CHECK_THROWS_WITH_AS(rcx::ensure_writable_directory(path), doctest::Contains("no files can be created there"),
                             std::runtime_error);
    }
}

namespace {

// The message parse() throws for `args`, or "(accepted)".
std::string usage_error(std::vector<const char*> args) {
    try {
        parse(args);
    } catch (const rcx::UsageError& e) {
        return e.what();
    }
    return "(accepted)";
}

} // namespace

TEST_CASE("arguments CLI11 matches to no option are named in our words") {
    CHECK(usage_error({"--bogus"}) == "unknown option '--bogus' (see --help)");
    CHECK(usage_error({"--bogus=3"}) == "unknown option '--bogus=3' (see --help)");
    CHECK(usage_error({"-x"}) == "unknown option '-x' (see --help)");
    CHECK(usage_error({"positional"}) ==
          "unexpected argument 'positional': the tracers take options only, each starting with -- (see --help)");
    CHECK(usage_error({"--frames", "3", "4"}) ==
          "unexpected argument '4': the tracers take options only, each starting with -- (see --help)");
    CHECK(usage_error({"--secondary", "rsh"}) == "unknown option '--secondary' (see --help)"); // the Vulkan tracer's own
}

TEST_CASE("a missing value, a value for a flag and an empty '--name=' are refused naming the option") {
    CHECK(usage_error({"--frames"}) == "--frames needs a value (see --help)");
    CHECK(usage_error({"--quiet", "--out"}) == "--out needs a value (see --help)");
    CHECK(usage_error({"--compare=yes"}) == "--compare takes no value");
    CHECK(usage_error({"--quiet=no"}) == "--quiet takes no value");
    CHECK(usage_error({"--help=1"}) == "--help takes no value");
    // CLI11 would take the next argument as the value of "--out="; refused instead.
    CHECK(usage_error({"--out=", "--compare"}) == "--out: nothing after '='");
    CHECK(usage_error({"--frames="}) == "--frames: nothing after '='");
}

TEST_CASE("options apply in command-line order: the last of a repeated option wins") {
    CHECK(*parse({"--frames", "3", "--frames=4"}).frames == 4);
    const rcx::Options size_then_width = parse({"--size", "8x8", "--width", "9"});
    CHECK(size_then_width.width == 9);
    CHECK(size_then_width.height == 8);
    CHECK(parse({"--width", "9", "--size", "8x8"}).width == 8);
    CHECK(parse({"--cache", "off", "--cache", "cdct"}).cache == rcx::CacheMode::cdct);
    // The first bad value on the command line is the one reported.
    CHECK(usage_error({"--frames", "x", "--depth", "y"}) == "--frames: 'x' is not an integer");
}

TEST_CASE("values: negative numbers, short flags, inf and auto keep their meaning") {
    CHECK(*parse({"--step", "-2.5"}).step_degrees == doctest::Approx(-2.5f));
    CHECK(parse({"--edge-threshold=-1"}).edge_threshold == -1.0f);
    CHECK(usage_error({"--threads", "-5"}) == "--threads: -5 is out of range 0..4096");
    CHECK(usage_error({"--frames", "0x10"}) == "--frames: '0x10' is not an integer"); // CLI11's own conversion takes hex
    CHECK(parse({"-q"}).quiet);
    CHECK(parse({"-h"}).help);
    CHECK(std::isinf(parse({"--origin-parallax", "inf"}).origin_parallax));
    CHECK(usage_error({"--origin-parallax", "0"}) == "--origin-parallax: must be > 0, got 0");
    CHECK(parse({"--face-size", "auto"}).face_size == 0);
    CHECK(parse({"--face-size=64"}).face_size == 64);
    CHECK(usage_error({"--face-size", "big"}) == "--face-size: 'big' is not an integer");
    CHECK(parse({}).first_face_size == 256); // raycache::AdaptiveResolution's default
    CHECK(parse({}).still_rays_per_texel == raycache::AdaptiveResolution{}.still_rays_per_texel);
    CHECK(parse({"--still-rays-per-texel", "0.5"}).still_rays_per_texel == 0.5f);
    CHECK(usage_error({"--still-rays-per-texel", "0"}) == "--still-rays-per-texel: must be > 0, got 0");
    CHECK(parse({"--first-face-size", "64"}).first_face_size == 64);
    CHECK(usage_error({"--first-face-size", "0"}) == "--first-face-size: 0 is out of range 8..1024");
    CHECK(usage_error({"--first-face-size", "2048"}) == "--first-face-size: 2048 is out of range 8..1024");
    // The range is AdaptiveResolution's own: its ends pass validate(), one step outside does not.
    raycache::AdaptiveResolution a;
    for (const char* first : {"8", "1024"}) {
        a.first_face_size = parse({"--first-face-size", first}).first_face_size;
        CHECK_NOTHROW(raycache::validate(a));
    }
    for (const int first : {7, 1025}) {
        a.first_face_size = first;
        CHECK_THROWS_WITH_AS(raycache::validate(a), doctest::Contains("first_face_size"), std::invalid_argument);
    }
    CHECK(usage_error({"--size", "8"}) == "--size: '8' is not WIDTHxHEIGHT (for example 512x512)");
    CHECK(usage_error({"--cdct-search", "walk"}) == "--cdct-search: 'walk' is not secant or relief");
    CHECK_FALSE(parse({"--cdct-search", "relief"}).secant);
    CHECK(usage_error({"--invalidate", "some"}) == "--invalidate: unknown policy 'some'; use none, all or exact");
    CHECK(parse({"--invalidate=none"}).invalidate == rcx::InvalidationPolicy::none);
    CHECK(usage_error({"--cache", "lru"}) == "--cache: unknown mode 'lru'; use off, cct, cdct or ceiling");
    CHECK(usage_error({"--max-gap", "-1"}) == "--max-gap: must be >= 0 (0 turns it off)");
    CHECK_FALSE(parse({"--no-pyramid"}).pyramid);
    CHECK(parse({}).pyramid);
}

TEST_CASE("--help lists every option by section, with the defaults of rcx::Options in brackets") {
    const std::string help = rcx::help_text("tracer");
    CHECK(help.rfind("Usage: tracer [OPTIONS]\n", 0) == 0);
    for (const char* section : {"\nScene and camera:\n", "\nCache:\n", "\nRun:\n"}) {
        CAPTURE(section);
        CHECK(help.find(section) != std::string::npos);
    }
    for (const char* line : {"  --size WxH          image size (or --width W --height H) [512x512]\n",
                             "  --delta F           CDCT relief search step, world units [0.2]\n",
                             "  --threads N         worker threads, 0 = all cores [0]\n",
                             "  -q,--quiet          only the summary; no progress bar\n"}) {
        CAPTURE(line);
        CHECK(help.find(line) != std::string::npos);
    }
    CHECK(help.find("[cct]") != std::string::npos);
    CHECK(help.find("[0.01]") != std::string::npos); // --origin-parallax: %g, not 0.010000
    CHECK(help.find("'--name value' or '--name=value'") != std::string::npos);
}

TEST_CASE("a tracer's own options parse and show beside the shared ones") {
    rcx::CommandLine command_line("tracer");
    bool hybrid = false;
    int capacity = 0;
    command_line.section("Own");
    command_line.add_flag("--hybrid", hybrid, "a flag of this tracer");
    command_line.add_option("--capacity", "N", "a number of this tracer [64]", [&](const std::string& text) {
        capacity = static_cast<int>(rcx::parse_int_value("--capacity", text, 64, 128));
    });
    command_line.add_note("A note of this tracer.");
    const std::vector<const char*> args{"tracer", "--hybrid", "--capacity=100", "--cache", "off"};
    const rcx::Options o = command_line.parse(static_cast<int>(args.size()), args.data());
    CHECK(hybrid);
    CHECK(capacity == 100);
    CHECK(o.cache == rcx::CacheMode::off);
    const std::string help = command_line.help();
    CHECK(help.find("\nOwn:\n  --hybrid            a flag of this tracer\n") != std::string::npos);
    CHECK(help.find("A note of this tracer.\n\nOptions take their value") != std::string::npos);

    rcx::CommandLine refusing("tracer");
    refusing.add_option("--capacity", "N", "", [](const std::string& text) {
        rcx::parse_int_value("--capacity", text, 64, 128);
    });
    const std::vector<const char*> bad{"tracer", "--capacity", "10"};
    CHECK_THROWS_WITH_AS(refusing.parse(static_cast<int>(bad.size()), bad.data()),
                         "--capacity: 10 is out of range 64..128", rcx::UsageError);
}

TEST_CASE("--step takes -360..360 degrees, so a frame's angle stays finite") {
    CHECK(*parse({"--step", "-360"}).step_degrees == -360.0f);
    CHECK(*parse({"--step", "360"}).step_degrees == 360.0f);
    CHECK(usage_error({"--step", "360.5"}) == "--step: 360.5 is out of range -360..360");
    CHECK(usage_error({"--step", "6e37"}) == "--step: 6e37 is out of range -360..360");
}

TEST_CASE("a number with spaces around it is refused, whatever side they are on") {
    // strtol and strtof pass over leading white space; the tracers refuse it as they refuse trailing.
    CHECK(usage_error({"--frames", " 3"}) == "--frames: ' 3' is not an integer");
    CHECK(usage_error({"--frames", "3 "}) == "--frames: '3 ' is not an integer");
    CHECK(usage_error({"--size", " 32x32"}) == "--size (width): ' 32' is not an integer");
    CHECK(usage_error({"--size", "32x 32"}) == "--size (height): ' 32' is not an integer");
    CHECK(usage_error({"--width", "\t16"}) == "--width: '\t16' is not an integer");
    CHECK(usage_error({"--step", " 1"}) == "--step: ' 1' is not a number");
    CHECK(usage_error({"--delta", "0.2 "}) == "--delta: '0.2 ' is not a number");
    CHECK(parse({"--frames", "3"}).frames == 3);
}

TEST_CASE("cache options given with a mode that keeps no cubes are named in a note, and change nothing") {
    const rcx::Options cached = parse({"--cache", "cct", "--face-size", "64", "--filtered"});
    CHECK(cached.notes.empty());
    const rcx::Options off = parse({"--cache", "off", "--face-size", "64", "--filtered", "--frames", "2"});
    REQUIRE(off.notes.size() == 2);
    CHECK(off.notes[0] == "--face-size has no effect with --cache off");
    CHECK(off.notes[1] == "--filtered has no effect with --cache off");
    CHECK(parse({"--cache", "ceiling", "--invalidate", "all"}).notes ==
          std::vector<std::string>{"--invalidate has no effect with --cache ceiling"});
    CHECK(parse({"--cache", "off"}).notes.empty()); // --cache itself is no cache option to note
    CHECK(parse({"--face-size", "64", "--cache", "off"}).notes.size() == 1); // in any order
}

TEST_CASE("a tracer that ignores --threads says so when it is given, instead of fitting it to the cores") {
    rcx::CommandLine command_line("tracer");
    command_line.ignore_threads("the Vulkan driver decides");
    const std::vector<const char*> given{"tracer", "--threads", "4096"};
    const rcx::Options o = command_line.parse(static_cast<int>(given.size()), given.data());
    REQUIRE(o.notes.size() == 1);
    CHECK(o.notes[0] == "--threads has no effect: the Vulkan driver decides");
    rcx::CommandLine quiet("tracer");
    quiet.ignore_threads("the Vulkan driver decides");
    const std::vector<const char*> none{"tracer", "--cache", "cct"};
    CHECK(quiet.parse(static_cast<int>(none.size()), none.data()).notes.empty());
}

TEST_CASE("--threads beyond the cores the machine has runs on those cores, with a note") {
    const unsigned cores = std::thread::hardware_concurrency();
    if (cores == 0 || cores >= 4096) return; // nothing to compare with
    const rcx::Options o = parse({"--threads", "4096"});
    CHECK(o.threads == static_cast<int>(cores));
    REQUIRE(o.notes.size() == 1);
    CHECK(o.notes[0] == "--threads 4096: this machine has " + std::to_string(cores) + " hardware threads; running " +
                            std::to_string(cores));
    CHECK(parse({"--threads", std::to_string(cores).c_str()}).notes.empty());
    CHECK(parse({"--threads", "1"}).threads == 1);
    CHECK(parse({"--threads", "0"}).threads == 0); // all cores, as before
}

TEST_CASE("tracer_main prints the command line's notes on stderr, then runs") {
    const std::filesystem::path captured = std::filesystem::temp_directory_path() / "raycache_test_tracer_main_notes.txt";
    std::fflush(stderr);
    const int saved = ::dup(2);
    REQUIRE(saved >= 0);
    REQUIRE(std::freopen(captured.c_str(), "w", stderr) != nullptr);
    bool ran = false;
    const int status = rcx::tracer_main(
        "tracer",
        [] {
            rcx::Options o;
            o.notes = {"--face-size has no effect with --cache off", "second"};
            return o;
        },
        [] { return std::string(); }, [&ran](const rcx::Options&) { return ran = true, 0; });
    std::fflush(stderr);
    ::dup2(saved, 2);
    ::close(saved);
    std::ifstream in(captured);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::filesystem::remove(captured);
    CHECK(status == 0);
    CHECK(ran);
    CHECK(text == "tracer: note: --face-size has no effect with --cache off\ntracer: note: second\n");
}
