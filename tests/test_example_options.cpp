// The example tracers' shared command line (rcx/options.hpp): values, defaults, and errors a user can act on.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "rcx/options.hpp"

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
}

TEST_CASE("bad command lines throw UsageError naming the option") {
    auto fails = [](std::vector<const char*> args, const char* mentioned) {
        CAPTURE(mentioned);
        CHECK_THROWS_WITH_AS(parse(args), doctest::Contains(mentioned), rcx::UsageError);
    };
    fails({"--bogus"}, "--bogus");
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
