// The GLSL side's correctly rounded division and square root (raycache/shared/rounding.h), run in C++ from
// starts a GPU might give (the right result moved by up to 3 ulps, and a reciprocal likewise off), against
// the CPU's IEEE division and square root, which round to nearest. Inputs (rounding_cases.hpp) include the
// hard cases: results within a hair of the midpoint between two floats.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <ios>
#include <random>
#include <vector>

#include <raycache/shared/rounding.h>

#include "rounding_cases.hpp"

using raycache::shared::raycache_divide_refined;
using raycache::shared::raycache_sqrt_refined;
using rounding_cases::moved;

namespace {

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

} // namespace

TEST_CASE("refined division rounds to nearest from starts up to 3 ulps off") {
    std::mt19937 rng(20261128);
    Tally t;
    std::vector<rounding_cases::Division> cases;
    SUBCASE("random operands") { cases = rounding_cases::random_divisions(rng, 60000); }
    SUBCASE("quotients within a hair of a midpoint") { cases = rounding_cases::near_midpoint_divisions(rng, 20000); }
    SUBCASE("exact quotients and small integers") { cases = rounding_cases::exact_divisions(rng, 20000); }
    for (const rounding_cases::Division& d : cases) check_divide(d.first, d.second, t);
    MESSAGE(t.checked << " divisions checked");
    CHECK(t.checked > 20 * 20000);
    CHECK(t.wrong == 0);
}

TEST_CASE("refined square root rounds to nearest from starts up to 3 ulps off") {
    std::mt19937 rng(1128);
    Tally t;
    std::vector<float> cases;
    SUBCASE("random operands") { cases = rounding_cases::random_roots(rng, 60000); }
    SUBCASE("roots within a hair of a midpoint") { cases = rounding_cases::near_midpoint_roots(rng, 20000); }
    SUBCASE("squares, and the ends of a binade") { cases = rounding_cases::exact_roots(rng, 20000); }
    for (float x : cases) check_sqrt(x, t);
    MESSAGE(t.checked << " square roots checked");
    CHECK(t.checked > 20 * 20000);
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
