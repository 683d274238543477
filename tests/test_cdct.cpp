// The CDCT: stores keyed by the hit point, and the relief search (thesis Algorithm 4) checked against
// analytic surroundings whose ray intersections are known in closed form.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>

#include <raycache/raycache.hpp>

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
    const int n = cube.face_size();
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column) {
                const TexelAddress t{face, column, row};
                const glm::vec3 d = glm::normalize(texel_direction(t, n));
                cube.store_at(t, DepthSample{face_color(face), depth(d)});
            }
    cube.begin_frame();
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
            // |o + t d - C| = R  =>  t = -b + sqrt(b^2 - c), b = d.(o - C), c = |o - C|^2 - R^2.
            const glm::vec3 oc = o - centre;
            const float b = glm::dot(d, oc);
            const float t_exact = -b + std::sqrt(b * b - (glm::dot(oc, oc) - radius * radius));
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
    fill(cube, [&](const glm::vec3& d) { return d.y < 0 ? std::min(height / -d.y, p.max_depth) : p.max_depth; });
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
    const int n = cube.face_size();
    for (int row = 0; row < n; ++row)
        for (int column = 0; column < n; ++column) {
            const TexelAddress t{3, column, row};
            const glm::vec3 d = glm::normalize(texel_direction(t, n));
            cube.store_at(t, DepthSample{face_color(3), 2.0f / -d.y});
        }
    cube.begin_frame();
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
    CHECK_THROWS_WITH_AS(validate(ReliefParameters{0.2f, 0.02f, 10, std::numeric_limits<float>::infinity()}),
                         doctest::Contains("max_depth"), std::invalid_argument);
}
