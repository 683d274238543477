// An analytic world for the invalidation tests (test_invalidation*.cpp): thirteen spheres of distinct
// colours around a mirror ball of radius 1 at the origin (not itself in the world), lit by a point light
// with shadows, one sphere above the others casting its shadow on them. Traced exactly (ray-sphere), with
// the path records a tracer would report.
#pragma once

#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "raycache/cdct.hpp"
#include "raycache/cube_face.hpp"
#include "raycache/invalidation.hpp"
#include "raycache/path_record.hpp"

namespace analytic {

using raycache::PathRecord;
using raycache::TexelAddress;

struct Ball {
    glm::vec3 centre;
    float radius;
    glm::vec3 colour;
    bool mirror = false; // reflects (colour x what its reflected ray sees), unlit
};

struct World {
    std::vector<Ball> balls;
    glm::vec3 light{0.0f, 8.0f, 0.0f};

    // Nearest ball hit by o + t d (t > 0), or -1.
    int nearest(glm::vec3 o, glm::vec3 d, float* t_hit, float t_max = INFINITY) const {
        int best = -1;
        float best_t = t_max;
        for (std::size_t i = 0; i < balls.size(); ++i) {
            const glm::vec3 oc = o - balls[i].centre;
            const float b = glm::dot(oc, d), c = glm::dot(oc, oc) - balls[i].radius * balls[i].radius;
            const float disc = b * b - c;
            if (disc < 0.0f) continue;
            const float t = -b - std::sqrt(disc);
            if (t > 1e-4f && t < best_t) best_t = t, best = static_cast<int>(i);
        }
        if (t_hit) *t_hit = best_t;
        return best;
    }

    // The colour seen along o + t d (d unit): the ball's colour, dimmed when the light is shadowed; black
    // sky. Fills `path` when given.
    glm::vec3 trace(glm::vec3 o, glm::vec3 d, PathRecord* path = nullptr) const { return traced(o, d, path).color; }

    // trace() with the distance to the hit (infinity for the sky), as a CDCT store takes it. Mirror balls
    // reflect up to 3 bounces deep; the path records what a tracer would report: every hit, shadow rays
    // (lit), bounces from a hit point that hit something (chained) or escaped (escaped(direction)).
    raycache::TracedRay traced(glm::vec3 o, glm::vec3 d, PathRecord* path = nullptr, int bounce = 0) const {
        float t = 0.0f;
        const int i = nearest(o, d, &t);
        if (i < 0) {
            if (path && bounce > 0) path->escaped(d);
            return {glm::vec3(0.0f), INFINITY};
        }
        const glm::vec3 p = o + t * d;
        const Ball& ball = balls[static_cast<std::size_t>(i)];
        if (path) {
            path->hit(static_cast<std::uint64_t>(i), p);
            if (bounce > 0) path->chained = true;
        }
        const glm::vec3 n = glm::normalize(p - ball.centre);
        const glm::vec3 q = p + 1e-3f * n;
        if (ball.mirror) {
            if (bounce >= 3) return {glm::vec3(0.0f), t};
            return {ball.colour * traced(q, glm::reflect(d, n), path, bounce + 1).color, t};
        }
        if (path) path->lit = true;
        const glm::vec3 to_light = light - q;
        const float dist = glm::length(to_light);
        const bool shadowed = nearest(q, to_light / dist, nullptr, dist) >= 0;
        return {ball.colour * (shadowed ? 0.25f : 1.0f), t};
    }
};

inline World make_world() {
    World w;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int i = 0; i < 12; ++i) {
        const float a = 6.2831853f * static_cast<float>(i) / 12.0f;
        const float r = 3.0f + 2.0f * u(rng);
        w.balls.push_back({glm::vec3(r * std::cos(a), -0.6f + 1.2f * u(rng), r * std::sin(a)), 0.35f + 0.35f * u(rng),
                           glm::vec3(0.2f + 0.8f * u(rng), 0.2f + 0.8f * u(rng), 0.2f + 0.8f * u(rng))});
    }
    // A ball above, between the others and the light: its shadow falls on them.
    w.balls.push_back({glm::vec3(3.5f, 3.0f, 0.2f), 0.5f, glm::vec3(0.9f, 0.9f, 0.9f)});
    return w;
}

const raycache::CubeBounds box{glm::vec3(0.0f), 1.0f};

// A random direction through texel `a` and a random point of the cube's box (corners now and then).
struct Sampler {
    std::mt19937 rng{17};
    std::uniform_real_distribution<float> u{0.0f, 1.0f};
    glm::vec3 direction(const TexelAddress& a, int n) {
        const float sc = 2.0f * ((static_cast<float>(a.column) + u(rng)) / static_cast<float>(n)) - 1.0f;
        const float tc = 2.0f * ((static_cast<float>(a.row) + u(rng)) / static_cast<float>(n)) - 1.0f;
        return glm::normalize(raycache::shared::raycache_face_point(a.face, 1.0f, sc, tc));
    }
    glm::vec3 origin(int k) {
        if (k < 8) return box.half_size * glm::vec3((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
        return box.half_size * glm::vec3(2.0f * u(rng) - 1.0f, 2.0f * u(rng) - 1.0f, 2.0f * u(rng) - 1.0f);
    }
};

// Rays leaving the mirror ball (radius 1 at the origin): from a random point of its surface into the
// half-space of its normal. The same seed gives the same rays.
struct LeavingRays {
    std::mt19937 rng;
    std::normal_distribution<float> g;
    explicit LeavingRays(unsigned seed) : rng(seed) {}
    // One ray: its origin (the surface point, which is also its normal) and its unit direction.
    std::pair<glm::vec3, glm::vec3> next() {
        const glm::vec3 n = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
        glm::vec3 d = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
        if (glm::dot(d, n) < 0.0f) d = -d;
        return {n, d};
    }
};

// The moves the oracle tests make, one at a time: ball 0 and ball 4 of the ring, and ball 12, the shadow
// caster above, each shifted by (0.3, 0.25, -0.2). The world after each, with the moved ball's index.
inline std::vector<std::pair<std::size_t, World>> test_moves(const World& before) {
    std::vector<std::pair<std::size_t, World>> moves;
    for (std::size_t moved : {std::size_t{0}, std::size_t{4}, std::size_t{12}}) {
        World after = before;
        after.balls[moved].centre += glm::vec3(0.3f, 0.25f, -0.2f);
        moves.push_back({moved, after});
    }
    return moves;
}

inline raycache::SceneChanges move_of(const World& before, const World& after, std::size_t i) {
    raycache::SceneChanges changes;
    changes.moved.push_back({i, {before.balls[i].centre, before.balls[i].radius}, {after.balls[i].centre, after.balls[i].radius}});
    changes.lights.push_back(before.light);
    return changes;
}

} // namespace analytic
