// The ray-space hierarchy's C++ reference (rcx/rsh_reference.hpp, raycache/shared/rsh_layout.h):
// equation 1's cone-sphere test against hand-derived cases and against sampled rays (it may accept too
// much, never reject a sphere some ray of the node meets); every node encloses its children and every ray
// below it (checked in double precision); and the hierarchy finds, for every ray, the closest hit that
// brute force over all primitives finds, on random rays and on the tracers' scenes, in one batch and in
// many. Tolerance on distances: none is needed (the same intersection test decides both ways); the check
// allows 1e-6 relative so that it states what it means.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "rcx/rsh_reference.hpp"
#include "rcx/scene.hpp"
#include "test_random.hpp"

namespace {

using namespace raycache::shared;
using rcx::rsh::Hit;
using rcx::rsh::Primitive;
using rcx::rsh::Ray;

raycache_rsh_node node(glm::vec3 c, float r, glm::vec3 d, float spread) {
    return raycache_rsh_node{c, r, glm::normalize(d), spread};
}

const float deg = 3.14159265358979f / 180.0f;

glm::vec3 random_unit(Lcg& g) {
    for (;;) {
        const glm::vec3 v(g.signed_uniform(), g.signed_uniform(), g.signed_uniform());
        const float l = glm::length(v);
        if (l > 0.1f && l <= 1.0f) return v / l;
    }
}

// A unit direction at angle exactly `angle` from unit d (towards a random side).
glm::vec3 at_angle(glm::vec3 d, float angle, Lcg& g) {
    glm::vec3 side = glm::cross(d, random_unit(g));
    while (glm::length(side) < 1e-3f) side = glm::cross(d, random_unit(g));
    side = glm::normalize(side);
    return glm::normalize(std::cos(angle) * d + std::sin(angle) * side);
}

// Whether the ray (o, unit u) meets the sphere (p, r) at some t >= 0, in double precision.
bool ray_meets_sphere(glm::dvec3 o, glm::dvec3 u, glm::dvec3 p, double r) {
    const glm::dvec3 op = p - o;
    const double t = std::max(0.0, glm::dot(op, u));
    return glm::length(op - t * u) <= r;
}

double angle_between(glm::vec3 a, glm::vec3 b) {
    const glm::dvec3 x = glm::normalize(glm::dvec3(a)), y = glm::normalize(glm::dvec3(b));
    return std::atan2(glm::length(glm::cross(x, y)), glm::dot(x, y));
}

void check_same_hits(const std::vector<Hit>& got, const std::vector<Hit>& expected) {
    REQUIRE(got.size() == expected.size());
    std::size_t hits = 0;
    for (std::size_t i = 0; i < got.size(); ++i) {
        CAPTURE(i);
        REQUIRE(got[i].primitive == expected[i].primitive);
        if (expected[i].primitive == rcx::rsh::no_hit) continue;
        ++hits;
        REQUIRE(std::abs(got[i].t - expected[i].t) <= 1e-6f * expected[i].t);
    }
    MESSAGE(hits << " of " << got.size() << " rays hit");
}

std::vector<Primitive> random_primitives(Lcg& g, int triangles, int spheres) {
    std::vector<Primitive> p;
    for (int i = 0; i < triangles; ++i) {
        const glm::vec3 c(6.0f * g.signed_uniform(), 6.0f * g.signed_uniform(), 6.0f * g.signed_uniform());
        const float size = 0.1f + 0.6f * g.uniform();
        p.push_back(rcx::rsh::triangle(c + size * random_unit(g), c + size * random_unit(g), c + size * random_unit(g)));
    }
    for (int i = 0; i < spheres; ++i)
        p.push_back(rcx::rsh::sphere(glm::vec3(6.0f * g.signed_uniform(), 6.0f * g.signed_uniform(), 6.0f * g.signed_uniform()),
                                     0.05f + 0.5f * g.uniform()));
    return p;
}

// Coherent rays, as from a curved mirror: 4^levels rays whose origins lie on a small patch and whose
// directions fan out smoothly with the Morton index; every 7th slot empty.
std::vector<Ray> coherent_rays(Lcg& g, int side) {
    std::vector<Ray> rays(static_cast<std::size_t>(side) * static_cast<std::size_t>(side));
    const glm::vec3 base(g.signed_uniform(), g.signed_uniform(), -7.0f);
    for (std::size_t m = 0; m < rays.size(); ++m) {
        const glm::uvec2 px = rcx::rsh::morton_pixel(static_cast<std::uint32_t>(m));
        const float x = (static_cast<float>(px.x) + 0.5f) / static_cast<float>(side) - 0.5f;
        const float y = (static_cast<float>(px.y) + 0.5f) / static_cast<float>(side) - 0.5f;
        const glm::vec3 o = base + glm::vec3(x, y, 0.0f);
        rays[m] = Ray{o, m % 7 == 3 ? 0.0f : std::numeric_limits<float>::infinity(),
                      glm::normalize(glm::vec3(1.4f * x, 1.4f * y, 1.0f)), static_cast<std::uint32_t>(m)};
    }
    return rays;
}

} // namespace

TEST_CASE("cone-sphere test: hand-derived cases") {
    const glm::vec3 z(0.0f, 0.0f, 1.0f);
    // A single ray along +z from the origin (radius 0, spread 0): meets spheres whose centre is within
    // their radius of the z axis.
    const raycache_rsh_node ray = node(glm::vec3(0.0f), 0.0f, z, 0.0f);
    CHECK(raycache_rsh_cone_sphere(ray, glm::vec4(0.0f, 0.0f, 5.0f, 1.0f)));
    CHECK(raycache_rsh_cone_sphere(ray, glm::vec4(0.9f, 0.0f, 5.0f, 1.0f)));
    CHECK_FALSE(raycache_rsh_cone_sphere(ray, glm::vec4(1.1f, 0.0f, 5.0f, 1.0f)));
    CHECK_FALSE(raycache_rsh_cone_sphere(ray, glm::vec4(0.0f, 2.0f, 5.0f, 1.0f)));
    // Behind the apex equation 1 is conservative: a sphere on the axis behind the origin is accepted.
    CHECK(raycache_rsh_cone_sphere(ray, glm::vec4(0.0f, 0.0f, -5.0f, 1.0f)));
    // Spread 45 degrees: the boundary line is x = z in the xz plane; the sphere at (6, 0, 5) lies
    // 1/sqrt(2) = 0.707 from it: radius 0.6 misses, 0.8 meets; a sphere on the axis far away meets.
    const raycache_rsh_node cone = node(glm::vec3(0.0f), 0.0f, z, 45.0f * deg);
    CHECK_FALSE(raycache_rsh_cone_sphere(cone, glm::vec4(6.0f, 0.0f, 5.0f, 0.6f)));
    CHECK(raycache_rsh_cone_sphere(cone, glm::vec4(6.0f, 0.0f, 5.0f, 0.8f)));
    CHECK(raycache_rsh_cone_sphere(cone, glm::vec4(4.9f, 0.0f, 5.0f, 0.01f)));
    CHECK(raycache_rsh_cone_sphere(cone, glm::vec4(0.0f, 0.0f, 100.0f, 0.01f)));
    // 30 degrees, sphere at (0, 10, 10): distance to the line y = z tan 30 is 10 cos 30 - 10 sin 30 = 3.66.
    const raycache_rsh_node cone30 = node(glm::vec3(0.0f), 0.0f, z, 30.0f * deg);
    CHECK_FALSE(raycache_rsh_cone_sphere(cone30, glm::vec4(0.0f, 10.0f, 10.0f, 3.6f)));
    CHECK(raycache_rsh_cone_sphere(cone30, glm::vec4(0.0f, 10.0f, 10.0f, 3.7f)));
    // The node's sphere radius adds to the triangle's: origins within 1 of (0, 0, 0), spread 0; the
    // sphere at (2.5, 0, 5) needs radius above 1.5.
    const raycache_rsh_node fat = node(glm::vec3(0.0f), 1.0f, z, 0.0f);
    CHECK_FALSE(raycache_rsh_cone_sphere(fat, glm::vec4(2.5f, 0.0f, 5.0f, 1.4f)));
    CHECK(raycache_rsh_cone_sphere(fat, glm::vec4(2.5f, 0.0f, 5.0f, 1.6f)));
    // An empty node meets nothing; a cone wider than RAYCACHE_RSH_WIDE_CONE meets everything.
    CHECK_FALSE(raycache_rsh_cone_sphere(raycache_rsh_empty_node(), glm::vec4(0.0f, 0.0f, 5.0f, 100.0f)));
    CHECK(raycache_rsh_cone_sphere(node(glm::vec3(0.0f), 0.0f, z, 2.0f), glm::vec4(0.0f, 0.0f, -50.0f, 0.1f)));
}

TEST_CASE("cone-sphere test: never rejects a sphere that a sampled ray of the node meets") {
    Lcg g{7};
    int rejected = 0, accepted = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const glm::vec3 c(3.0f * g.signed_uniform(), 3.0f * g.signed_uniform(), 3.0f * g.signed_uniform());
        const float r = trial % 3 == 0 ? 0.0f : 0.5f * g.uniform();
        const glm::vec3 d = random_unit(g);
        const float spread = trial % 4 == 0 ? 0.0f : 1.4f * g.uniform() * g.uniform();
        const raycache_rsh_node n = node(c, r, d, spread);
        // A sphere near the cone's boundary: at some distance along a direction just outside the cone.
        const glm::vec3 towards = at_angle(d, spread + 0.3f * g.signed_uniform(), g);
        const glm::vec3 p = c + (1.0f + 8.0f * g.uniform()) * towards;
        const float radius = 0.05f + 0.6f * g.uniform();
        if (raycache_rsh_cone_sphere(n, glm::vec4(p, radius))) {
            ++accepted;
            continue;
        }
        ++rejected;
        CAPTURE(trial);
        for (int k = 0; k < 400; ++k) {
            // Origins inside the node's sphere (on its surface half of the time), directions within the
            // spread (on the boundary half of the time).
            const glm::vec3 o = c + (k % 2 ? r : r * g.uniform()) * random_unit(g);
            const glm::vec3 u = at_angle(d, (k % 4 < 2 ? 1.0f : g.uniform()) * spread, g);
            REQUIRE_FALSE(ray_meets_sphere(o, u, p, radius));
        }
    }
    MESSAGE(rejected << " rejected, " << accepted << " accepted");
    CHECK(rejected > 50); // the test does reject: a test that always accepts would pass the loop above
    CHECK(accepted > 50);
}

TEST_CASE("hierarchy: every node encloses its children and every ray below it") {
    Lcg g{11};
    for (int side : {4, 16}) {
        CAPTURE(side);
        const std::vector<Ray> rays = coherent_rays(g, side);
        const rcx::rsh::Hierarchy h = rcx::rsh::build(rays);
        REQUIRE(h.levels == (side == 4 ? 2 : 4));
        for (int l = 0; l < h.levels; ++l) {
            for (std::size_t k = 0; k < (std::size_t{1} << (2 * l)); ++k) {
                const raycache_rsh_node& p = h.nodes[raycache_rsh_level_first(l) + k];
                // Rays below: leaves [k * 4^(L-l), (k + 1) * 4^(L-l)).
                const std::size_t span = std::size_t{1} << (2 * (h.levels - l));
                bool any = false;
                for (std::size_t i = k * span; i < (k + 1) * span; ++i) {
                    if (!(rays[i].tmax > 0.0f)) continue;
                    any = true;
                    REQUIRE(glm::length(glm::dvec3(rays[i].origin) - glm::dvec3(p.centre)) <= p.radius);
                    REQUIRE(angle_between(rays[i].direction, p.direction) <= p.spread);
                }
                REQUIRE(any == (p.radius >= 0.0f));
                for (int c = 0; c < 4; ++c) {
                    const raycache_rsh_node& ch = h.nodes[raycache_rsh_level_first(l + 1) + 4 * k + c];
                    if (ch.radius < 0.0f) continue;
                    REQUIRE(glm::length(glm::dvec3(ch.centre) - glm::dvec3(p.centre)) + ch.radius <= p.radius);
                    REQUIRE(angle_between(ch.direction, p.direction) + ch.spread <= p.spread);
                }
            }
        }
    }
    // The hand-derived case: two rays from (0,0,0) and (2,0,0) along +z and +x: the parent's sphere
    // is centred at (1,0,0) with radius 1, its cone along (1,0,1)/sqrt2 with spread 45 degrees.
    const raycache_rsh_ray a{glm::vec3(0.0f), 1.0f, glm::vec3(0.0f, 0.0f, 1.0f), 0u};
    const raycache_rsh_ray b{glm::vec3(2.0f, 0.0f, 0.0f), 1.0f, glm::vec3(1.0f, 0.0f, 0.0f), 0u};
    const raycache_rsh_node e = raycache_rsh_empty_node();
    const raycache_rsh_node p = raycache_rsh_enclose(raycache_rsh_leaf(a), e, raycache_rsh_leaf(b), e);
    CHECK(p.centre.x == doctest::Approx(1.0f));
    CHECK(p.radius == doctest::Approx(1.0f).epsilon(1e-4));
    CHECK(p.direction.x == doctest::Approx(std::sqrt(0.5f)));
    CHECK(p.direction.z == doctest::Approx(std::sqrt(0.5f)));
    CHECK(p.spread == doctest::Approx(45.0f * deg).epsilon(1e-4));
    CHECK(raycache_rsh_enclose(e, e, e, e).radius < 0.0f);
}

TEST_CASE("traversal: random rays and primitives find the brute-force closest hit, in one batch and in many") {
    Lcg g{3};
    const std::vector<Primitive> prims = random_primitives(g, 300, 40);
    const std::vector<Ray> rays = coherent_rays(g, 32);
    const std::vector<Hit> expected = rcx::rsh::brute_force(rays, prims);
    const rcx::rsh::Hierarchy h = rcx::rsh::build(rays);
    rcx::rsh::TraceStats one;
    check_same_hits(rcx::rsh::trace(rays, h, prims, 1u << 22, &one), expected);
    CHECK(one.batches == 1);
    CHECK(one.overflows == 0);
    // Leaves keep few primitives per ray (the hierarchy culls), far fewer than all 340.
    MESSAGE("leaf pairs per ray " << static_cast<double>(one.leaf_pairs) / static_cast<double>(rays.size()));
    CHECK(one.leaf_pairs < rays.size() * 40);
    rcx::rsh::TraceStats many;
    // A capacity below the pairs of the last level: batches are split until each fits.
    const std::size_t capacity = std::max<std::size_t>(one.leaf_pairs / 4, 64);
    check_same_hits(rcx::rsh::trace(rays, h, prims, capacity, &many), expected);
    CHECK(many.batches > 1);
    CHECK(many.overflows > 0);
    CHECK(many.leaf_pairs == one.leaf_pairs); // the same pairs reach the leaves, in several batches
    // Scattered rays (random origins and directions): a loose hierarchy, still exact.
    std::vector<Ray> scattered(200);
    for (Ray& r : scattered) r = Ray{glm::vec3(5.0f * g.signed_uniform(), 5.0f * g.signed_uniform(), 5.0f * g.signed_uniform()),
                                     std::numeric_limits<float>::infinity(), random_unit(g), 0u};
    scattered[17].tmax = 2.0f; // a bounded ray (shadow rays are)
    check_same_hits(rcx::rsh::trace(scattered, rcx::rsh::build(scattered), prims, 5000), rcx::rsh::brute_force(scattered, prims));
}

TEST_CASE("traversal: first-bounce rays of the tracers' scenes find the brute-force closest hit") {
    for (const std::string name : {"behind-8", "dynamic-8"}) {
        CAPTURE(name);
        const rcx::Scene base = rcx::make_scene(name);
        const rcx::Scene scene = base.dynamic() ? base.at_frame(5) : base;
        const std::vector<Ray> rays = rcx::rsh::first_bounce_rays(scene, scene.camera_at(5), 32);
        const std::vector<Primitive> prims = rcx::rsh::primitives_of(scene);
        std::size_t live = 0;
        for (const Ray& r : rays) live += r.tmax > 0.0f ? 1 : 0;
        CHECK(live > 50);
        rcx::rsh::TraceStats stats;
        check_same_hits(rcx::rsh::trace(rays, rcx::rsh::build(rays), prims, 1u << 20, &stats),
                        rcx::rsh::brute_force(rays, prims));
        MESSAGE(name << ": " << prims.size() << " primitives, " << live << " rays, leaf pairs per ray "
                     << static_cast<double>(stats.leaf_pairs) / static_cast<double>(live));
    }
}
