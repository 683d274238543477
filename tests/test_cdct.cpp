// The CDCT: stores keyed by the hit point, and the relief search (thesis Algorithm 4) checked against
// analytic surroundings whose ray intersections are known in closed form.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <raycache/raycache.hpp>

#include "cdct_scenes.hpp"

using namespace raycache;

namespace {

const glm::vec3 centre(1.0f, 2.0f, 3.0f);
const CubeBounds bounds{centre, 1.0f};

// Colour by face, so a test can tell which part of the cube answered: red = (face + 1) / 8.
glm::vec3 face_color(int face) { return glm::vec3((face + 1) / 8.0f, 0.25f, 0.5f); }

// The face a vector points at, by the largest magnitude (callers avoid near-ties).
int dominant_face(const glm::vec3& v) {
    const glm::vec3 a = glm::abs(v);
    if (a.x >= a.y && a.x >= a.z) return v.x > 0 ? 0 : 1;
    if (a.y >= a.z) return v.y > 0 ? 2 : 3;
    return v.z > 0 ? 4 : 5;
}

bool near_face_edge(const glm::vec3& v) {
    glm::vec3 a = glm::abs(v);
    const float big = std::max(a.x, std::max(a.y, a.z));
    int close = (a.x > 0.98f * big) + (a.y > 0.98f * big) + (a.z > 0.98f * big);
    return close > 1;
}

// Fills every texel with the surroundings described by depth(direction from the centre, unit length).
template <class Depth>
void fill(CdctCube& cube, Depth depth) {
    rcx_test::for_each_texel_direction(cube, [&](const TexelAddress& t, const glm::vec3& d) {
        cube.store_at(t, DepthSample{face_color(t.face), depth(d)});
    });
    cube.begin_frame();
}

// Fills only the -Y face, with a floor 2 below the centre; the rest of the cube stays empty.
void fill_floor_face_only(CdctCube& cube) {
    const int n = cube.face_size();
    for (int row = 0; row < n; ++row)
        for (int column = 0; column < n; ++column) {
            const TexelAddress t{3, column, row};
            const glm::vec3 d = glm::normalize(texel_direction(t, n));
            cube.store_at(t, DepthSample{face_color(3), 2.0f / -d.y});
        }
    cube.begin_frame();
}

// Distance along unit d from o, inside the sphere of `radius` around the centre, to where it leaves it:
// |o + t d - C| = R  =>  t = -b + sqrt(b^2 - c), b = d.(o - C), c = |o - C|^2 - R^2.
float sphere_exit(const glm::vec3& o, const glm::vec3& d, float radius) {
    const glm::vec3 oc = o - centre;
    const float b = glm::dot(d, oc);
    return -b + std::sqrt(b * b - (glm::dot(oc, oc) - radius * radius));
}

// Depth seen from the centre in unit direction d with the floor y = centre.y - height below it and the
// environment (stored at max_depth) everywhere else.
auto floor_depth(float height, float max_depth) {
    return [=](const glm::vec3& d) { return d.y < 0 ? std::min(height / -d.y, max_depth) : max_depth; };
}

glm::vec3 random_origin(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-0.9f, 0.9f);
    return centre + glm::vec3(u(rng), u(rng), u(rng));
}

glm::vec3 random_direction(std::mt19937& rng) {
    std::normal_distribution<float> g;
    for (;;) {
        glm::vec3 v(g(rng), g(rng), g(rng));
        if (glm::length(v) > 1e-3f) return glm::normalize(v);
    }
}

} // namespace

TEST_CASE("inside a sphere of constant depth the search finds the ray's exit within epsilon") {
    const float radius = 5.0f;
    CdctCube cube(64);
    fill(cube, [&](const glm::vec3&) { return radius; });
    std::mt19937 rng(7);
    for (ReliefParameters p : {ReliefParameters{2.0f, 0.2f, 1024, 100.0f}, ReliefParameters{0.2f, 0.02f, 1024, 100.0f},
                               ReliefParameters{0.02f, 0.002f, 1024, 100.0f}}) {
        CAPTURE(p.step);
        int checked = 0;
        for (int i = 0; i < 300; ++i) {
            const glm::vec3 o = random_origin(rng);
            const glm::vec3 d = random_direction(rng);
            const float t_exact = sphere_exit(o, d, radius);
            const glm::vec3 exact = o + t_exact * d;
            const ReliefResult r = relief_search(cube, bounds, o, d, p);
            REQUIRE(r.hit);
            CHECK(glm::length(r.point - exact) <= p.epsilon + 1e-4f);
            CHECK(std::abs(r.distance - t_exact) <= p.epsilon + 1e-4f);
            if (!near_face_edge(exact - centre)) {
                CHECK(r.color.x == doctest::Approx(face_color(dominant_face(exact - centre)).x));
                ++checked;
            }
        }
        CHECK(checked > 100);
    }
}

TEST_CASE("the search reads one texel at the box exit, one per linear step, and one per bisection") {
    // From the centre along +X: the box exit is at t = 1, the sphere at t = 5. Steps of 0.25 reach it
    // after 16 steps exactly (all values exact in binary); bisecting 0.25 down to <= 0.02 takes 4 halvings.
    CdctCube cube(16);
    fill(cube, [](const glm::vec3&) { return 5.0f; });
    const ReliefResult r = relief_search(cube, bounds, centre, glm::vec3(1, 0, 0), ReliefParameters{0.25f, 0.02f, 100, 100.0f});
    REQUIRE(r.hit);
    CHECK(r.texels_read == 1 + 16 + 4);
    CHECK(r.distance == 5.0f);
    CHECK(r.point == centre + glm::vec3(5, 0, 0));
    CHECK(r.color.x == doctest::Approx(face_color(0).x));
    // With too few steps allowed the search gives up: a miss, having read 1 + max_steps texels.
    const ReliefResult short_search =
        relief_search(cube, bounds, centre, glm::vec3(1, 0, 0), ReliefParameters{0.25f, 0.02f, 10, 100.0f});
    CHECK_FALSE(short_search.hit);
    CHECK(short_search.texels_read == 1 + 10);
}

TEST_CASE("above a plane the search finds the ray's hit on the plane") {
    // The floor y = centre.y - 2; rays that miss it are stored as the environment, at max_depth.
    const float height = 2.0f;
    const ReliefParameters p{0.05f, 0.005f, 4096, 100.0f};
    CdctCube cube(1024);
    fill(cube, floor_depth(height, p.max_depth));
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    float worst = 0.0f;
    for (int i = 0; i < 400; ++i) {
        const glm::vec3 o = centre + glm::vec3(u(rng), u(rng), u(rng));
        glm::vec3 d = random_direction(rng);
        d.y = -std::abs(d.y);
        if (-d.y < std::cos(glm::radians(45.0f))) continue; // within 45 degrees of straight down
        const float t_exact = (centre.y - height - o.y) / d.y;
        const ReliefResult r = relief_search(cube, bounds, o, d, p);
        REQUIRE(r.hit);
        worst = std::max(worst, glm::length(r.point - (o + t_exact * d)));
    }
    // Nearest sampling stores one depth per texel: at N = 1024 and these angles the plane's depth changes
    // by at most about 0.01 across a texel, so the hit lies within epsilon + 0.01 of the exact one.
    MESSAGE("worst distance from the exact hit on the plane: " << worst);
    CHECK(worst <= p.epsilon + 0.01f);
}

TEST_CASE("a ray whose path crosses an unfilled part of the cube misses") {
    // Only the -Y face is filled (a floor 2 below the centre); the rest of the cube is empty.
    CdctCube cube(32);
    fill_floor_face_only(cube);
    const ReliefParameters p{0.1f, 0.01f, 1000, 100.0f};
    CHECK(relief_search(cube, bounds, centre, glm::vec3(0, -1, 0), p).hit);   // straight down: all -Y
    CHECK_FALSE(relief_search(cube, bounds, centre, glm::vec3(0, 1, 0), p).hit); // up: empty +Y
    CHECK_FALSE(relief_search(cube, bounds, centre, glm::vec3(1, -0.2f, 0), p).hit); // starts in empty +X
    const CubeStatistics s = cube.statistics();
    CHECK(s.lookups == 3);
    CHECK(s.hits == 1);
    CHECK(s.misses == 2);
}

TEST_CASE("texels stored during a frame are invisible to the search until the next frame") {
    CdctCube cube(16);
    const int n = cube.face_size();
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column) cube.store_at({face, column, row}, DepthSample{face_color(face), 5.0f});
    const ReliefParameters p{0.25f, 0.02f, 100, 100.0f};
    CHECK_FALSE(relief_search(cube, bounds, centre, glm::vec3(0, 0, 1), p).hit);
    cube.begin_frame();
    CHECK(relief_search(cube, bounds, centre, glm::vec3(0, 0, 1), p).hit);
}

TEST_CASE("store_hit keys by the hit point seen from the centre and store_escape by the direction") {
    CdctCube cube(8);
    const ReliefParameters p{0.2f, 0.02f, 100, 50.0f};
    // Hit 3 below the centre: -Y face, sc = x = 0 and tc = -z = 0 -> texel (3, 4, 4), distance 3.
    CHECK(store_hit(cube, bounds, centre + glm::vec3(0, -3, 0), glm::vec3(0.5f), p));
    const auto below = cube.load({3, 4, 4});
    REQUIRE(below.has_value());
    CHECK(below->distance == 3.0f);
    CHECK(below->color == glm::vec3(0.5f));
    // A hit beyond max_depth is stored at max_depth.
    CHECK(store_hit(cube, bounds, centre + glm::vec3(0, 0, 80), glm::vec3(1.0f), p)); // +Z face, (4, 4)
    CHECK(cube.load({4, 4, 4})->distance == 50.0f);
    // An escaped ray towards +X: texel (0, 4, 4) at max_depth.
    CHECK(store_escape(cube, glm::vec3(2, 0, 0), glm::vec3(0.25f), p));
    CHECK(cube.load({0, 4, 4})->distance == 50.0f);
    // A hit at the centre itself has no direction: refused.
    CHECK_FALSE(store_hit(cube, bounds, centre, glm::vec3(1.0f), p));
    CHECK(cube.valid_texels() == 3);
}

TEST_CASE("cdct_cached_trace traces on a miss, stores the hit, and answers from the cube next frame") {
    CdctCube cube(128);
    const ReliefParameters p{0.1f, 0.01f, 1000, 100.0f};
    int traces = 0;
    // The world: a wall at x = centre.x + 4 whose colour is 0.75.
    auto trace_from = [&](const glm::vec3& o, const glm::vec3& d) {
        return [&traces, o, d] {
            ++traces;
            return TracedRay{glm::vec3(0.75f), (centre.x + 4.0f - o.x) / glm::normalize(d).x};
        };
    };
    const glm::vec3 o = centre;
    const glm::vec3 d(1, 0, 0);
    CHECK(cdct_cached_trace(cube, bounds, o, d, p, trace_from(o, d)) == glm::vec3(0.75f));
    CHECK(traces == 1);
    CHECK(cdct_cached_trace(cube, bounds, o, d, p, trace_from(o, d)) == glm::vec3(0.75f)); // same frame: traced
    CHECK(traces == 2);
    cube.begin_frame();
    int read = -1;
    CHECK(cdct_cached_trace(cube, bounds, o, d, p, trace_from(o, d), &read) == glm::vec3(0.75f));
    CHECK(traces == 2);
    CHECK(read > 1);
    // An escaped ray is stored at max_depth and found there.
    const glm::vec3 up(0, 1, 0);
    cdct_cached_trace(cube, bounds, o, up, p, [&] { ++traces; return TracedRay{glm::vec3(0.125f)}; });
    cube.begin_frame();
    ReliefParameters far = p;
    far.step = 1.0f;
    const ReliefResult r = relief_search(cube, bounds, o, up, far);
    REQUIRE(r.hit);
    CHECK(r.color == glm::vec3(0.125f));
    CHECK(std::abs(r.distance - 100.0f) <= far.epsilon);
}

TEST_CASE("a trace reporting a negative hit distance gives its colour and stores nothing") {
    // A ray along +X that reports a hit 5 behind its origin would key a texel on the -X face, which later
    // searches towards -X would take for a surface.
    CdctCube cube(16);
    const ReliefParameters p{0.1f, 0.01f, 1000, 100.0f};
    for (float behind : {-5.0f, -std::numeric_limits<float>::min(), -std::numeric_limits<float>::infinity()}) {
        CAPTURE(behind);
        const glm::vec3 color = cdct_cached_trace(cube, bounds, centre, glm::vec3(1, 0, 0), p,
                                                  [&] { return TracedRay{glm::vec3(0.75f), behind}; });
        CHECK(color == glm::vec3(0.75f));
    }
    CHECK(cube.valid_texels() == 0);
    CHECK(cube.statistics().stores == 0);
    cube.begin_frame();
    CHECK_FALSE(relief_search(cube, bounds, centre, glm::vec3(-1, 0, 0), p).hit);
    // Pre-filling leaves such texels empty too.
    CHECK(prefill(cube, bounds, p, [](glm::vec3, glm::vec3) { return TracedRay{glm::vec3(0.5f), -1.0f}; }) == 0);
    CHECK(cube.valid_texels() == 0);
}

TEST_CASE("a traced ray's reported work is counted when it fills a texel, and not when it stores nothing") {
    CdctCube cube(16);
    const ReliefParameters p{0.1f, 0.01f, 1000, 100.0f};
    cdct_cached_trace(cube, bounds, centre, glm::vec3(1, 0, 0), p, [&] { return TracedRay{glm::vec3(0.5f), 3.0f, 7}; });
    cdct_cached_trace(cube, bounds, centre, glm::vec3(0, 1, 0), p, [&] { return TracedRay{glm::vec3(0.5f), -1.0f, 5}; }); // not stored
    cdct_cached_trace(cube, bounds, centre, glm::vec3(0, 0, 1), p, [&] { return TracedRay{glm::vec3(0.5f), 3.0f}; });     // no work given
    const raycache::CubeStatistics s = cube.statistics();
    CHECK(s.stores == 2);
    CHECK(s.filled_work == 7);
    CHECK(s.work_reports == 1);
}

TEST_CASE("bad origins, directions and boxes make the search a miss without reading the cube") {
    CdctCube cube(8);
    fill(cube, [](const glm::vec3&) { return 5.0f; });
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    const ReliefParameters p;
    struct Bad {
        glm::vec3 origin, direction;
        CubeBounds box;
    };
    const Bad bad[] = {
        {centre, glm::vec3(0.0f), bounds},
        {centre, glm::vec3(nan, 0, 1), bounds},
        {centre, glm::vec3(0, inf, 0), bounds},
        {glm::vec3(nan, 0, 0), glm::vec3(1, 0, 0), bounds},
        {glm::vec3(0, -inf, 0), glm::vec3(1, 0, 0), bounds},
        {centre, glm::vec3(1, 0, 0), CubeBounds{centre, 0.0f}},
        {centre, glm::vec3(1, 0, 0), CubeBounds{centre, -1.0f}},
        {centre, glm::vec3(1, 0, 0), CubeBounds{centre, nan}},
        {centre, glm::vec3(1, 0, 0), CubeBounds{glm::vec3(inf), 1.0f}},
    };
    for (const Bad& b : bad) {
        const ReliefResult r = relief_search(cube, b.box, b.origin, b.direction, p);
        CHECK_FALSE(r.hit);
        CHECK(r.texels_read == 0);
    }
    CHECK_FALSE(store_hit(cube, bounds, glm::vec3(nan), glm::vec3(1), p));
    CHECK_FALSE(store_escape(cube, glm::vec3(0.0f), glm::vec3(1), p));
}

TEST_CASE("relief parameters are validated with a message naming the field") {
    CHECK_NOTHROW(validate(ReliefParameters{}));
    CHECK_THROWS_WITH_AS(validate(ReliefParameters{0.0f, 0.02f, 10, 100.0f}), doctest::Contains("step"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(validate(ReliefParameters{0.2f, -1.0f, 10, 100.0f}), doctest::Contains("epsilon"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(validate(ReliefParameters{0.2f, 0.02f, 0, 100.0f}), doctest::Contains("max_steps"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(validate(ReliefParameters{0.2f, 0.02f, 10, 100.0f, 0.0f}), doctest::Contains("max_gap"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(validate(ReliefParameters{0.2f, 0.02f, 10, std::numeric_limits<float>::infinity()}),
                         doctest::Contains("max_depth"), std::invalid_argument);
}

TEST_CASE("max_steps above RAYCACHE_MAX_RELIEF_STEPS is refused by validate and makes a search a miss that reads nothing") {
    ReliefParameters p{0.25f, 0.02f, RAYCACHE_MAX_RELIEF_STEPS, 100.0f};
    CHECK_NOTHROW(validate(p));
    p.max_steps = std::numeric_limits<int>::max();
    CHECK_THROWS_WITH_AS(validate(p), doctest::Contains("max_steps"), std::invalid_argument);
    p.max_steps = RAYCACHE_MAX_RELIEF_STEPS + 1;
    CHECK_THROWS_WITH_AS(validate(p), doctest::Contains("max_steps"), std::invalid_argument);

    CdctCube cube(16);
    fill(cube, [](const glm::vec3&) { return 5.0f; });
    DepthPyramid pyramid(16);
    pyramid.rebuild(cube);
    for (int steps : {RAYCACHE_MAX_RELIEF_STEPS + 1, std::numeric_limits<int>::max()}) {
        CAPTURE(steps);
        p.max_steps = steps;
        for (const DepthPyramid* with : {static_cast<const DepthPyramid*>(nullptr), static_cast<const DepthPyramid*>(&pyramid)}) {
            const ReliefResult r = relief_search(cube, bounds, centre, glm::vec3(1, 0, 0), p, with);
            CHECK_FALSE(r.hit);
            CHECK(r.texels_read == 0);
        }
    }
    // At the limit the search runs: the sphere is found, linear and with the pyramid.
    p.max_steps = RAYCACHE_MAX_RELIEF_STEPS;
    CHECK(relief_search(cube, bounds, centre, glm::vec3(1, 0, 0), p).hit);
    CHECK(relief_search(cube, bounds, centre, glm::vec3(1, 0, 0), p, &pyramid).hit);
}

TEST_CASE("a linear search whose step no longer moves the ray ends at once as a miss") {
    // From the centre along +X the walk starts at the box exit, t = 1, where 1 + 1e-30 == 1: every step
    // would read the same texel again, up to max_steps (2^24 here: about a second per search).
    CdctCube cube(16);
    fill(cube, [](const glm::vec3&) { return 5.0f; });
    const ReliefParameters p{1e-30f, 0.02f, RAYCACHE_MAX_RELIEF_STEPS, 100.0f};
    const ReliefResult r = relief_search(cube, bounds, centre, glm::vec3(1, 0, 0), p);
    CHECK_FALSE(r.hit);
    CHECK(r.texels_read == 1); // the box exit only
    // A step that still moves the ray on is walked as before.
    const ReliefResult small = relief_search(cube, bounds, centre, glm::vec3(1, 0, 0), ReliefParameters{1e-3f, 1e-4f, 8192, 100.0f});
    REQUIRE(small.hit);
    CHECK(small.distance == doctest::Approx(5.0f).epsilon(1e-3));
}

TEST_CASE("a depth pyramid refuses a cube of another face size in every build, and changes nothing") {
    CdctCube small(8), large(16);
    fill(large, [](const glm::vec3&) { return 5.0f; });
    for (int face = 0; face < 6; ++face) large.store_at({face, 15, 15}, DepthSample{glm::vec3(1.0f), 2.0f}); // written this frame
    DepthPyramid pyramid(8);
    CHECK_THROWS_WITH_AS(pyramid.update(large), doctest::Contains("face size"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(pyramid.rebuild(large), doctest::Contains("face size"), std::invalid_argument);
    for (int level = 1; level <= pyramid.levels(); ++level)
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < pyramid.blocks(level); ++row)
                for (int column = 0; column < pyramid.blocks(level); ++column)
                    REQUIRE(pyramid.min_distance(face, level, column, row) == 0.0f);
    CHECK_NOTHROW(pyramid.update(small));
}

TEST_CASE("DepthPyramid::bytes_for gives a pyramid's bytes without making one") {
    for (int n : {1, 2, 3, 13, 64, 291, 512, 4096}) {
        CAPTURE(n);
        CHECK(DepthPyramid::bytes_for(n) == DepthPyramid(n).bytes());
    }
    CHECK(DepthPyramid::bytes_for(0) == 0);
    CHECK(DepthPyramid::bytes_for(4097) == 0);
}

TEST_CASE("a depth pyramid answers 0 for level 0 and for any block off the pyramid") {
    CdctCube cube(8);
    fill(cube, [](const glm::vec3&) { return 5.0f; });
    DepthPyramid pyramid(8); // levels 1..3: 4, 2 and 1 blocks along an edge
    pyramid.rebuild(cube);
    REQUIRE(pyramid.levels() == 3);
    CHECK(pyramid.min_distance(0, 1, 3, 3) == 5.0f);
    CHECK(pyramid.min_distance(5, 3, 0, 0) == 5.0f);
    CHECK(pyramid.blocks(0) == 0);
    CHECK(pyramid.blocks(4) == 0);
    CHECK(pyramid.min_distance(0, 0, 0, 0) == 0.0f); // level 0 is the cube, not the pyramid
    CHECK(pyramid.min_distance(0, -1, 0, 0) == 0.0f);
    CHECK(pyramid.min_distance(0, 4, 0, 0) == 0.0f);
    CHECK(pyramid.min_distance(6, 1, 0, 0) == 0.0f);
    CHECK(pyramid.min_distance(-1, 1, 0, 0) == 0.0f);
    CHECK(pyramid.min_distance(0, 1, 4, 0) == 0.0f);
    CHECK(pyramid.min_distance(0, 1, 0, -1) == 0.0f);
}

TEST_CASE("with a depth pyramid the search finds the same sphere hits within epsilon and reads fewer texels") {
    const float radius = 5.0f;
    CdctCube cube(64);
    fill(cube, [&](const glm::vec3&) { return radius; });
    DepthPyramid pyramid(64);
    pyramid.rebuild(cube);
    std::mt19937 rng(3);
    for (ReliefParameters p : {ReliefParameters{0.2f, 0.02f, 1024, 100.0f}, ReliefParameters{0.02f, 0.002f, 1024, 100.0f}}) {
        CAPTURE(p.step);
        long linear_reads = 0, pyramid_reads = 0;
        for (int i = 0; i < 300; ++i) {
            const glm::vec3 o = random_origin(rng);
            const glm::vec3 d = random_direction(rng);
            const float t_exact = sphere_exit(o, d, radius);
            const ReliefResult r = relief_search(cube, bounds, o, d, p, &pyramid);
            REQUIRE(r.hit);
            CHECK(std::abs(r.distance - t_exact) <= p.epsilon + 1e-4f);
            pyramid_reads += r.texels_read;
            linear_reads += relief_search(cube, bounds, o, d, p).texels_read;
        }
        MESSAGE("texels read per search: linear " << linear_reads / 300.0 << ", pyramid " << pyramid_reads / 300.0);
        CHECK(pyramid_reads * 2 < linear_reads);
    }
}

TEST_CASE("with a depth pyramid the search finds the hits on a plane and misses through unfilled texels") {
    const float height = 2.0f;
    const ReliefParameters p{0.05f, 0.005f, 4096, 100.0f};
    CdctCube cube(512);
    fill(cube, floor_depth(height, p.max_depth));
    DepthPyramid pyramid(512);
    pyramid.rebuild(cube);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    float worst = 0.0f;
    for (int i = 0; i < 400; ++i) {
        const glm::vec3 o = centre + glm::vec3(u(rng), u(rng), u(rng));
        glm::vec3 d = random_direction(rng);
        d.y = -std::abs(d.y);
        if (-d.y < std::cos(glm::radians(45.0f))) continue;
        const ReliefResult r = relief_search(cube, bounds, o, d, p, &pyramid);
        REQUIRE(r.hit);
        worst = std::max(worst, glm::length(r.point - (o + (centre.y - height - o.y) / d.y * d)));
    }
    // At N = 512 a texel spans twice the angle of the linear test's N = 1024: the same bound, doubled.
    CHECK(worst <= p.epsilon + 0.02f);
    // Rays upwards meet the environment, stored at max_depth, in a few pyramid steps.
    const ReliefResult up = relief_search(cube, bounds, centre, glm::vec3(0.1f, 1.0f, 0.2f), p, &pyramid);
    REQUIRE(up.hit);
    CHECK(glm::length(up.point - centre) == doctest::Approx(p.max_depth).epsilon(1e-3));
    CHECK(up.texels_read < 64);

    // Empty the +Y face: the pyramid, rebuilt, sends the search down to the empty texels: a miss.
    for (int row = 0; row < 512; ++row)
        for (int column = 0; column < 512; ++column) cube.invalidate({2, column, row});
    pyramid.rebuild(cube);
    CHECK_FALSE(relief_search(cube, bounds, centre, glm::vec3(0.1f, 1.0f, 0.2f), p, &pyramid).hit);
    CHECK(relief_search(cube, bounds, centre, glm::vec3(0.1f, -1.0f, 0.2f), p, &pyramid).hit);
}

TEST_CASE("a depth pyramid updated from each frame's stores holds the minimum of every block") {
    const int n = 13; // not a power of two: edge blocks are partial
    CdctCube cube(n);
    DepthPyramid pyramid(n);
    CHECK(pyramid.levels() == 4); // 13 -> 7 -> 4 -> 2 -> 1
    std::mt19937 rng(9);
    std::uniform_int_distribution<int> face(0, 5), coordinate(0, n - 1);
    std::uniform_real_distribution<float> depth(1.0f, 50.0f);
    for (int frame = 0; frame < 6; ++frame) {
        for (int i = 0; i < 150; ++i)
            cube.store_at({face(rng), coordinate(rng), coordinate(rng)}, DepthSample{glm::vec3(1.0f), depth(rng)});
        pyramid.update(cube);
        cube.begin_frame();
        // Brute force: the minimum over each block's texels, empty texels counting as 0.
        for (int level = 1; level <= pyramid.levels(); ++level)
            for (int f = 0; f < 6; ++f)
                for (int br = 0; br < pyramid.blocks(level); ++br)
                    for (int bc = 0; bc < pyramid.blocks(level); ++bc) {
                        float expected = 1e30f;
                        for (int r = br << level; r < std::min((br + 1) << level, n); ++r)
                            for (int c = bc << level; c < std::min((bc + 1) << level, n); ++c) {
                                const auto s = cube.load({f, c, r});
                                expected = std::min(expected, s ? s->distance : 0.0f);
                            }
                        REQUIRE(pyramid.min_distance(f, level, bc, br) == expected);
                    }
    }
}

TEST_CASE("with max_gap, a ray that passes behind a foreground edge misses instead of taking the wrong surface") {
    // Foreground: a narrow cone around +X (unit x > 0.97, half-angle 14 degrees) at distance 2;
    // background everywhere else at distance 10.
    CdctCube cube(128);
    fill(cube, [](const glm::vec3& d) { return d.x > 0.97f ? 2.0f : 10.0f; });
    DepthPyramid pyramid(128);
    pyramid.rebuild(cube);
    // From 0.9 above the centre along (1, -0.1, 0): Q - C = (s, 0.9 - 0.1 s, 0) enters the cone
    // (y/x < tan 14 deg = 0.25) at s = 2.57, |Q - C| = 2.65: behind the foreground, a 0.65 gap.
    const glm::vec3 o = centre + glm::vec3(0.0f, 0.9f, 0.0f), d(1.0f, -0.1f, 0.0f);
    ReliefParameters thesis{0.05f, 0.005f, 4096, 100.0f};
    ReliefParameters gap = thesis;
    gap.max_gap = 0.5f;
    const ReliefResult accepted = relief_search(cube, bounds, o, d, thesis);
    REQUIRE(accepted.hit); // the thesis takes the foreground's colour, though the ray passes behind it
    CHECK(glm::length(accepted.point - centre) > 2.5f);
    CHECK_FALSE(relief_search(cube, bounds, o, d, gap).hit);
    CHECK_FALSE(relief_search(cube, bounds, o, d, gap, &pyramid).hit);
    // A ray that meets the foreground head-on is still a hit with max_gap.
    const ReliefResult head_on = relief_search(cube, bounds, centre, glm::vec3(1, 0.05f, 0), gap, &pyramid);
    REQUIRE(head_on.hit);
    CHECK(glm::length(head_on.point - centre) == doctest::Approx(2.0f).epsilon(0.01));
}

TEST_CASE("pre-filling traces every empty texel from the cube's centre outwards and stores what it hit") {
    // The world: a sphere of radius 6 around the centre, except below y = centre.y - 2 (a floor).
    auto trace = [](glm::vec3 o, glm::vec3 d) {
        const float floor_t = d.y < 0 ? (centre.y - 2.0f - o.y) / d.y : std::numeric_limits<float>::infinity();
        const glm::vec3 oc = o - centre;
        const float b = glm::dot(oc, d);
        const float sphere_t = -b + std::sqrt(b * b - (glm::dot(oc, oc) - 36.0f));
        return floor_t < sphere_t ? TracedRay{glm::vec3(0.25f), floor_t} : TracedRay{glm::vec3(0.75f), sphere_t};
    };
    CdctCube cube(32);
    cube.store_at({2, 0, 0}, DepthSample{glm::vec3(1.0f), 3.0f}); // already filled: left alone
    const ReliefParameters p{0.1f, 0.01f, 1000, 100.0f};
    CHECK(prefill(cube, bounds, p, trace) == 6 * 32 * 32 - 1);
    CHECK(cube.valid_fraction() == 1.0);
    CHECK(cube.load({2, 0, 0})->distance == 3.0f);
    // Straight down: the floor, 2 below the centre (-Y face centre texel (3, 16, 16) looks almost straight down).
    const auto down = cube.load({3, 16, 16});
    REQUIRE(down.has_value());
    CHECK(down->distance == doctest::Approx(2.0f).epsilon(0.001));
    CHECK(down->color.x == doctest::Approx(0.25f));
    // Sideways: the sphere, at 6.
    CHECK(cube.load({0, 16, 16})->distance == doctest::Approx(6.0f).epsilon(0.001));
    // After begin_frame, a search from anywhere in the box finds the floor at its analytic place.
    cube.begin_frame();
    const ReliefResult r = relief_search(cube, bounds, centre + glm::vec3(0.5f, 0.5f, 0.0f), glm::vec3(0.3f, -1.0f, 0.1f), p);
    REQUIRE(r.hit);
    CHECK(r.point.y == doctest::Approx(centre.y - 2.0f).epsilon(0.01));
    // The CCT stores colours only.
    CctCube colours(8);
    CHECK(prefill(colours, bounds, p, trace) == 6 * 8 * 8);
    CHECK(colours.load({3, 4, 4})->x == doctest::Approx(0.25f));
}

TEST_CASE("the secant search finds the exit of a constant-depth sphere on its second read, within epsilon") {
    // Every texel at distance 5: after the box exit (read 1), the jump to the sphere of radius 5 lands on
    // it exactly (read 2). Expected hit: sphere_exit, worked in closed form above.
    CdctCube cube(64);
    fill(cube, [](const glm::vec3&) { return 5.0f; });
    ReliefParameters p;
    p.epsilon = 0.01f;
    std::mt19937 rng(5);
    float worst = 0.0f;
    int most_reads = 0;
    for (int i = 0; i < 500; ++i) {
        const glm::vec3 o = random_origin(rng), d = random_direction(rng);
        const ReliefResult r = secant_search(cube, bounds, o, d, p);
        REQUIRE(r.hit);
        worst = std::max(worst, std::abs(r.distance - sphere_exit(o, d, 5.0f)));
        most_reads = std::max(most_reads, r.texels_read);
    }
    CHECK(worst <= p.epsilon);
    CHECK(most_reads == 2);
}

TEST_CASE("above a plane the secant search finds the ray's hit within epsilon plus the texel's depth step, in at most max_reads reads") {
    const float height = 2.0f;
    ReliefParameters p;
    p.epsilon = 0.005f;
    p.max_reads = 16;
    CdctCube cube(1024);
    fill(cube, floor_depth(height, p.max_depth));
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    float worst = 0.0f;
    long reads = 0;
    int hits = 0, tries = 0;
    for (int i = 0; i < 400; ++i) {
        const glm::vec3 o = centre + glm::vec3(u(rng), u(rng), u(rng));
        glm::vec3 d = random_direction(rng);
        d.y = -std::abs(d.y);
        if (-d.y < std::cos(glm::radians(45.0f))) continue; // within 45 degrees of straight down
        ++tries;
        const float t_exact = (centre.y - height - o.y) / d.y;
        const ReliefResult r = secant_search(cube, bounds, o, d, p);
        CHECK(r.texels_read <= p.max_reads);
        reads += r.texels_read;
        if (!r.hit) continue;
        ++hits;
        worst = std::max(worst, glm::length(r.point - (o + t_exact * d)));
    }
    MESSAGE("secant on a plane: " << hits << " of " << tries << " hit, " << static_cast<double>(reads) / tries
                                  << " reads a search, worst distance from the exact hit " << worst);
    // As for the relief search: the plane's depth changes by at most about 0.01 across a texel here.
    CHECK(worst <= p.epsilon + 0.01f);
    CHECK(hits >= tries * 9 / 10);
    CHECK(static_cast<double>(reads) / tries <= 8.0);
}

TEST_CASE("the secant search misses on an empty texel, and behind a depth discontinuity wider than max_gap") {
    // -Y filled with a floor 2 below the centre, the rest empty: straight down hits, straight up misses.
    CdctCube cube(32);
    fill_floor_face_only(cube);
    ReliefParameters p;
    CHECK(secant_search(cube, bounds, centre, glm::vec3(0, -1, 0), p).hit);
    const ReliefResult up = secant_search(cube, bounds, centre, glm::vec3(0, 1, 0), p);
    CHECK_FALSE(up.hit);
    CHECK(up.texels_read == 1);

    // A near wall (distance 1.5) over the half x > 0 and the far environment (100) over x < 0. The ray from
    // (-0.5, 0, 0.9) along (1, 0, 2) crosses x = 0 at (0, 0, 1.9), 1.9 from the centre: behind the wall's
    // edge, where the cube saw nothing. The crossing found there is 0.4 behind the wall: max_gap 0.3
    // refuses it; without max_gap (the thesis) the wall's colour is taken.
    CdctCube edge(128);
    fill(edge, [](const glm::vec3& d) { return d.x > 0.0f ? 1.5f : 100.0f; });
    p.max_reads = 64;
    const glm::vec3 o = centre + glm::vec3(-0.5f, 0.0f, 0.9f), dir = glm::normalize(glm::vec3(1.0f, 0.0f, 2.0f));
    const ReliefResult taken = secant_search(edge, bounds, o, dir, p);
    CHECK(taken.hit);
    CHECK(glm::length(taken.point - centre) == doctest::Approx(1.9f).epsilon(0.01));
    p.max_gap = 0.3f;
    CHECK_FALSE(secant_search(edge, bounds, o, dir, p).hit);
}

TEST_CASE("the secant search's gap test reads the far end's distance as read, not as Illinois steps halved it") {
    // The state machine driven by hand: a ray from the centre along +z, so a point at t is t from the centre.
    // Reads: t = 1 sees depth 3 (before it: the next read jumps to t = 3); t = 3 sees depth 2.5 (0.5 past
    // it: the far end); every later read, short of t = 3, sees a surface 0.06 beyond itself (before it, by
    // more than epsilon 0.05). False position then walks the near end up to t = 3 (2.6, 2.643, 2.712,
    // 2.805, 2.901, 2.966), halving the far end's f on each repeated near-end read (Illinois: 0.5 down to
    // 0.0156), until the bracket is shorter than epsilon. The far end lies 0.5 past its surface, more than
    // max_gap 0.2: a miss (a search that took it would answer from a surface 0.5 nearer than the ray got).
    using namespace raycache::shared;
    raycache_secant_search s = raycache_secant_begin(glm::vec3(0.0f), glm::vec3(0, 0, 1), 1.0f, 0.05f, 0.2f, 16);
    std::vector<float> read_at;
    while (s.status == RAYCACHE_SECANT_READ) {
        REQUIRE(read_at.size() < 16);
        read_at.push_back(s.t);
        const float depth = read_at.size() == 1 ? 3.0f : s.t >= 3.0f ? 2.5f : s.t + 0.06f;
        raycache_secant_advance(s, true, depth, glm::vec3(depth));
    }
    REQUIRE(read_at.size() == 8);
    CHECK(read_at[1] == 3.0f);
    CHECK(read_at[2] == doctest::Approx(2.6f));
    CHECK(read_at[7] == doctest::Approx(2.966f).epsilon(0.001));
    CHECK(s.hi_f < 0.02f); // halved five times
    CHECK(s.status == RAYCACHE_SECANT_MISS);
    // The same reads with max_gap 0.6: the far end is within it, so the bracket's far end is taken.
    s = raycache_secant_begin(glm::vec3(0.0f), glm::vec3(0, 0, 1), 1.0f, 0.05f, 0.6f, 16);
    int reads = 0;
    while (s.status == RAYCACHE_SECANT_READ) {
        const float depth = ++reads == 1 ? 3.0f : s.t >= 3.0f ? 2.5f : s.t + 0.06f;
        raycache_secant_advance(s, true, depth, glm::vec3(depth));
    }
    CHECK(s.status == RAYCACHE_SECANT_HIT);
    CHECK(s.t == 3.0f);
    CHECK(s.color.x == 2.5f);
}

TEST_CASE("secant parameters are validated, and bad input misses without reading") {
    ReliefParameters p;
    p.max_reads = 0;
    CHECK_THROWS_WITH_AS(validate(p), doctest::Contains("max_reads"), std::invalid_argument);
    p.max_reads = RAYCACHE_SECANT_MAX_READS + 1;
    CHECK_THROWS_WITH_AS(validate(p), doctest::Contains("max_reads"), std::invalid_argument);
    CdctCube cube(8);
    fill(cube, [](const glm::vec3&) { return 5.0f; });
    const float nan = std::numeric_limits<float>::quiet_NaN();
    CHECK(secant_search(cube, bounds, glm::vec3(nan), glm::vec3(1, 0, 0), ReliefParameters{}).texels_read == 0);
    CHECK(secant_search(cube, bounds, centre, glm::vec3(0), ReliefParameters{}).texels_read == 0);
    CHECK(secant_search(cube, CubeBounds{centre, -1.0f}, centre, glm::vec3(1, 0, 0), ReliefParameters{}).texels_read == 0);
    // max_reads past the limit (not validated here) is clamped, never read past.
    ReliefParameters many;
    many.max_reads = 1 << 30;
    CHECK(secant_search(cube, bounds, centre, glm::vec3(1, 0, 0), many).texels_read <= RAYCACHE_SECANT_MAX_READS);
}
