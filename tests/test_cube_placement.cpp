// raycache/cube_placement.hpp: where a cube sits around a sphere, a box and a mesh's vertices. Every
// expected value is worked out by hand below (all of them exact in float), not read back from the code.
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "raycache/cube_placement.hpp"

using namespace raycache;

namespace {
const float inf = std::numeric_limits<float>::infinity();
const float not_a_number = std::numeric_limits<float>::quiet_NaN();

void check_cube(const CubeBounds& b, glm::vec3 centre, float half_size) {
    CHECK(b.centre.x == centre.x);
    CHECK(b.centre.y == centre.y);
    CHECK(b.centre.z == centre.z);
    CHECK(b.half_size == half_size);
}
} // namespace

TEST_CASE("a box's cube is centred on the box, half-size its largest half-extent, whichever axis that is") {
    // [-1, 3] x [2, 3] x [3, 4]: middle (1, 2.5, 3.5), half-extents (2, 0.5, 0.5).
    check_cube(cube_around_box({-1, 2, 3}, {3, 3, 4}), {1, 2.5f, 3.5f}, 2.0f);
    // [0, 1] x [-4, 2] x [0, 0.5]: middle (0.5, -1, 0.25), half-extents (0.5, 3, 0.25).
    check_cube(cube_around_box({0, -4, 0}, {1, 2, 0.5f}), {0.5f, -1, 0.25f}, 3.0f);
    // [5, 6] x [5, 6] x [-10, 10]: middle (5.5, 5.5, 0), half-extents (0.5, 0.5, 10).
    check_cube(cube_around_box({5, 5, -10}, {6, 6, 10}), {5.5f, 5.5f, 0}, 10.0f);
    // A flat box (a floor quad) still has a cube: [-8, 8] x [0, 0] x [-2, 2], middle (0, 0, 0), half 8.
    check_cube(cube_around_box({-8, 0, -2}, {8, 0, 2}), {0, 0, 0}, 8.0f);
}

TEST_CASE("a sphere's cube is centred on it with half-size its radius") {
    check_cube(cube_around_sphere({0.1f, -2, 7}, 0.3f), {0.1f, -2, 7}, 0.3f);
    check_cube(cube_around_sphere({0, 1, 0}, 1.0f), {0, 1, 0}, 1.0f);
}

TEST_CASE("a mesh's cube is the cube around its vertices' box, and encloses every vertex") {
    // x in [-1, 1], y in [0, 2], z in [-3, 1]: middle (0, 1, -1), half-extents (1, 1, 2).
    const std::vector<glm::vec3> vertices{{1, 0, 0}, {-1, 2, 0}, {0, 0, -3}, {0.5f, 1, 1}};
    const CubeBounds b = cube_around_points(vertices);
    check_cube(b, {0, 1, -1}, 2.0f);
    for (const glm::vec3& p : vertices) {
        const glm::vec3 d = glm::abs(p - b.centre);
        CHECK(std::fmax(d.x, std::fmax(d.y, d.z)) <= b.half_size);
    }
    // Any range of points: an array, the order of the points not mattering.
    const std::array<glm::vec3, 4> reversed{vertices[3], vertices[2], vertices[1], vertices[0]};
    check_cube(cube_around_points(reversed), {0, 1, -1}, 2.0f);
}

TEST_CASE("placement refuses empty, inverted, infinite and NaN bounds, naming the object") {
    CHECK_THROWS_WITH_AS(cube_around_box({1, 1, 1}, {1, 1, 1}, "mesh 'dot'"), doctest::Contains("mesh 'dot'"),
                         std::invalid_argument);                                   // a single point
    CHECK_THROWS_AS(cube_around_box({0, 2, 0}, {1, 1, 1}), std::invalid_argument); // lower above upper on y
    CHECK_THROWS_AS(cube_around_box({inf, inf, inf}, {-inf, -inf, -inf}), std::invalid_argument); // an empty accumulation
    CHECK_THROWS_AS(cube_around_box({0, 0, 0}, {inf, 1, 1}), std::invalid_argument);
    CHECK_THROWS_AS(cube_around_box({-inf, 0, 0}, {inf, 1, 1}), std::invalid_argument);
    CHECK_THROWS_AS(cube_around_box({0, not_a_number, 0}, {1, 1, 1}), std::invalid_argument);

    CHECK_THROWS_WITH_AS(cube_around_sphere({0, 0, 0}, 0.0f, "sphere 3"), doctest::Contains("sphere 3"),
                         std::invalid_argument);
    CHECK_THROWS_AS(cube_around_sphere({0, 0, 0}, -1.0f), std::invalid_argument);
    CHECK_THROWS_AS(cube_around_sphere({0, 0, 0}, inf), std::invalid_argument);
    CHECK_THROWS_AS(cube_around_sphere({not_a_number, 0, 0}, 1.0f), std::invalid_argument);

    CHECK_THROWS_WITH_AS(cube_around_points(std::vector<glm::vec3>{}, "mesh 'empty'"), doctest::Contains("mesh 'empty'"),
                         std::invalid_argument);
    CHECK_THROWS_AS(cube_around_points(std::vector<glm::vec3>{{2, 2, 2}, {2, 2, 2}}), std::invalid_argument);
    // A NaN vertex between finite ones is refused, not passed over by the min/max.
    CHECK_THROWS_WITH_AS(cube_around_points(std::vector<glm::vec3>{{0, 0, 0}, {not_a_number, 0, 0}, {1, 1, 1}}, "mesh 'bad'"),
                         doctest::Contains("not finite"), std::invalid_argument);
}
