// raycache::CdctCache: one object's CDCT cache owning its cube, bounds, parameters and depth pyramid.
// The world here is a sphere of radius 5 around the cube's centre, coloured 0.5 (exact in RGB9E5): every
// search that answers must meet it 5 from the centre (within the search's epsilon) and see 0.5, and every
// block of the pyramid, once the cube is full, holds 5.
#include <doctest/doctest.h>

#include <cmath>
#include <cstddef>
#include <stdexcept>

#include "raycache/cdct_cache.hpp"
#include "raycache/prefill.hpp"

using namespace raycache;

namespace {

const glm::vec3 centre(1.0f, 2.0f, 3.0f);
const CubeBounds bounds{centre, 1.0f};
constexpr float radius = 5.0f;

// The sphere, seen from inside it: distance along unit(d) from o to where the ray leaves it.
TracedRay trace_sphere(glm::vec3 o, glm::vec3 d) {
    d = glm::normalize(d);
    const glm::vec3 oc = o - centre;
    const float b = glm::dot(oc, d);
    return TracedRay{glm::vec3(0.5f), -b + std::sqrt(b * b - (glm::dot(oc, oc) - radius * radius))};
}

ReliefParameters relief() {
    ReliefParameters p;
    p.step = 0.1f;
    p.epsilon = 0.01f;
    p.search = DepthSearch::relief;
    return p;
}

} // namespace

TEST_CASE("CdctCache refuses a bad face size, unusable bounds and bad parameters") {
    CHECK_THROWS_AS(CdctCache(0, bounds), std::invalid_argument);
    CHECK_THROWS_WITH_AS(CdctCache(8, CubeBounds{centre, 0.0f}), doctest::Contains("half-size"), std::invalid_argument);
    CHECK_THROWS_AS(CdctCache(8, CubeBounds{glm::vec3(NAN), 1.0f}), std::invalid_argument);
    ReliefParameters p;
    p.epsilon = 0.0f;
    CHECK_THROWS_WITH_AS(CdctCache(8, bounds, p), doctest::Contains("epsilon"), std::invalid_argument);
    CHECK_THROWS_AS(CdctCache(std::unique_ptr<CdctCube>(), bounds), std::invalid_argument);
}

TEST_CASE("CdctCache keeps a pyramid only for the relief walk, and begin_frame brings it up to the frame's stores") {
    CHECK(CdctCache(16, bounds).pyramid() == nullptr); // the default search is the secant search
    CHECK(CdctCache(16, bounds, relief(), false).pyramid() == nullptr);
    CdctCache cache(16, bounds, relief());
    REQUIRE(cache.pyramid() != nullptr);
    CHECK(cache.pyramid_bytes() == DepthPyramid::bytes_for(16));
    const int top = cache.pyramid()->levels(); // one block a face

    CHECK(prefill(cache.cube(), bounds, relief(), trace_sphere) == 6u * 16u * 16u);
    for (int face = 0; face < 6; ++face) CHECK(cache.pyramid()->min_distance(face, top, 0, 0) == 0.0f); // not yet
    cache.begin_frame();
    for (int face = 0; face < 6; ++face) {
        CAPTURE(face);
        CHECK(cache.pyramid()->min_distance(face, top, 0, 0) == doctest::Approx(radius).epsilon(1e-5));
    }
    cache.clear();
    CHECK(cache.cube().valid_texels() == 0u);
    for (int face = 0; face < 6; ++face) CHECK(cache.pyramid()->min_distance(face, top, 0, 0) == 0.0f);
}

TEST_CASE("CdctCache::cached_trace traces and stores on a miss, then answers from the cube with the sphere's hit") {
    CdctCache cache(32, bounds, relief());
    int traced = 0;
    const glm::vec3 origin = centre + glm::vec3(0.3f, -0.2f, 0.1f), direction(1.0f, 0.4f, -0.3f);
    auto trace = [&] {
        ++traced;
        return trace_sphere(origin, direction);
    };
    CHECK(cache.cached_trace(origin, direction, trace) == glm::vec3(0.5f));
    CHECK(traced == 1);
    CHECK(cache.cube().valid_texels() == 1u); // the hit, keyed from the centre
    CHECK_FALSE(cache.store(origin, direction, TracedRay{glm::vec3(1.0f), -1.0f})); // behind the origin: no store

    cache.clear();
    prefill(cache.cube(), bounds, relief(), trace_sphere);
    cache.begin_frame();
    int read = 0;
    CHECK(cache.cached_trace(origin, direction, trace, &read) == glm::vec3(0.5f));
    CHECK(traced == 1); // answered by the cube
    const ReliefResult found = cache.lookup(origin, direction);
    REQUIRE(found.hit);
    CHECK(found.texels_read == read);
    CHECK(std::abs(glm::length(found.point - centre) - radius) <= 0.02f);
    CHECK(found.color == glm::vec3(0.5f));

    // The same walk without the pyramid: the same surface, more texels read.
    CdctCache linear(32, bounds, relief(), false);
    prefill(linear.cube(), bounds, relief(), trace_sphere);
    linear.begin_frame();
    const ReliefResult walked = linear.lookup(origin, direction);
    REQUIRE(walked.hit);
    CHECK(std::abs(glm::length(walked.point - centre) - radius) <= 0.02f);
    CHECK(walked.texels_read > found.texels_read);
}

TEST_CASE("CdctCache takes over a filled cube and builds its pyramid from it") {
    auto cube = std::make_unique<CdctCube>(8);
    prefill(*cube, bounds, relief(), trace_sphere);
    cube->begin_frame();
    CdctCache cache(std::move(cube), bounds, relief());
    CHECK(cache.pyramid()->min_distance(0, cache.pyramid()->levels(), 0, 0) == doctest::Approx(radius).epsilon(1e-5));
    CHECK(cache.lookup(centre, glm::vec3(0.0f, 0.0f, 1.0f)).hit);
}

TEST_CASE("CdctCache::move_to re-centres the searches: the sphere, moved with the cube, is met around the new centre") {
    // The cube filled with the sphere of radius 5 around `centre`, then moved by (10, 0, 0): a ray from the
    // moved origin meets the stored surface 5 from the new centre (as if the sphere had moved along), and
    // nowhere near the old one.
    CdctCache cache(32, bounds, relief());
    prefill(cache.cube(), bounds, relief(), trace_sphere);
    cache.begin_frame();
    const glm::vec3 shift(10.0f, 0.0f, 0.0f), origin = centre + glm::vec3(0.3f, -0.2f, 0.1f), direction(1.0f, 0.4f, -0.3f);
    cache.move_to(CubeBounds{centre + shift, 1.0f});
    CHECK(cache.bounds().centre == centre + shift);
    const ReliefResult found = cache.lookup(origin + shift, direction);
    REQUIRE(found.hit);
    CHECK(std::abs(glm::length(found.point - (centre + shift)) - radius) <= 0.02f);
    CHECK(found.color == glm::vec3(0.5f));
    CHECK_THROWS_AS(cache.move_to(CubeBounds{centre, 0.0f}), std::invalid_argument);
    CHECK(cache.bounds().centre == centre + shift); // refused: unchanged
}
