// Operands for testing correctly rounded division and square root (raycache/shared/rounding.h), shared by
// the C++ test of the refinements (test_rounding.cpp) and the GLSL one on a Vulkan device
// (vulkan/test_vulkan_rounding.cpp): random operands, and the hard cases, whose exact results lie within a
// hair of the midpoint between two floats, built with exact integer arithmetic.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

namespace rounding_cases {

// x moved by k ulps (k < 0: towards -infinity).
inline float moved(float x, int k) {
    for (; k > 0; --k) x = std::nextafter(x, INFINITY);
    for (; k < 0; ++k) x = std::nextafter(x, -INFINITY);
    return x;
}

// A float with a random significand and an exponent in [lo, hi], random sign.
inline float random_float(std::mt19937& rng, int lo, int hi) {
    const std::uint32_t significand = rng() & 0x7FFFFFu;
    const int exponent = std::uniform_int_distribution<int>(lo, hi)(rng);
    const float f = std::ldexp(1.0f + static_cast<float>(significand) * 0x1p-23f, exponent);
    return (rng() & 1u) ? -f : f;
}

// Operands whose exact quotient lies within about 2^-24 ulp of the midpoint between two floats (the
// hardest rounding decisions): for odd B and a small c, M = c / B mod 2^25 makes M B - c a multiple of 2^25,
// so A = (M B - c) / 2^25 and A / B = M / 2^25 - c / (2^25 B), with M / 2^25 a midpoint when M is odd and
// has 25 bits. Returns false when A does not fit a float's significand.
inline bool near_midpoint_quotient(std::uint32_t b_odd, int c, float& a, float& b) {
    std::uint32_t inverse = b_odd; // Newton's iteration for 1 / B mod 2^32: each step doubles the bits
    for (int i = 0; i < 5; ++i) inverse *= 2u - b_odd * inverse;
    const std::int64_t m = static_cast<std::int64_t>((static_cast<std::uint32_t>(c) * inverse) & 0x1FFFFFFu);
    if (m < (1 << 24) || (m & 1) == 0) return false;
    const std::int64_t numerator = m * static_cast<std::int64_t>(b_odd) - c;
    const std::int64_t quotient_a = numerator >> 25;
    if ((numerator & 0x1FFFFFF) != 0 || quotient_a >= (1 << 24)) return false;
    a = static_cast<float>(quotient_a);
    b = static_cast<float>(b_odd);
    return true;
}

// x whose exact root lies within about 2^-24 ulp of a midpoint: odd 25-bit M with M^2 = delta mod 2^26
// for a small delta = 1 mod 8 (Hensel lifting finds the roots of delta mod 2^26), x = (M^2 - delta) / 2^26,
// so sqrt(x) = M / 2^13 - delta / (2^14 M) nearly, and M / 2^13 is halfway between two floats.
inline int near_midpoint_squares(int delta, float out[4]) {
    std::uint64_t r = 1; // a root of delta mod 8, lifted one bit at a time
    for (int k = 3; k < 26; ++k)
        if (((r * r - static_cast<std::uint64_t>(static_cast<std::int64_t>(delta))) & ((std::uint64_t{1} << (k + 1)) - 1)) != 0)
            r += std::uint64_t{1} << (k - 1);
    const std::uint64_t mod = std::uint64_t{1} << 26;
    const std::uint64_t roots[4] = {r % mod, (mod - r) % mod, (r + mod / 2) % mod, (mod - r + mod / 2) % mod};
    int n = 0;
    for (const std::uint64_t m : roots) {
        if (m < (1u << 24) || m >= (1u << 25)) continue;
        const std::int64_t square = static_cast<std::int64_t>(m * m) - delta;
        if (square % (std::int64_t{1} << 26) != 0) continue;
        const std::int64_t x = square >> 26;
        if (x > 0 && x < (1 << 24)) out[n++] = static_cast<float>(x);
    }
    return n;
}

using Division = std::pair<float, float>; // a, b

inline std::vector<Division> random_divisions(std::mt19937& rng, int n) {
    std::vector<Division> out;
    for (int i = 0; i < n; ++i) out.push_back({random_float(rng, -40, 40), random_float(rng, -40, 40)});
    return out;
}

// a = RN(m b) for a midpoint m between two floats (within half an ulp of a of it), with b's significand all
// ones for a third of them; and quotients within 2^-24 ulp of a midpoint, n of them, scaled by powers of two.
inline std::vector<Division> near_midpoint_divisions(std::mt19937& rng, int n) {
    std::vector<Division> out;
    for (int i = 0; i < n; ++i) {
        const float q = std::abs(random_float(rng, -20, 20));
        const double m = (static_cast<double>(q) + static_cast<double>(std::nextafter(q, INFINITY))) / 2.0;
        const float b = (i % 3 == 0) ? std::ldexp(0x1.fffffep0f, (i % 7) - 3) : std::abs(random_float(rng, -20, 20));
        const float a = static_cast<float>(m * static_cast<double>(b));
        out.push_back({a, b});
        out.push_back({-a, b});
    }
    for (int made = 0, i = 0; made < n && i < 20 * n; ++i) {
        float a = 0.0f, b = 0.0f;
        const int c = (static_cast<int>(rng() % 4u) * 2 + 1) * ((rng() & 1u) ? 1 : -1);
        if (!near_midpoint_quotient((rng() & 0x7FFFFFu) | 0x800001u, c, a, b)) continue;
        ++made;
        const int shift = static_cast<int>(rng() % 41u) - 20;
        out.push_back({std::ldexp(a, shift), b});
        out.push_back({-a, std::ldexp(b, -shift)});
    }
    return out;
}

// Exact quotients (the residual is 0) and small integers.
inline std::vector<Division> exact_divisions(std::mt19937& rng, int n) {
    std::vector<Division> out;
    for (int i = 0; i < n; ++i) {
        const float q = random_float(rng, -20, 20);
        const float b = std::ldexp(1.0f, (i % 41) - 20);
        out.push_back({q * b, b});
        out.push_back({static_cast<float>(i % 8191 + 1), static_cast<float>(i % 4093 + 1)});
    }
    return out;
}

inline std::vector<float> random_roots(std::mt19937& rng, int n) {
    std::vector<float> out;
    for (int i = 0; i < n; ++i) out.push_back(std::abs(random_float(rng, -60, 60)));
    return out;
}

// RN(m^2) for midpoints m, and its neighbours; and every root within 2^-24 ulp of a midpoint that
// near_midpoint_squares makes for |delta| < 4096, also scaled by even powers of two.
inline std::vector<float> near_midpoint_roots(std::mt19937& rng, int n) {
    std::vector<float> out;
    for (int i = 0; i < n; ++i) {
        const float s = std::abs(random_float(rng, -30, 30));
        const double m = (static_cast<double>(s) + static_cast<double>(std::nextafter(s, INFINITY))) / 2.0;
        const float x = static_cast<float>(m * m);
        out.insert(out.end(), {x, std::nextafter(x, INFINITY), std::nextafter(x, 0.0f)});
    }
    for (int delta = -4095; delta <= 4097; delta += 8) { // every small delta = 1 mod 8
        float x[4];
        const int k = near_midpoint_squares(delta, x);
        for (int j = 0; j < k; ++j) out.insert(out.end(), {x[j], std::ldexp(x[j], 2 * (delta % 17))});
    }
    return out;
}

// Squares of floats, powers of two and their neighbours (the ends of a binade).
inline std::vector<float> exact_roots(std::mt19937& rng, int n) {
    std::vector<float> out;
    for (int i = 0; i < n; ++i) {
        const float s = std::abs(random_float(rng, -30, 30));
        const float p = std::ldexp(1.0f, (i % 101) - 50);
        out.insert(out.end(), {s * s, p, std::nextafter(p, 0.0f), std::nextafter(p, INFINITY)});
    }
    return out;
}

} // namespace rounding_cases
