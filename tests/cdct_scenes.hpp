// cdct_scenes.hpp: CDCT cubes and rays for the tests that compare searches bit for bit: GLSL against C++
// (tests/vulkan/test_vulkan_cdct.cpp) and a build with FMA contraction against a plain one
// (tests/fma_search_hash.cpp). Two kinds of cube contents:
//   analytic  every texel written by store_at: a sphere of radius 5 with an unfilled cap, rolling hills
//             of depth 2..5 with parallax, a small cube of random depths (random colours);
//   stored    cubes filled the way a tracer fills them: rays from inside the box traced through a small
//             world (an open-topped room with three spheres) and handed to cdct_cached_trace over a few
//             frames, so texels hold what stores made of real hits and escapes, with holes where no ray
//             went.
// Rays: from inside and around each box, plus bad ones (NaN or infinite origins, zero, NaN and infinite
// directions, ties and signed zeros).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <raycache/raycache.hpp>
#include <raycache/shared/gpu_layout.h>

#include "cube_words.hpp"

namespace rcx_test {

// Cubes that share one GPU texel buffer: cube k's texels start at descriptors[k].first_texel.
struct CdctScene {
    std::vector<raycache::CdctCube> cubes;
    std::vector<raycache::CubeBounds> bounds;
    std::vector<raycache::shared::raycache_gpu_cube> descriptors;
    std::size_t elements = 0;

    void add(int n, raycache::CubeBounds b) {
        cubes.emplace_back(n);
        bounds.push_back(b);
        descriptors.push_back(
            raycache::shared::raycache_make_gpu_cube(b.centre, b.half_size, static_cast<std::uint32_t>(elements), n));
        descriptors.back().index = static_cast<std::uint32_t>(cubes.size() - 1); // its GPU counters
        elements += cubes.back().texel_count();
    }
    // Every cube's words, in buffer order.
    std::vector<std::uint64_t> words() const {
        std::vector<std::uint64_t> all;
        for (const raycache::CdctCube& cube : cubes) {
            const std::vector<std::uint64_t> w = words_of(cube);
            all.insert(all.end(), w.begin(), w.end());
        }
        return all;
    }
};

// A direction of random length (2^-10 .. 2^10), not unit: searches must make it unit themselves.
inline glm::vec3 random_direction(std::mt19937& rng) {
    std::normal_distribution<float> g;
    return glm::vec3(g(rng), g(rng), g(rng)) * std::exp2(std::uniform_real_distribution<float>(-10, 10)(rng));
}

// Calls f(texel, unit direction from the centre through the texel's centre) for every texel of the cube.
template <class F>
void for_each_texel_direction(const raycache::CdctCube& cube, F&& f) {
    const int n = cube.face_size();
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column) {
                const raycache::TexelAddress t{face, column, row};
                f(t, glm::normalize(raycache::texel_direction(t, n)));
            }
}

// Three cubes in one buffer, filled analytically when `fill` (see the top of the file); texel colours random.
inline CdctScene make_analytic_scene(std::mt19937& rng, bool fill) {
    using namespace raycache;
    CdctScene s;
    s.add(32, CubeBounds{glm::vec3(1.0f, 2.0f, 3.0f), 1.0f});
    s.add(64, CubeBounds{glm::vec3(-4.0f, 0.5f, 2.0f), 0.75f});
    s.add(7, CubeBounds{glm::vec3(0.0f), 2.0f});
    if (!fill) return s;
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (std::size_t c = 0; c < s.cubes.size(); ++c) {
        CdctCube& cube = s.cubes[c];
        for_each_texel_direction(cube, [&](const TexelAddress& t, const glm::vec3& d) {
            float depth;
            if (c == 0) {
                if (d.y > 0.8f) return; // the hole
                depth = 5.0f;
            } else if (c == 1) {
                depth = 3.5f + 1.5f * std::sin(3.0f * d.x) * std::cos(2.0f * d.z);
            } else {
                depth = 2.5f + 5.0f * u(rng);
            }
            cube.store_at(t, DepthSample{glm::vec3(u(rng), u(rng), u(rng)), depth});
        });
        cube.begin_frame();
    }
    return s;
}

// One ray a tracer traced from a cached object, and what it found: handed to cdct_cached_trace in `frame`.
struct TracedSample {
    std::uint32_t cube;
    std::uint32_t frame;
    glm::vec3 origin;
    glm::vec3 direction; // not unit length
    raycache::TracedRay traced;
};

// The world around a stored cube, from its centre: an open-topped room (walls at x, z = +-6, floor at
// y = -3; rays leaving above y = 4 escape) with three spheres. Colour and distance along unit d from o.
inline raycache::TracedRay trace_world(const glm::vec3& centre, const glm::vec3& origin, const glm::vec3& d) {
    const glm::vec3 o = origin - centre;
    float best = std::numeric_limits<float>::infinity();
    glm::vec3 color(0.0f);
    const glm::vec4 spheres[] = {{2.5f, -1.0f, 0.5f, 1.2f}, {-1.5f, 0.5f, -2.5f, 0.8f}, {0.3f, 2.5f, 1.8f, 0.6f}};
    for (int k = 0; k < 3; ++k) {
        const glm::vec3 oc = o - glm::vec3(spheres[k]);
        const float b = glm::dot(oc, d), c = glm::dot(oc, oc) - spheres[k].w * spheres[k].w;
        const float disc = b * b - c;
        if (disc < 0.0f) continue;
        float t = -b - std::sqrt(disc);
        if (t <= 0.0f) t = -b + std::sqrt(disc);
        if (t > 0.0f && t < best) {
            best = t;
            color = glm::vec3(0.2f + 0.3f * k, 0.9f - 0.25f * k, 0.5f) * (0.5f + 0.5f * std::abs(d.y));
        }
    }
    // The room: leave through the nearest wall or floor; above the top, the environment.
    const float lo[3] = {-6.0f, -3.0f, -6.0f}, hi[3] = {6.0f, 4.0f, 6.0f};
    float exit = std::numeric_limits<float>::infinity();
    int axis = -1;
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0f) continue;
        const float t = ((d[a] > 0.0f ? hi[a] : lo[a]) - o[a]) / d[a];
        if (t < exit) exit = t, axis = a;
    }
    if (exit < best && axis >= 0 && !(axis == 1 && d.y > 0.0f)) {
        const glm::vec3 p = o + exit * d;
        const int checker = (static_cast<int>(std::floor(p.x)) + static_cast<int>(std::floor(p.y)) +
                             static_cast<int>(std::floor(p.z))) & 1;
        best = exit;
        color = checker ? glm::vec3(0.8f, 0.75f, 0.7f) : glm::vec3(0.1f, 0.15f, 0.3f + 0.1f * axis);
    } else if (exit < best) {
        best = std::numeric_limits<float>::infinity();
        color = glm::vec3(0.4f, 0.6f, 1.0f); // the sky
    }
    return raycache::TracedRay{color, best};
}

// Three empty cubes (face sizes 32, 48 and 16) and the rays that fill them: per cube per_cube rays from
// inside its box, over `frames` frames. Every 53rd ray reports a hit behind its origin (not stored), every
// 61st a NaN distance (an escape), every 67th has a zero direction (nothing stored).
inline CdctScene make_stored_scene(std::mt19937& rng, int per_cube, int frames, std::vector<TracedSample>& samples) {
    using namespace raycache;
    CdctScene s;
    s.add(32, CubeBounds{glm::vec3(0.5f, -1.0f, 2.0f), 1.0f});
    s.add(48, CubeBounds{glm::vec3(-3.0f, 1.0f, 0.0f), 0.5f});
    s.add(16, CubeBounds{glm::vec3(2.0f, 2.0f, -2.0f), 1.5f});
    std::uniform_real_distribution<float> u(-0.9f, 0.9f);
    for (std::uint32_t c = 0; c < s.cubes.size(); ++c)
        for (int i = 0; i < per_cube; ++i) {
            TracedSample t{};
            t.cube = c;
            t.frame = static_cast<std::uint32_t>(i % frames);
            t.origin = s.bounds[c].centre + s.bounds[c].half_size * glm::vec3(u(rng), u(rng), u(rng));
            t.direction = random_direction(rng);
            t.traced = trace_world(s.bounds[c].centre, t.origin, glm::normalize(t.direction));
            if (i % 53 == 7) t.traced.distance = -1.0f;
            if (i % 61 == 8) t.traced.distance = std::nanf("");
            if (i % 67 == 9) t.direction = glm::vec3(0.0f);
            samples.push_back(t);
        }
    return s;
}

// Fills the cubes with the samples as a tracer would: frame by frame, each ray through cdct_cached_trace
// (a search with p, then a store of what the ray found on a miss), then begin_frame().
inline void apply_samples(CdctScene& s, const std::vector<TracedSample>& samples, const raycache::ReliefParameters& p) {
    std::uint32_t frames = 0;
    for (const TracedSample& t : samples) frames = std::max(frames, t.frame + 1);
    for (std::uint32_t frame = 0; frame < frames; ++frame) {
        for (const TracedSample& t : samples)
            if (t.frame == frame)
                raycache::cdct_cached_trace(s.cubes[t.cube], s.bounds[t.cube], t.origin, t.direction, p,
                                            [&] { return t.traced; });
        for (raycache::CdctCube& cube : s.cubes) cube.begin_frame();
    }
}

// A search ray: from origin in direction (any length) through cube `cube` of a scene.
struct CdctRay {
    glm::vec3 origin;
    std::uint32_t cube;
    glm::vec3 direction;
};

// per_cube rays per cube from inside and around its box (every fifth origin up to 3 half-sizes out),
// with the bad ones of the top of the file mixed in.
inline std::vector<CdctRay> search_rays(const CdctScene& s, std::mt19937& rng, int per_cube) {
    std::vector<CdctRay> rays;
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const float inf = std::numeric_limits<float>::infinity(), nan = std::nanf("");
    for (std::uint32_t c = 0; c < s.cubes.size(); ++c)
        for (int i = 0; i < per_cube; ++i) {
            const float reach = i % 5 == 0 ? 3.0f : 0.95f; // every fifth origin may lie outside the box
            CdctRay q{};
            q.origin = s.bounds[c].centre + s.bounds[c].half_size * reach * glm::vec3(u(rng), u(rng), u(rng));
            q.direction = random_direction(rng);
            q.cube = c;
            switch (i % 97) {
            case 1: q.origin.x = nan; break;
            case 2: q.origin.y = inf; break;
            case 3: q.direction = glm::vec3(0.0f); break;
            case 4: q.direction = glm::vec3(nan, 1.0f, 0.0f); break;
            case 5: q.direction = glm::vec3(-0.0f, 1.0f, 0.0f); break;
            case 6: q.direction = glm::vec3(1.0f, -1.0f, 1.0f); break;
            case 7: q.direction = glm::vec3(2.0f, 2.0f, -0.0f); break;
            case 8: q.direction = glm::vec3(0.0f, 0.0f, -inf); break;
            default: break;
            }
            rays.push_back(q);
        }
    return rays;
}

// Parameter sets of the secant search the comparisons run: epsilon from 1e-4 to 0.2, max_gap finite and
// infinite, max_reads 1, 4, 8 and 64.
inline std::vector<raycache::ReliefParameters> secant_parameter_sets() {
    const float inf = std::numeric_limits<float>::infinity();
    struct Set {
        float epsilon, max_gap;
        int max_reads;
    };
    const Set sets[] = {{0.02f, inf, 8},   {0.02f, 0.5f, 8}, {0.002f, inf, 64}, {0.2f, 0.3f, 4},
                        {0.02f, inf, 1},   {0.005f, 0.1f, 64}, {0.05f, inf, 4}, {1e-4f, 0.5f, 64}};
    std::vector<raycache::ReliefParameters> out;
    for (const Set& set : sets) {
        raycache::ReliefParameters p;
        p.search = raycache::DepthSearch::secant;
        p.epsilon = set.epsilon;
        p.max_gap = set.max_gap;
        p.max_reads = set.max_reads;
        out.push_back(p);
    }
    return out;
}

} // namespace rcx_test
