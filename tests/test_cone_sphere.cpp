// The cone-sphere geometry of invalidation (raycache/shared/cone_sphere.h): Roger et al.'s equation 1 on
// hand-derived cases, the cone of a texel region against the texel choice, and the conservativeness of
// "rays from a ball through a region meet a sphere" against brute force (rays sampled from the box's
// corners, faces and inside, through directions sampled in the region, intersected with the sphere).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <glm/glm.hpp>

#include "raycache/cube_face.hpp"
#include "raycache/shared/cone_sphere.h"

namespace {

using raycache::shared::raycache_direction_cone;

constexpr float pi = 3.14159265358979f;

raycache_direction_cone cone_of(glm::vec3 axis, float degrees) {
    const float a = degrees * pi / 180.0f;
    return {glm::normalize(axis), std::cos(a), std::sin(a)};
}

bool meets(glm::vec3 apex, raycache_direction_cone cone, glm::vec3 centre, float radius) {
    return raycache::shared::raycache_cone_meets_sphere(apex, cone, centre, radius);
}

// Whether the ray o + t d (t >= 0, d unit) meets the sphere: the nearest point of the ray to its centre.
bool ray_meets_sphere(glm::vec3 o, glm::vec3 d, glm::vec3 c, float r) {
    const float t = std::max(0.0f, glm::dot(c - o, d));
    const glm::vec3 p = o + t * d;
    return glm::dot(p - c, p - c) <= r * r;
}

} // namespace

TEST_CASE("equation 1 on hand-derived cases: on the axis, off to the side, at the rim, behind the apex") {
    const glm::vec3 o(0.0f);
    const raycache_direction_cone c30 = cone_of({0, 0, 1}, 30.0f);
    CHECK(meets(o, c30, {0, 0, 10}, 1.0f));  // on the axis
    CHECK(!meets(o, c30, {10, 0, 0}, 1.0f)); // 90 degrees off, cap asin(0.1) = 5.7: 35.7 < 90
    // At 40 degrees and distance 10 the sphere meets the 30-degree cone iff asin(r/10) >= 10 degrees, i.e.
    // r >= 10 sin 10 = 1.7365.
    const glm::vec3 at40 = 10.0f * glm::vec3(std::sin(40.0f * pi / 180.0f), 0.0f, std::cos(40.0f * pi / 180.0f));
    CHECK(meets(o, c30, at40, 1.80f));
    CHECK(!meets(o, c30, at40, 1.65f));
    CHECK(!meets(o, c30, {0, 0, -5}, 1.0f)); // behind the apex
    CHECK(meets(o, c30, {0, 0, -5}, 5.5f));  // the apex lies in the sphere
    // A 90-degree cone is the half-space z >= 0: a sphere at (10, 0, -0.5) is 92.86 degrees off the axis;
    // radius 1 gives a cap of 5.74 (meets), radius 0.4 a cap of 2.29 (does not).
    const raycache_direction_cone c90 = cone_of({0, 0, 1}, 90.0f);
    CHECK(meets(o, c90, {10, 0, -0.5f}, 1.0f));
    CHECK(!meets(o, c90, {10, 0, -0.5f}, 0.4f));
    // The apex moved: the same geometry translated.
    CHECK(meets({3, 4, 5}, c30, glm::vec3(3, 4, 5) + at40, 1.80f));
    CHECK(!meets({3, 4, 5}, c30, glm::vec3(3, 4, 5) + at40, 1.65f));
}

TEST_CASE("a whole face's cone reaches its corners, 54.74 degrees, and holds every direction the face's texels take") {
    const raycache_direction_cone face = raycache::shared::raycache_region_cone(RAYCACHE_FACE_POSITIVE_Z, 0, 0, 1, 1, 1);
    CHECK(face.axis.z == doctest::Approx(1.0f));
    const float corner = 1.0f / std::sqrt(3.0f); // cos of the angle from +Z to (1, 1, 1)
    CHECK(face.cos_spread <= corner);
    CHECK(face.cos_spread >= corner - 2e-4f);

    // Tiles and texels of several faces and sizes: every direction whose texel lies in the region is within
    // the region's cone (directions sampled over the whole sphere; the texel choice decides membership).
    std::mt19937 rng(7);
    std::normal_distribution<float> g;
    for (int n : {1, 5, 16, 37, 64}) {
        for (int trial = 0; trial < 40; ++trial) {
            const int f = trial % 6;
            const int c0 = static_cast<int>(rng() % static_cast<unsigned>(n)), r0 = static_cast<int>(rng() % static_cast<unsigned>(n));
            const int c1 = std::min(n, c0 + 1 + static_cast<int>(rng() % 16u)), r1 = std::min(n, r0 + 1 + static_cast<int>(rng() % 16u));
            const raycache_direction_cone cone = raycache::shared::raycache_region_cone(f, c0, r0, c1, r1, n);
            int inside = 0;
            for (int k = 0; k < 4000; ++k) {
                // Directions near the region: its centre plus noise of the region's size.
                const float sc = 2.0f * ((static_cast<float>(c0 + c1) * 0.5f + g(rng) * static_cast<float>(c1 - c0)) / static_cast<float>(n)) - 1.0f;
                const float tc = 2.0f * ((static_cast<float>(r0 + r1) * 0.5f + g(rng) * static_cast<float>(r1 - r0)) / static_cast<float>(n)) - 1.0f;
                const glm::vec3 d = raycache::shared::raycache_face_point(f, 1.0f, sc, tc);
                const raycache::shared::raycache_texel_address a = raycache::shared::raycache_texel_of(d, n);
                if (a.face != f || a.column < c0 || a.column >= c1 || a.row < r0 || a.row >= r1) continue;
                ++inside;
                REQUIRE(glm::dot(glm::normalize(d), cone.axis) >= cone.cos_spread);
            }
            CHECK(inside > 0);
        }
    }
}

TEST_CASE("a region's cone: its axis through the region's centre, its spread to its farthest corner (in doubles)") {
    // Independent of the library's arithmetic: the face's corners turned into 3D by the face table (as
    // doubles) and normalised, the axis through the region's centre point, the angle to each corner; the
    // cone must hold the farthest corner and be no wider than it by more than the slack and float rounding.
    std::mt19937 rng(5);
    for (int n : {1, 2, 3, 16, 37, 256, 4096}) {
        for (int trial = 0; trial < 300; ++trial) {
            const int f = trial % 6;
            const int c0 = static_cast<int>(rng() % static_cast<unsigned>(n)), r0 = static_cast<int>(rng() % static_cast<unsigned>(n));
            const int span = trial % 3 == 0 ? n : 1 + static_cast<int>(rng() % 16u);
            const int c1 = std::min(n, c0 + span), r1 = std::min(n, r0 + 1 + static_cast<int>(rng() % static_cast<unsigned>(span)));
            auto point = [&](double s, double t) {
                const glm::vec3 p = raycache::shared::raycache_face_point(f, 1.0f, static_cast<float>(s), static_cast<float>(t));
                const glm::dvec3 d(p);
                return d / glm::length(d);
            };
            auto coordinate = [n](int texel) { return 2.0 * texel / n - 1.0; };
            const double s0 = coordinate(c0), s1 = coordinate(c1), t0 = coordinate(r0), t1 = coordinate(r1);
            const glm::dvec3 axis = point(0.5 * (s0 + s1), 0.5 * (t0 + t1));
            double farthest = 0.0;
            for (const glm::dvec2 corner : {glm::dvec2(s0, t0), glm::dvec2(s1, t0), glm::dvec2(s0, t1), glm::dvec2(s1, t1)})
                farthest = std::max(farthest, std::acos(std::min(1.0, glm::dot(axis, point(corner.x, corner.y)))));
            const raycache_direction_cone cone = raycache::shared::raycache_region_cone(f, c0, r0, c1, r1, n);
            CAPTURE(n);
            CAPTURE(f);
            CAPTURE(c0);
            CAPTURE(r0);
            CAPTURE(c1);
            CAPTURE(r1);
            REQUIRE(glm::length(glm::dvec3(cone.axis) - axis) < 1e-6);
            // Both the cosine and the sine hold the farthest corner widened by most of the 1e-4 rad slack (a
            // cone test reads both); neither is wider than the slack, the sine's rounding up and 2 ulps of 1 allow.
            REQUIRE(cone.cos_spread <= std::cos(farthest + 0.5e-4));
            REQUIRE(cone.sin_spread >= std::sin(std::min(farthest + 0.5e-4, 1.5707963)));
            CHECK(cone.cos_spread >= std::cos(farthest + 1.01e-4) - 2e-6);
            CHECK(cone.sin_spread <= std::sin(farthest + 1.01e-4) + 1e-6);
        }
    }
}

TEST_CASE("one texel's cone: holds every direction the texel choice gives it, and is at most 15% wider than its corners' cone") {
    // Hand-derived: the centre texel of a 2 x 2 face is a quarter of it, [0, 1] x [0, 1] on +Z; its centre
    // point (0.5, 0.5, 1) is 0.707 from its corners in the face plane, and no point of it is nearer the
    // face's centre than 0 (r_min = 0), so the bound is 0.707 rad (40.5 degrees; the corners themselves lie
    // 19.5 and 35.3 degrees from the axis).
    const raycache_direction_cone quarter = raycache::shared::raycache_texel_cone(RAYCACHE_FACE_POSITIVE_Z, 1, 1, 2);
    CHECK(glm::length(quarter.axis - glm::normalize(glm::vec3(0.5f, -0.5f, 1.0f))) < 1e-6f); // +Z: t runs along -y
    CHECK(quarter.cos_spread == doctest::Approx(1.0f - 0.5f * 0.5f).epsilon(1e-3)); // 1 - x^2 / 2 for x = 0.7071
    // Every sampled direction whose texel is (face, column, row) lies in the cone, on faces of several sizes;
    // and the cone is at most 15% wider (in angle) than the exact cone to the texel's corners (on faces of 16 to 512 texels).
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int n : {1, 2, 3, 16, 37, 512, 4096}) {
        for (int trial = 0; trial < 60; ++trial) {
            const int f = trial % 6;
            const int column = static_cast<int>(rng() % static_cast<unsigned>(n)), row = static_cast<int>(rng() % static_cast<unsigned>(n));
            const raycache_direction_cone cone = raycache::shared::raycache_texel_cone(f, column, row, n);
            const raycache_direction_cone corners = raycache::shared::raycache_region_cone(f, column, row, column + 1, row + 1, n);
            // Small faces' texels span tens of degrees, where the bound is looser (still conservative); on
            // faces of thousands of texels both cones are below what float cosines resolve.
            if (n >= 16 && n <= 512)
                CHECK(std::acos(std::max(-1.0f, std::min(1.0f, cone.cos_spread))) <= 1.15f * std::acos(std::min(1.0f, corners.cos_spread)) + 2e-4f);
            for (int k = 0; k < 500; ++k) {
                // Points of the texel, its edges and corners included (u in [0, 1] reaches both ends).
                const float a = k < 4 ? static_cast<float>(k & 1) : u(rng), b = k < 4 ? static_cast<float>(k >> 1) : u(rng);
                const float sc = 2.0f * ((static_cast<float>(column) + a) / static_cast<float>(n)) - 1.0f;
                const float tc = 2.0f * ((static_cast<float>(row) + b) / static_cast<float>(n)) - 1.0f;
                const glm::vec3 d = glm::normalize(raycache::shared::raycache_face_point(f, 1.0f, sc, tc));
                REQUIRE(glm::dot(d, cone.axis) >= cone.cos_spread);
            }
        }
    }
}

TEST_CASE("rays from any point of the box through any direction of a tile: the test never misses a sphere they meet") {
    // Brute force: a cube of half-size h at c; spheres placed at random; rays from the box's 8 corners, its
    // centre and random interior and surface points, through random directions of the tile. Every sphere
    // some ray meets must be reported; the test must also reject some spheres (it is not "always yes").
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const glm::vec3 c(0.3f, -0.2f, 0.1f);
    const float h = 0.9f;
    const float ball = 1.7320509f * h;
    int met = 0, rejected = 0, reported_unmet = 0;
    for (int trial = 0; trial < 600; ++trial) {
        const int n = 32, f = trial % 6;
        const int tc0 = 16 * static_cast<int>(rng() % 2u), tr0 = 16 * static_cast<int>(rng() % 2u);
        const raycache_direction_cone cone = raycache::shared::raycache_region_cone(f, tc0, tr0, tc0 + 16, tr0 + 16, n);
        const glm::vec3 s = c + 6.0f * glm::vec3(u(rng), u(rng), u(rng));
        const float r = 0.1f + 0.6f * (u(rng) + 1.0f);
        const bool said = raycache::shared::raycache_rays_from_ball_meet_sphere(c, ball, cone, s, r);
        bool any = false;
        for (int k = 0; k < 3000 && !any; ++k) {
            glm::vec3 p;
            if (k < 9) p = k == 8 ? c : c + h * glm::vec3((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
            else {
                p = c + h * glm::vec3(u(rng), u(rng), u(rng));
                if (k % 2) { // on a face of the box
                    const int axis = static_cast<int>(rng() % 3u);
                    p[axis] = c[axis] + (u(rng) < 0.0f ? -h : h);
                }
            }
            // A direction of the tile: a point of its rectangle on the face, through the texel choice.
            const float sc = 2.0f * ((static_cast<float>(tc0) + 8.0f + 8.0f * u(rng)) / n) - 1.0f;
            const float tc = 2.0f * ((static_cast<float>(tr0) + 8.0f + 8.0f * u(rng)) / n) - 1.0f;
            const glm::vec3 d = glm::normalize(raycache::shared::raycache_face_point(f, 1.0f, sc, tc));
            any = ray_meets_sphere(p, d, s, r);
        }
        if (any) {
            ++met;
            REQUIRE(said);
        } else if (!said)
            ++rejected;
        else
            ++reported_unmet;
    }
    MESSAGE(met << " spheres met, " << rejected << " rejected, " << reported_unmet << " reported without a sampled ray meeting them");
    CHECK(met > 50);
    CHECK(rejected > 100);
}

TEST_CASE("the cone from a light toward a ball holds every segment from the light to the ball") {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const glm::vec3 light(0.0f, 10.0f, 0.0f);
    int met = 0, rejected = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const glm::vec3 b(3.0f * u(rng), -0.5f + 0.5f * u(rng), 3.0f * u(rng));
        const float rb = 0.05f + 0.5f * (u(rng) + 1.0f);
        const raycache_direction_cone cone = raycache::shared::raycache_cone_toward_ball(light, b, rb);
        const glm::vec3 s(3.0f * u(rng), 1.0f + 4.0f * (u(rng) + 1.0f), 3.0f * u(rng));
        const float r = 0.2f + 0.3f * (u(rng) + 1.0f);
        bool any = false;
        for (int k = 0; k < 2000 && !any; ++k) {
            glm::vec3 q = glm::vec3(u(rng), u(rng), u(rng));
            if (glm::dot(q, q) > 1.0f) continue;
            q = b + rb * q;
            // segment light -> q meets the sphere
            const glm::vec3 d = q - light;
            const float t = glm::clamp(glm::dot(s - light, d) / glm::dot(d, d), 0.0f, 1.0f);
            const glm::vec3 p = light + t * d;
            any = glm::dot(p - s, p - s) <= r * r;
        }
        const bool said = meets(light, cone, s, r);
        if (any) {
            ++met;
            REQUIRE(said);
        } else if (!said)
            ++rejected;
    }
    CHECK(met > 20);
    CHECK(rejected > 20);
    // The light inside the ball: every direction.
    CHECK(meets(light, raycache::shared::raycache_cone_toward_ball(light, light + glm::vec3(0.1f), 1.0f), {0, -50, 0}, 0.1f));
}

TEST_CASE("sphere against box: inside, touching a face, past a corner") {
    const glm::vec3 lo(0.0f), hi(1.0f);
    CHECK(raycache::shared::raycache_box_meets_sphere(lo, hi, {0.5f, 0.5f, 0.5f}, 0.1f));
    CHECK(raycache::shared::raycache_box_meets_sphere(lo, hi, {1.5f, 0.5f, 0.5f}, 0.51f));
    CHECK(!raycache::shared::raycache_box_meets_sphere(lo, hi, {1.5f, 0.5f, 0.5f}, 0.49f));
    // Past the corner (1, 1, 1) by (1, 1, 1): distance sqrt(3) = 1.732.
    CHECK(!raycache::shared::raycache_box_meets_sphere(lo, hi, {2, 2, 2}, 1.70f));
    CHECK(raycache::shared::raycache_box_meets_sphere(lo, hi, {2, 2, 2}, 1.75f));
}

TEST_CASE("the cone of a box of unit directions holds every direction in the box, a box around zero is every direction") {
    using raycache::shared::raycache_cone_of_direction_box;
    // Box [-0.2, 0.2] x [-0.2, 0.2] x [0.9, 1]: axis +z; the widest corners (+-0.2, +-0.2, 0.9) lie at
    // cos = 0.9 / sqrt(0.89) = 0.95400 (17.45 degrees); (+-0.2, +-0.2, 1) only at 1 / sqrt(1.08) = 0.96225.
    const raycache_direction_cone c = raycache_cone_of_direction_box({-0.2f, -0.2f, 0.9f}, {0.2f, 0.2f, 1.0f});
    CHECK(c.axis.z == doctest::Approx(1.0f));
    CHECK(c.cos_spread == doctest::Approx(0.95400).epsilon(1e-4));
    CHECK(c.cos_spread <= 0.9540042f); // widened, never narrowed
    // Brute force: every unit vector inside a random box lies within the cone.
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    int boxes = 0, narrow = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const glm::vec3 a = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
        const glm::vec3 b = glm::normalize(a + 0.6f * glm::vec3(u(rng), u(rng), u(rng)));
        const glm::vec3 lo = glm::min(a, b), hi = glm::max(a, b);
        const raycache_direction_cone cone = raycache_cone_of_direction_box(lo, hi);
        ++boxes;
        narrow += cone.cos_spread > 0.0f;
        for (int k = 0; k < 2000; ++k) {
            const glm::vec3 d = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
            if (glm::any(glm::lessThan(d, lo)) || glm::any(glm::greaterThan(d, hi))) continue;
            REQUIRE(glm::dot(d, cone.axis) >= cone.cos_spread - 1e-6f);
        }
        // Its two defining directions in particular.
        CHECK(glm::dot(a, cone.axis) >= cone.cos_spread - 1e-6f);
        CHECK(glm::dot(b, cone.axis) >= cone.cos_spread - 1e-6f);
    }
    CHECK(narrow > boxes / 2); // mostly a real bound, not "every direction"
    // One direction: a cone of about the slack around it.
    const glm::vec3 one = glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f));
    const raycache_direction_cone single = raycache_cone_of_direction_box(one, one);
    CHECK(glm::dot(single.axis, one) == doctest::Approx(1.0f));
    CHECK(single.cos_spread > 0.9999f);
    // Boxes holding (0, 0, 0), or reaching past 90 degrees from their centre: every direction.
    CHECK(raycache_cone_of_direction_box({-1, -1, -1}, {1, 1, 1}).cos_spread <= -1.0f);
    CHECK(raycache_cone_of_direction_box({-1, -1, -0.1f}, {1, 1, 1}).cos_spread <= -1.0f);
    CHECK(raycache_cone_of_direction_box({0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}).cos_spread <= -1.0f);
    // ... and such a cone meets every sphere.
    CHECK(meets({0, 0, 0}, raycache_cone_of_direction_box({-1, -1, -1}, {1, 1, 1}), {0, 0, -50}, 0.1f));
}

TEST_CASE("rays from a ball through a box of unit directions: spheres away from every direction of the box are rejected, met ones never") {
    using namespace raycache::shared;
    // Both necessary conditions, as invalidation tests escaped bounces: the box's cone, and the box's facing.
    auto test = [](glm::vec3 c, float r, glm::vec3 lo, glm::vec3 hi, glm::vec3 s, float rho) {
        return raycache_rays_from_ball_meet_sphere(c, r, raycache_cone_of_direction_box(lo, hi), s, rho) &&
               raycache_direction_box_may_reach_sphere(c, r, lo, hi, s, rho);
    };
    // Directions with y >= -0.05: a box reaching past 90 degrees from its centre, whose cone is every direction.
    const glm::vec3 lo(-1.0f, -0.05f, -1.0f), hi(1.0f, 1.0f, 1.0f);
    REQUIRE(raycache_cone_of_direction_box(lo, hi).cos_spread <= -1.0f);
    // A sphere straight below (0, -10, 0), radius 1, from the ball (0, 0.5): every direction towards it has
    // y < 0, while the box's best alignment with -y is 0.05 < cos(asin(1.5 / 10)) = 0.98869.
    CHECK_FALSE(test({0, 0, 0}, 0.5f, lo, hi, {0, -10, 0}, 1.0f));
    // Beside the ball at (10, 0, 0): the direction (0.995, 0.0995, 0) lies in the box and passes
    // 10 x 0.0995 = 0.995 < 1.5 from the centre.
    CHECK(test({0, 0, 0}, 0.5f, lo, hi, {10, 0, 0}, 1.0f));
    // A sphere holding the ball's centre, whichever side: met.
    CHECK(test({0, 0, 0}, 0.5f, lo, hi, {0, -10, 0}, 9.6f));
    // At the rim: the sphere (0, -10, 0), radius 9.4, grown by the ball to 9.9, is seen within
    // asin(0.99) = 81.89 degrees of -y (cos 0.14107). Directions with y >= -0.14 come no nearer than
    // acos(0.14) = 81.95 degrees: a miss; with y >= -0.15, 81.37 degrees: met.
    CHECK_FALSE(test({0, 0, 0}, 0.5f, {-1.0f, -0.14f, -1.0f}, hi, {0, -10, 0}, 9.4f));
    CHECK(test({0, 0, 0}, 0.5f, {-1.0f, -0.15f, -1.0f}, hi, {0, -10, 0}, 9.4f));

    // Brute force: rays sampled from the ball in directions sampled inside random boxes of unit directions;
    // whenever one meets the sphere, the test says so. Wide boxes (every direction by the cone) too.
    std::mt19937 rng(41);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    int rejected = 0, rejected_by_box_alone = 0, cases = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const glm::vec3 a = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
        const glm::vec3 b = glm::normalize(a + (trial % 2 ? 0.6f : 2.0f) * glm::vec3(u(rng), u(rng), u(rng)));
        const glm::vec3 blo = glm::min(a, b), bhi = glm::max(a, b);
        const glm::vec3 c(u(rng), u(rng), u(rng));
        const float r = 0.1f + 0.5f * (u(rng) + 1.0f);
        const glm::vec3 s = c + (3.0f + 5.0f * (u(rng) + 1.0f)) * glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
        const float rho = 0.2f + (u(rng) + 1.0f);
        const bool said = test(c, r, blo, bhi, s, rho);
        ++cases;
        rejected += !said;
        rejected_by_box_alone += !said && raycache_rays_from_ball_meet_sphere(c, r, raycache_cone_of_direction_box(blo, bhi), s, rho);
        if (said) continue;
        for (int k = 0; k < 3000; ++k) {
            const glm::vec3 d = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
            if (glm::any(glm::lessThan(d, blo)) || glm::any(glm::greaterThan(d, bhi))) continue;
            glm::vec3 p(u(rng), u(rng), u(rng));
            if (glm::length(p) > 1.0f) p = glm::normalize(p);
            REQUIRE_FALSE(ray_meets_sphere(c + r * p, d, s, rho));
        }
        // The box's corners and the directions that define it, from the ball's centre and its surface.
        REQUIRE_FALSE(ray_meets_sphere(c, a, s, rho));
        REQUIRE_FALSE(ray_meets_sphere(c, b, s, rho));
        REQUIRE_FALSE(ray_meets_sphere(c + r * glm::normalize(s - c), a, s, rho));
    }
    CHECK(rejected > cases / 4);            // a real bound
    CHECK(rejected_by_box_alone > cases / 20); // and one the cone alone does not give
}

namespace {

// The distance from p to the convex hull of the balls (a, ra) and (b, rb), by brute force: the hull is the
// union of the balls a + l (b - a), radius ra + l (rb - ra), l in [0, 1] (convex combinations of the two
// balls), so the distance is the least over l of |p - centre(l)| - radius(l); sampled at 20001 values of l
// (from above: never less than the true least).
float hull_distance(glm::vec3 a, float ra, glm::vec3 b, float rb, glm::vec3 p) {
    float best = std::numeric_limits<float>::infinity();
    for (int k = 0; k <= 20000; ++k) {
        const float l = static_cast<float>(k) / 20000.0f;
        best = std::min(best, glm::length(p - (a + l * (b - a))) - (ra + l * (rb - ra)));
    }
    return best;
}

bool hull_meets(glm::vec3 a, float ra, glm::vec3 b, float rb, glm::vec3 s, float r) {
    return raycache::shared::raycache_ball_hull_meets_sphere(a, ra, b, rb, s, r);
}

// Whether the segment p -> q meets the sphere (s, r).
bool segment_meets_sphere(glm::vec3 p, glm::vec3 q, glm::vec3 s, float r) {
    const glm::vec3 d = q - p;
    const float t = glm::dot(d, d) > 0.0f ? glm::clamp(glm::dot(s - p, d) / glm::dot(d, d), 0.0f, 1.0f) : 0.0f;
    const glm::vec3 x = p + t * d;
    return glm::dot(x - s, x - s) <= r * r;
}

} // namespace

TEST_CASE("the hull of two balls against a sphere, on hand-derived cases: beside a capsule, beside a tapered one, behind the larger ball") {
    // A capsule along x (radius 1 at both ends, 10 long): a sphere 2.5 from its axis at the middle meets it
    // exactly when its radius is at least 1.5.
    CHECK_FALSE(hull_meets({0, 0, 0}, 1.0f, {10, 0, 0}, 1.0f, {5, 2.5f, 0}, 1.4f));
    CHECK(hull_meets({0, 0, 0}, 1.0f, {10, 0, 0}, 1.0f, {5, 2.5f, 0}, 1.6f));
    // Radii 3 and 1, 10 apart: the outer tangent's normal is (sin, cos) = (0.2, 0.9798) in the plane of the
    // axis, and the tangent line is 0.2 x + 0.9798 y = 3. The point (5, 4) lies 0.2 x 5 + 0.9798 x 4 - 3 =
    // 1.919 beyond it, and projects onto the tangent between the tangent points (0.9798 x 5 - 0.2 x 4 =
    // 4.099, within [0, 9.798]): a sphere there meets the hull when its radius reaches 1.919.
    CHECK_FALSE(hull_meets({0, 0, 0}, 3.0f, {10, 0, 0}, 1.0f, {5, 0, 4}, 1.85f));
    CHECK(hull_meets({0, 0, 0}, 3.0f, {10, 0, 0}, 1.0f, {5, 0, 4}, 1.99f));
    // The same, turned: the small ball first.
    CHECK_FALSE(hull_meets({10, 0, 0}, 1.0f, {0, 0, 0}, 3.0f, {5, -4, 0}, 1.85f));
    CHECK(hull_meets({10, 0, 0}, 1.0f, {0, 0, 0}, 3.0f, {5, -4, 0}, 1.99f));
    // Behind the larger ball, on the axis: 5 from its centre, so 2 from the hull.
    CHECK_FALSE(hull_meets({0, 0, 0}, 3.0f, {10, 0, 0}, 1.0f, {-5, 0, 0}, 1.9f));
    CHECK(hull_meets({0, 0, 0}, 3.0f, {10, 0, 0}, 1.0f, {-5, 0, 0}, 2.1f));
    // One ball inside the other: the hull is the larger one.
    CHECK_FALSE(hull_meets({0, 0, 0}, 5.0f, {1, 0, 0}, 1.0f, {0, 8, 0}, 2.9f));
    CHECK(hull_meets({0, 0, 0}, 5.0f, {1, 0, 0}, 1.0f, {0, 8, 0}, 3.1f));
    // Two equal balls at one place.
    CHECK(hull_meets({2, 2, 2}, 1.0f, {2, 2, 2}, 1.0f, {2, 4.9f, 2}, 2.0f));
    CHECK_FALSE(hull_meets({2, 2, 2}, 1.0f, {2, 2, 2}, 1.0f, {2, 5.1f, 2}, 2.0f));
}

TEST_CASE("the hull of two balls against a sphere: never misses a segment between the balls that meets it, and agrees with the brute-force distance") {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    auto ball_point = [&](glm::vec3 c, float r) {
        for (;;) {
            const glm::vec3 q(u(rng), u(rng), u(rng));
            if (glm::dot(q, q) <= 1.0f) return c + r * q;
        }
    };
    int met = 0, rejected = 0, segments_met = 0;
    for (int trial = 0; trial < 600; ++trial) {
        const glm::vec3 a(2.0f * u(rng), 2.0f * u(rng), 2.0f * u(rng));
        const float ra = 0.2f + 1.5f * (u(rng) + 1.0f);
        const glm::vec3 b = a + (trial % 3 == 0 ? 1.0f : 12.0f) * glm::vec3(u(rng), u(rng), u(rng));
        const float rb = 0.05f + (trial % 2 ? 0.3f : 2.0f) * (u(rng) + 1.0f);
        const glm::vec3 s = 0.5f * (a + b) + 5.0f * glm::vec3(u(rng), u(rng), u(rng));
        const float r = 0.1f + 1.5f * (u(rng) + 1.0f);
        const bool said = hull_meets(a, ra, b, rb, s, r);
        // Against the brute-force distance: a sphere reaching the hull is met; one clearly short of it is not.
        const float d = hull_distance(a, ra, b, rb, s);
        const float tolerance = 1e-3f * (1.0f + glm::length(b - a) + ra + rb + r);
        if (d <= r) REQUIRE(said);
        if (d > r + tolerance) REQUIRE_FALSE(said);
        met += said;
        rejected += !said;
        // Segments between the balls' points (inside and on their surfaces): one that meets the sphere is seen.
        for (int k = 0; k < 300; ++k) {
            glm::vec3 p = ball_point(a, ra), q = ball_point(b, rb);
            if (k % 3 == 0) p = a + ra * glm::normalize(p - a + glm::vec3(1e-6f));
            if (k % 5 == 0) q = b + rb * glm::normalize(q - b + glm::vec3(1e-6f));
            if (segment_meets_sphere(p, q, s, r)) {
                ++segments_met;
                REQUIRE(said);
            }
        }
    }
    MESSAGE(met << " configurations met, " << rejected << " rejected; " << segments_met << " sampled segments met a sphere");
    CHECK(met > 100);
    CHECK(rejected > 100);
}

TEST_CASE("the ball around a cone's shell holds every point of it, and is no larger than its farthest point needs") {
    using namespace raycache::shared;
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    // By hand: a cone of half-angle 60 degrees around +z from the origin, distances 3 to 5. The centre sits
    // at 4 on the axis; the farthest points are on the rim, at distance 3 or 5: 9 + 16 - 24 x 0.5 = 13 and
    // 25 + 16 - 40 x 0.5 = 21, so the radius is sqrt(21) = 4.583.
    const raycache_direction_cone c60{glm::vec3(0, 0, 1), 0.5f, std::sqrt(0.75f)};
    const raycache_ball hand = raycache_cone_shell_ball(glm::vec3(0.0f), c60, 3.0f, 5.0f);
    CHECK(hand.centre.z == doctest::Approx(4.0f));
    CHECK(hand.radius >= std::sqrt(21.0f));
    CHECK(hand.radius <= std::sqrt(21.0f) * 1.001f);
    for (int trial = 0; trial < 300; ++trial) {
        const glm::vec3 apex(10.0f * u(rng) - 5.0f, 10.0f * u(rng) - 5.0f, 10.0f * u(rng) - 5.0f);
        const glm::vec3 axis = glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f));
        const float spread = (trial % 2 ? 0.05f : 1.2f) * u(rng);
        const raycache_direction_cone cone{axis, std::cos(spread), std::sin(spread)};
        const float near = 20.0f * u(rng), far = near + (trial % 3 ? 1.0f : 0.01f) * 10.0f * u(rng);
        const raycache_ball ball = raycache_cone_shell_ball(apex, cone, near, far);
        // Any unit direction within the spread, at any distance in [near, far]: inside the ball.
        const glm::vec3 side = glm::normalize(glm::cross(axis, std::abs(axis.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0)));
        const glm::vec3 other = glm::cross(axis, side);
        float farthest = 0.0f;
        for (int k = 0; k < 400; ++k) {
            const float angle = (k % 4 == 0 ? 1.0f : u(rng)) * spread, around = 6.2831853f * u(rng);
            const glm::vec3 d = std::cos(angle) * axis + std::sin(angle) * (std::cos(around) * side + std::sin(around) * other);
            const float r = k % 8 == 0 ? near : k % 8 == 4 ? far : near + (far - near) * u(rng); // the rim at both ends
            const float from_centre = glm::length(apex + r * d - ball.centre);
            farthest = std::max(farthest, from_centre);
            REQUIRE(from_centre <= ball.radius + 1e-6f * (1.0f + glm::length(apex) + far)); // this test's own rounding
        }
        CHECK(ball.radius <= farthest * 1.01f + 1e-3f * (1.0f + far));
    }
}
