// Bad data and misuse: vectors that are not directions (the library's guarantee: lookups miss, stores are
// ignored, nothing is read or written out of bounds), addresses off the cube (a programmer error:
// RAYCACHE_ASSERT, then refused), and colours or distances that cannot be stored as given.
//
// RAYCACHE_ASSERT is routed to a counter (instead of assert()) before any RayCache header is included,
// so these tests see whether it fired and go on running.
#include <atomic>

namespace {
std::atomic<int> assertion_failures{0};
} // namespace
#define RAYCACHE_ASSERT(condition) ((condition) ? (void)0 : (void)assertion_failures.fetch_add(1))

#include <doctest/doctest.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>

#include "raycache/raycache.hpp"

namespace {

using raycache::CctCube;
using raycache::CdctCube;
using raycache::CubeStatistics;
using raycache::DepthSample;
using raycache::TexelAddress;

constexpr float inf = std::numeric_limits<float>::infinity();
constexpr float nan_value = std::numeric_limits<float>::quiet_NaN();
constexpr float largest_subnormal = 1.1754942e-38f;  // 0x007FFFFF
constexpr float smallest_major = 0x1p-64f;           // 5.421011e-20, the smallest allowed major magnitude
constexpr float largest_major = 0x1p64f;             // 1.8446744e19, the largest

struct NamedVector {
    const char* name;
    glm::vec3 v;
};

// Vectors that are not directions: zero, NaN, infinite, too short (major below 2^-64), too long (above 2^64).
const NamedVector not_directions[] = {
    {"zero", {0.0f, 0.0f, 0.0f}},
    {"-0", {-0.0f, -0.0f, -0.0f}},
    {"mixed zeros", {0.0f, -0.0f, 0.0f}},
    {"NaN x", {nan_value, 1.0f, 0.0f}},
    {"NaN y", {1.0f, nan_value, 0.0f}},
    {"NaN z", {1.0f, 0.0f, nan_value}},
    {"NaN z, minor", {1.0f, 0.5f, nan_value}},
    {"all NaN", {nan_value, nan_value, nan_value}},
    {"negative NaN", {-nan_value, 0.0f, 1.0f}},
    {"+inf x", {inf, 0.0f, 0.0f}},
    {"-inf x", {-inf, 0.0f, 0.0f}},
    {"+inf y", {1.0f, inf, 0.0f}},
    {"-inf y", {1.0f, -inf, 0.0f}},
    {"+inf z", {0.0f, 1.0f, inf}},
    {"-inf z, minor", {5.0f, 1.0f, -inf}},
    {"all inf", {inf, inf, inf}},
    {"subnormal x", {1e-40f, 0.0f, 0.0f}},
    {"subnormals", {-1e-40f, 1e-45f, largest_subnormal}},
    {"normal but below 2^-64", {1.17549435e-38f, 1e-30f, -5e-20f}},
    {"just below 2^-64", {0.0f, std::nextafter(0x1p-64f, 0.0f), 0.0f}},
    {"major above 1.85e19 (x)", {5e37f, 0.0f, 0.0f}},
    {"major above 1.85e19 (y)", {1.0f, -1.9e19f, 0.0f}},
    {"major above 1.85e19 (z)", {0.0f, 0.0f, std::numeric_limits<float>::max()}},
    {"just above 2^64", {std::nextafter(0x1p64f, inf), 0.0f, 0.0f}},
};

int failures_now() { return assertion_failures.load(); }

} // namespace

TEST_CASE("vectors that are not directions miss, and the miss is counted") {
    CctCube cube(2);
    for (const NamedVector& bad : not_directions) {
        CAPTURE(bad.name);
        CHECK_FALSE(raycache::is_direction(bad.v));
        CHECK_FALSE(cube.lookup(bad.v).has_value());
        CHECK_FALSE(cube.peek(bad.v).has_value());
    }
    const std::uint64_t count = sizeof not_directions / sizeof not_directions[0];
    const CubeStatistics s = cube.statistics();
    CHECK(s.lookups == count);
    CHECK(s.misses == count);
    CHECK(s.hits == 0u);
}

TEST_CASE("vectors that are not directions miss even when every texel is filled") {
    CctCube cube(1);
    const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const glm::vec3& a : axes) REQUIRE(cube.store(a, glm::vec3(1.0f)));
    cube.begin_frame();
    REQUIRE(cube.valid_texels() == 6u);
    for (const NamedVector& bad : not_directions) {
        CAPTURE(bad.name);
        CHECK_FALSE(cube.lookup(bad.v).has_value());
    }
    CHECK(cube.statistics().hits == 0u);
}

TEST_CASE("stores keyed by vectors that are not directions are refused and write nothing") {
    const int before = failures_now();
    CctCube cube(2);
    REQUIRE(cube.store(glm::vec3(0.0f, 1.0f, 0.0f), glm::vec3(0.5f)));
    for (const NamedVector& bad : not_directions) {
        CAPTURE(bad.name);
        CHECK_FALSE(cube.store(bad.v, glm::vec3(1.0f)));
        CHECK(cube.valid_texels() == 1u);
    }
    const std::uint64_t count = sizeof not_directions / sizeof not_directions[0];
    CubeStatistics s = cube.statistics();
    CHECK(s.stores == 1u);
    CHECK(s.refused_stores == count);
    // Only the one good store's texel holds a value: +Y on N = 2, tu = (0 + 1)/2 -> column 1, row 1.
    int filled = 0;
    for (int f = 0; f < 6; ++f)
        for (int r = 0; r < 2; ++r)
            for (int c = 0; c < 2; ++c)
                if (cube.load(TexelAddress{f, c, r})) ++filled;
    CHECK(filled == 1);
    CHECK(cube.load(TexelAddress{2, 1, 1}).has_value());
    cube.begin_frame();
    CHECK(cube.valid_texels() == 1u);
    CHECK(failures_now() == before); // bad data is not a programmer error
}

TEST_CASE("a CDCT cube refuses stores keyed by vectors that are not directions") {
    CdctCube cube(2);
    for (const NamedVector& bad : not_directions) {
        CAPTURE(bad.name);
        CHECK_FALSE(cube.store(bad.v, DepthSample{glm::vec3(1.0f), 3.0f}));
        CHECK_FALSE(cube.lookup(bad.v).has_value());
    }
    CHECK(cube.valid_texels() == 0u);
    CHECK(cube.statistics().refused_stores == sizeof not_directions / sizeof not_directions[0]);
}

TEST_CASE("texel_of returns no texel for vectors that are not directions") {
    const int before = failures_now();
    for (int n : {1, 2, 128, 4096}) {
        for (const NamedVector& bad : not_directions) {
            CAPTURE(n);
            CAPTURE(bad.name);
            CHECK_FALSE(raycache::texel_of(bad.v, n).has_value());
        }
    }
    CHECK(failures_now() == before);
}

TEST_CASE("the limits of a direction: 2^-64 and 2^64 are directions, just beyond them are not") {
    CHECK(raycache::is_direction(glm::vec3(smallest_major, 0.0f, 0.0f)));
    CHECK(raycache::is_direction(glm::vec3(0.0f, -largest_major, 0.0f)));
    CHECK_FALSE(raycache::is_direction(glm::vec3(std::nextafter(smallest_major, 0.0f), 0.0f, 0.0f)));
    CHECK_FALSE(raycache::is_direction(glm::vec3(0.0f, -std::nextafter(largest_major, inf), 0.0f)));
    // A tiny or huge direction still lands on the texel of its face's centre: +X on N = 2, tu = tv = 0.5 -> (1, 1).
    // Subnormal minor components (which GPUs flush to zero) change nothing there.
    CctCube cube(2);
    CHECK(cube.store(glm::vec3(smallest_major, largest_subnormal, -1e-45f), glm::vec3(1.0f)));
    CHECK(cube.store(glm::vec3(-largest_major, 0.0f, 0.0f), glm::vec3(0.5f)));
    CHECK(cube.load(TexelAddress{0, 1, 1}).has_value());
    CHECK(cube.load(TexelAddress{1, 1, 1}).has_value());
    CHECK(cube.valid_texels() == 2u);
}

TEST_CASE("a store by an address off the cube asserts, is refused and writes nothing") {
    CctCube cube(2);
    const TexelAddress off_cube[] = {{6, 0, 0}, {-1, 0, 0}, {0, 2, 0}, {0, 0, 2}, {0, -1, 0}, {0, 0, -1},
                                     {5, 1, 2}, {1000000, 0, 0}, {0, 1 << 30, 1 << 30}, {-2147483647 - 1, 0, 0}};
    for (const TexelAddress& t : off_cube) {
        CAPTURE(t.face);
        CAPTURE(t.column);
        CAPTURE(t.row);
        CHECK_FALSE(cube.contains(t));
        const int before = failures_now();
        CHECK_FALSE(cube.store_at(t, glm::vec3(1.0f)));
        CHECK(failures_now() == before + 1);
    }
    const CubeStatistics s = cube.statistics();
    CHECK(s.refused_stores == sizeof off_cube / sizeof off_cube[0]);
    CHECK(s.stores == 0u);
    CHECK(s.valid_texels == 0u);
    for (int f = 0; f < 6; ++f)
        for (int r = 0; r < 2; ++r)
            for (int c = 0; c < 2; ++c) CHECK_FALSE(cube.load(TexelAddress{f, c, r}).has_value());
    SUBCASE("a store by an address on the cube does not assert") {
        const int before = failures_now();
        CHECK(cube.store_at(TexelAddress{5, 1, 1}, glm::vec3(1.0f)));
        CHECK(failures_now() == before);
        CHECK(cube.load(TexelAddress{5, 1, 1}).has_value());
    }
}

TEST_CASE("load and invalidate by an address off the cube assert and touch nothing") {
    CctCube cube(2);
    REQUIRE(cube.store_at(TexelAddress{0, 0, 0}, glm::vec3(1.0f)));
    cube.begin_frame();
    int before = failures_now();
    CHECK_FALSE(cube.load(TexelAddress{0, 2, 0}).has_value());
    CHECK(failures_now() == before + 1);
    before = failures_now();
    cube.invalidate(TexelAddress{-1, 0, 0});
    cube.invalidate(TexelAddress{6, 0, 0});
    CHECK(failures_now() == before + 2);
    CHECK(cube.valid_texels() == 1u);
    CHECK(cube.load(TexelAddress{0, 0, 0}).has_value());
}

TEST_CASE("texel_of with a face size outside 1 to 4096 asserts") {
    const int before = failures_now();
    (void)raycache::texel_of(glm::vec3(1.0f, 0.0f, 0.0f), 0);
    (void)raycache::texel_of(glm::vec3(1.0f, 0.0f, 0.0f), 4097);
    CHECK(failures_now() == before + 2);
}

TEST_CASE("CCT colours that are NaN, infinite or negative are stored clamped") {
    // Documented clamp: NaN and negatives -> 0, above 65280 and +inf -> 65280 (= 510 * 2^7, exactly stored).
    CctCube cube(2);
    struct Case {
        glm::vec3 colour;
        glm::vec3 stored;
        glm::vec3 direction;
    };
    const Case cases[] = {
        {{nan_value, -inf, 0.5f}, {0.0f, 0.0f, 0.5f}, {1.0f, 0.0f, 0.0f}},
        {{inf, -2.0f, nan_value}, {65280.0f, 0.0f, 0.0f}, {-1.0f, 0.0f, 0.0f}},
        {{1e9f, 70000.0f, inf}, {65280.0f, 65280.0f, 65280.0f}, {0.0f, 1.0f, 0.0f}},
        {{-1.0f, -0.0f, -1e-30f}, {0.0f, 0.0f, 0.0f}, {0.0f, -1.0f, 0.0f}},
        {{nan_value, nan_value, nan_value}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}},
        {{-5.0f, 0.25f, inf}, {0.0f, 0.0f, 65280.0f}, {0.0f, 0.0f, -1.0f}}, // 0.25 is under half a step of 2^7
    };
    for (const Case& c : cases) CHECK(cube.store(c.direction, c.colour));
    CHECK(cube.valid_texels() == 6u);
    cube.begin_frame();
    for (std::size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        CAPTURE(i);
        const Case& c = cases[i];
        const std::optional<glm::vec3> got = cube.lookup(c.direction);
        REQUIRE(got.has_value());
        CHECK(got->x == c.stored.x);
        CHECK(got->y == c.stored.y);
        CHECK(got->z == c.stored.z);
    }
}

TEST_CASE("CDCT samples with a negative, NaN or infinite distance are refused") {
    CdctCube cube(2);
    const glm::vec3 d(1.0f, 0.0f, 0.0f);
    for (float distance : {-1.0f, -1e-30f, nan_value, inf, -inf}) {
        CAPTURE(distance);
        CHECK_FALSE(cube.store(d, DepthSample{glm::vec3(1.0f), distance}));
    }
    CHECK(cube.valid_texels() == 0u);
    CHECK(cube.statistics().refused_stores == 5u);
    SUBCASE("a bad colour at a good distance is stored clamped") {
        CHECK(cube.store(d, DepthSample{glm::vec3(nan_value, inf, -1.0f), 2.0f}));
        cube.begin_frame();
        const std::optional<DepthSample> got = cube.lookup(d);
        REQUIRE(got.has_value());
        CHECK(got->distance == 2.0f);
        CHECK(got->color.x == 0.0f);
        CHECK(got->color.y == 65280.0f);
        CHECK(got->color.z == 0.0f);
    }
}

TEST_CASE("cached_trace answers a vector that is not a direction by tracing, without storing") {
    CctCube cube(2);
    int calls = 0;
    const glm::vec3 traced(0.1f, 0.2f, 0.3f);
    for (int frame = 0; frame < 2; ++frame) {
        for (const NamedVector& bad : not_directions) {
            CAPTURE(bad.name);
            const glm::vec3 got = raycache::cached_trace(cube, bad.v, [&] {
                ++calls;
                return traced;
            });
            CHECK(got == traced);
        }
        cube.begin_frame();
    }
    const int count = static_cast<int>(sizeof not_directions / sizeof not_directions[0]);
    CHECK(calls == 2 * count);
    CHECK(cube.valid_texels() == 0u);
}

TEST_CASE("begin_frame, clear, invalidate and a pyramid update inside a frame's lookup or search assert, naming the rule") {
    // The caller's trace runs inside cached_trace's (and the CDCT's) frame scope: calling a between-frames
    // function from it is the misuse the rule forbids, detected deterministically here.
#if RAYCACHE_CHECK_FRAME_RULE
    raycache::CctCube cct(8);
    int before = failures_now();
    raycache::cached_trace(cct, glm::vec3(1, 0, 0), [&] {
        cct.begin_frame();
        cct.clear();
        cct.invalidate(raycache::TexelAddress{0, 1, 1});
        return glm::vec3(1.0f);
    });
    CHECK(failures_now() - before == 3);
    cct.begin_frame(); // between frames: fine
    CHECK(failures_now() - before == 3);

    raycache::CdctCube cdct(8);
    raycache::DepthPyramid pyramid(8);
    before = failures_now();
    raycache::cdct_cached_trace(cdct, raycache::CubeBounds{glm::vec3(0), 1.0f}, glm::vec3(0), glm::vec3(0, 1, 0),
                                raycache::ReliefParameters{}, [&] {
                                    pyramid.update(cdct);
                                    cdct.begin_frame();
                                    return raycache::TracedRay{glm::vec3(1.0f), 2.0f};
                                });
    CHECK(failures_now() - before == 2);
    pyramid.update(cdct);
    cdct.begin_frame();
    CHECK(failures_now() - before == 2);
#else
    MESSAGE("RAYCACHE_CHECK_FRAME_RULE is off in this build (NDEBUG): the rule is not checked");
#endif
}
