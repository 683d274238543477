// The GLSL side's correctly rounded division and square root (raycache/shared/rounding.h), run in C++ from
// starts a GPU might give (the right result moved by up to 3 ulps, and a reciprocal likewise off), against
// the CPU's IEEE division and square root, which round to nearest. Inputs include the hard cases: results
// that lie within a hair of the midpoint between two floats, built from exact double arithmetic.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <ios>
#include <random>

#include <raycache/shared/rounding.h>

using raycache::shared::raycache_divide_refined;
using raycache::shared::raycache_sqrt_refined;

namespace {

// x moved by k ulps (k < 0: towards -infinity).
float moved(float x, int k) {
    for (; k > 0; --k) x = std::nextafter(x, INFINITY);
    for (; k < 0; ++k) x = std::nextafter(x, -INFINITY);
    return x;
}

// A float with a random significand and an exponent in [lo, hi], random sign.
float random_float(std::mt19937& rng, int lo, int hi) {
    const std::uint32_t significand = rng() & 0x7FFFFFu;
    const int exponent = std::uniform_int_distribution<int>(lo, hi)(rng);
    float f = std::ldexp(1.0f + static_cast<float>(significand) * 0x1p-23f, exponent);
    return (rng() & 1u) ? -f : f;
}

struct Tally {
    long checked = 0, wrong = 0;
};

void check_divide(float a, float b, Tally& t) {
    const float expected = a / b;
    for (int kq = -3; kq <= 3; ++kq)
        for (int ky = -2; ky <= 2; ky += 2) {
            const float got = raycache_divide_refined(a, b, moved(expected, kq), moved(1.0f / b, ky));
            ++t.checked;
            if (got != expected) {
                if (++t.wrong <= 5)
                    MESSAGE("divide " << std::hexfloat << a << " / " << b << " from " << kq << " ulp: " << got
                                      << ", expected " << expected);
            }
        }
}

void check_sqrt(float x, Tally& t) {
    const float expected = std::sqrt(x);
    for (int ks = -3; ks <= 3; ++ks)
        for (int kh = -2; kh <= 2; kh += 2) {
            const float got = raycache_sqrt_refined(x, moved(expected, ks), moved(0.5f / expected, kh));
            ++t.checked;
            if (got != expected) {
                if (++t.wrong <= 5)
                    MESSAGE("sqrt " << std::hexfloat << x << " from " << ks << " ulp: " << got << ", expected " << expected);
            }
        }
}

// Operands whose exact quotient lies within about 2^-24 ulp of the midpoint between two floats (the
// hardest rounding decisions): for odd B and a small c, M = c / B mod 2^25 makes M B - c a multiple of 2^25,
// so A = (M B - c) / 2^25 and A / B = M / 2^25 - c / (2^25 B), with M / 2^25 a midpoint when M is odd and
// has 25 bits. Returns false when A does not fit a float's significand.
bool near_midpoint_quotient(std::uint32_t b_odd, int c, float& a, float& b) {
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
int near_midpoint_squares(int delta, float out[4]) {
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

} // namespace

TEST_CASE("refined division rounds to nearest from starts up to 3 ulps off") {
    std::mt19937 rng(20261128);
    Tally t;
    SUBCASE("random operands") {
        for (int i = 0; i < 60000; ++i) check_divide(random_float(rng, -40, 40), random_float(rng, -40, 40), t);
    }
    SUBCASE("quotients within a hair of a midpoint") {
        // a = RN(m b) for a midpoint m between two floats q and q+: a / b is then as close to m as a float
        // a can make it, which is where a wrong rounding decision shows.
        for (int i = 0; i < 60000; ++i) {
            const float q = std::abs(random_float(rng, -20, 20));
            const double m = (static_cast<double>(q) + static_cast<double>(std::nextafter(q, INFINITY))) / 2.0;
            const float b = (i % 3 == 0) ? std::ldexp(0x1.fffffep0f, (i % 7) - 3) : std::abs(random_float(rng, -20, 20));
            const float a = static_cast<float>(m * static_cast<double>(b));
            check_divide(a, b, t);
            check_divide(-a, b, t);
        }
    }
    SUBCASE("quotients within 2^-24 ulp of a midpoint") {
        int made = 0;
        for (int i = 0; made < 20000 && i < 400000; ++i) {
            float a = 0.0f, b = 0.0f;
            const int c = (static_cast<int>(rng() % 4u) * 2 + 1) * ((rng() & 1u) ? 1 : -1);
            if (!near_midpoint_quotient((rng() & 0x7FFFFFu) | 0x800001u, c, a, b)) continue;
            ++made;
            const int shift = static_cast<int>(rng() % 41u) - 20;
            check_divide(std::ldexp(a, shift), b, t);
            check_divide(-a, std::ldexp(b, -shift), t);
        }
        CHECK(made == 20000);
    }
    SUBCASE("exact quotients and powers of two") {
        for (int i = 0; i < 20000; ++i) {
            const float q = random_float(rng, -20, 20);
            const float b = std::ldexp(1.0f, (i % 41) - 20);
            check_divide(q * b, b, t); // exact: the residual is 0
            const float c = static_cast<float>(i % 4093 + 1);
            check_divide(static_cast<float>(i % 8191 + 1), c, t);
        }
    }
    MESSAGE(t.checked << " divisions checked");
    CHECK(t.checked > 0);
    CHECK(t.wrong == 0);
}

TEST_CASE("refined square root rounds to nearest from starts up to 3 ulps off") {
    std::mt19937 rng(1128);
    Tally t;
    SUBCASE("random operands") {
        for (int i = 0; i < 60000; ++i) check_sqrt(std::abs(random_float(rng, -60, 60)), t);
    }
    SUBCASE("roots within a hair of a midpoint") {
        for (int i = 0; i < 60000; ++i) {
            const float s = std::abs(random_float(rng, -30, 30));
            const double m = (static_cast<double>(s) + static_cast<double>(std::nextafter(s, INFINITY))) / 2.0;
            check_sqrt(static_cast<float>(m * m), t);
            check_sqrt(std::nextafter(static_cast<float>(m * m), INFINITY), t);
            check_sqrt(std::nextafter(static_cast<float>(m * m), 0.0f), t);
        }
    }
    SUBCASE("roots within 2^-24 ulp of a midpoint") {
        int made = 0;
        for (int delta = -4095; delta <= 4097; delta += 8) { // every small delta = 1 mod 8
            float x[4];
            const int n = near_midpoint_squares(delta, x);
            for (int k = 0; k < n; ++k) {
                ++made;
                check_sqrt(x[k], t);
                check_sqrt(std::ldexp(x[k], 2 * (delta % 17)), t); // an even power of two keeps the root's digits
            }
        }
        CHECK(made > 500);
    }
    SUBCASE("squares, and the ends of a binade") {
        for (int i = 0; i < 20000; ++i) {
            const float s = std::abs(random_float(rng, -30, 30));
            const float x = s * s;
            check_sqrt(x, t);
            const float p = std::ldexp(1.0f, (i % 101) - 50);
            check_sqrt(p, t);
            check_sqrt(std::nextafter(p, 0.0f), t);
            check_sqrt(std::nextafter(p, INFINITY), t);
        }
    }
    MESSAGE(t.checked << " square roots checked");
    CHECK(t.checked > 0);
    CHECK(t.wrong == 0);
}

TEST_CASE("outside the refinable range the device's result is returned unchanged") {
    // Hand-picked: a residual there could underflow, so the refinement must not touch the start.
    CHECK(raycache_divide_refined(0x1p-100f, 3.0f, 0x1.555556p-102f, 0.33333334f) == 0x1.555556p-102f);
    CHECK(raycache_divide_refined(1.0f, 0x1p100f, 0x1.000002p-100f, 0x1p-100f) == 0x1.000002p-100f);
    CHECK(raycache_divide_refined(0.0f, 3.0f, 0.0f, 0.33333334f) == 0.0f);
    CHECK(raycache_sqrt_refined(0.0f, 0.0f, INFINITY) == 0.0f);
    CHECK(raycache_sqrt_refined(0x1p-100f, 0x1.000002p-50f, 0x1p49f) == 0x1.000002p-50f);
    // Inside it, a start 1 ulp off is mended: 1 / 3 and sqrt(2), rounded to nearest by hand (0x1.555556p-2
    // and 0x1.6a09e6p0 are the nearest floats).
    CHECK(raycache_divide_refined(1.0f, 3.0f, 0x1.555558p-2f, 0x1.555554p-2f) == 0x1.555556p-2f);
    CHECK(raycache_sqrt_refined(2.0f, 0x1.6a09e8p0f, 0x1.6a09e6p-2f) == 0x1.6a09e6p0f);
}
