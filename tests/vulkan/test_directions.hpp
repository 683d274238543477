// test_directions.hpp: the directions the Vulkan cross-checks feed to GLSL, C++ and the device's sampler:
// random ones of every size, every kind of tie between magnitudes, signed zeros, directions on texel
// edges (t = k/N as exactly as floats allow) and their float neighbours, and the limits of what counts as
// a direction.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <glm/glm.hpp>

namespace rcx_test {

struct Direction {
    glm::vec3 v;
    const char* kind;
};

inline float next_up(float x, int steps) {
    for (int i = 0; i < steps; ++i) x = std::nextafter(x, std::numeric_limits<float>::infinity());
    for (int i = 0; i > steps; --i) x = std::nextafter(x, -std::numeric_limits<float>::infinity());
    return x;
}

// The direction with magnitude m along face f's major axis and face coordinates (sc, tc) (the face
// table read backwards).
inline glm::vec3 on_face(int f, float m, float sc, float tc) {
    switch (f) {
    case 0: return {m, -tc, -sc};
    case 1: return {-m, -tc, sc};
    case 2: return {sc, m, tc};
    case 3: return {sc, -m, -tc};
    case 4: return {sc, -tc, m};
    default: return {-sc, -tc, -m};
    }
}

// About 125,000 directions for face size n (100,000 of them random), each labelled with its kind;
// the same ones for the same seed.
inline std::vector<Direction> directions_for(int n, std::uint32_t seed) {
    std::vector<Direction> out;
    std::mt19937 rng(seed);
    std::normal_distribution<float> gauss;
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::uniform_int_distribution<int> exponent(-40, 40);

    // Random directions, of every size between 2^-40 and 2^40, some close to an axis.
    for (int i = 0; i < 100000; ++i) {
        glm::vec3 v(gauss(rng), gauss(rng), gauss(rng));
        if (i % 4 == 1) v[i % 3] *= 64.0f;
        v *= std::ldexp(1.0f, exponent(rng));
        out.push_back({v, "random"});
    }

    // Ties: |x| = |y| = |z|, and each pair equal with the third smaller or zero, in every sign.
    for (int i = 0; i < 150; ++i) {
        const float a = i < 5 ? std::ldexp(1.0f, i - 2) : std::ldexp(0.5f + unit(rng), exponent(rng));
        const float small[] = {a * unit(rng), 0.0f, -0.0f};
        for (int signs = 0; signs < 8; ++signs) {
            const float sx = signs & 1 ? -1.0f : 1.0f, sy = signs & 2 ? -1.0f : 1.0f, sz = signs & 4 ? -1.0f : 1.0f;
            out.push_back({{sx * a, sy * a, sz * a}, "tie xyz"});
            for (float b : small) {
                out.push_back({{sx * a, sy * a, sz * b}, "tie xy"});
                out.push_back({{sx * a, sy * b, sz * a}, "tie xz"});
                out.push_back({{sx * b, sy * a, sz * a}, "tie yz"});
            }
        }
    }

    // Signed zeros in the minor components, alone and with a non-zero third component.
    for (int i = 0; i < 200; ++i) {
        const float a = std::ldexp(0.5f + unit(rng), exponent(rng));
        const float c = a * (2.0f * unit(rng) - 1.0f);
        for (int axis = 0; axis < 3; ++axis)
            for (int signs = 0; signs < 8; ++signs) {
                glm::vec3 v(signs & 2 ? -0.0f : 0.0f, signs & 4 ? -0.0f : 0.0f, 0.0f);
                glm::vec3 w(v.x, c, 0.0f);
                const float major = signs & 1 ? -a : a;
                v = glm::vec3(v.x, v.y, major);
                w = glm::vec3(w.x, w.y, major);
                // rotate the components so the major one is `axis`
                for (int r = 0; r < axis + 1; ++r) {
                    v = glm::vec3(v.z, v.x, v.y);
                    w = glm::vec3(w.z, w.x, w.y);
                }
                out.push_back({v, "signed zeros"});
                out.push_back({w, "signed zero + minor"});
            }
    }

    // Texel edges: sc = (2k/N - 1) m, so that t = sc * (0.5/m) + 0.5 is k/N as nearly as floats allow,
    // and its neighbours 1 and 2 floats away, on every face, along columns and rows, for several m.
    std::vector<int> ks;
    if (n <= 64) {
        for (int k = 0; k <= n; ++k) ks.push_back(k);
    } else {
        std::uniform_int_distribution<int> any_k(0, n);
        ks = {0, 1, n / 2, n - 1, n};
        while (ks.size() < 180) ks.push_back(any_k(rng));
    }
    for (int f = 0; f < 6; ++f)
        for (int k : ks)
            for (int mi = 0; mi < 4; ++mi) {
                const float m = mi == 0 ? 1.0f : mi == 1 ? 0.75f : mi == 2 ? 0.3f + 3.0f * unit(rng)
                                                                           : std::ldexp(0.5f + unit(rng), exponent(rng));
                const float edge = static_cast<float>((2.0 * k / n - 1.0) * m);
                for (int step = -2; step <= 2; ++step) {
                    const float sc = next_up(edge, step);
                    const float other = m * (2.0f * unit(rng) - 1.0f) * 0.999f;
                    out.push_back({on_face(f, m, sc, other), "texel edge (column)"});
                    out.push_back({on_face(f, m, other, sc), "texel edge (row)"});
                }
            }

    // The limits of a direction: major magnitude 2^-64 and 2^64 (directions) and one float beyond
    // (not directions); zero, infinite and NaN vectors (not directions).
    const float lowest = std::ldexp(1.0f, -64), highest = std::ldexp(1.0f, 64);
    for (int i = 0; i < 100; ++i) {
        const float u = 2.0f * unit(rng) - 1.0f, w = 2.0f * unit(rng) - 1.0f;
        for (float m : {lowest, next_up(lowest, 1), next_up(lowest, -1), highest, next_up(highest, -1), next_up(highest, 1)})
            for (int f = 0; f < 6; ++f) out.push_back({on_face(f, m, u * m, w * m), "limits"});
    }
    // Subnormal minor components, which GPUs may flush to zero, next to majors from the smallest up.
    for (int i = 0; i < 100; ++i) {
        const float tiny = std::ldexp(2.0f * unit(rng) - 1.0f, -127 - i % 22);
        for (float m : {lowest, 1.0f, highest})
            for (int f = 0; f < 6; ++f) {
                out.push_back({on_face(f, m, tiny, (2.0f * unit(rng) - 1.0f) * m), "subnormal minor"});
                out.push_back({on_face(f, m, -tiny, tiny), "subnormal minor"});
            }
    }
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    for (glm::vec3 v : {glm::vec3(0.0f), glm::vec3(-0.0f), glm::vec3(inf, 0, 0), glm::vec3(1, -inf, 0),
                        glm::vec3(nan, 1, 1), glm::vec3(1, 1, nan), glm::vec3(inf, inf, inf), glm::vec3(1e-40f, 0, 0)})
        out.push_back({v, "not a direction"});
    return out;
}

} // namespace rcx_test
