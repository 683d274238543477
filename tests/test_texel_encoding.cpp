// Texel encodings: RGB9E5 colour words (CCT) and colour + distance words (CDCT), see
// raycache/shared/texel_encoding.h and raycache/texel.hpp.
//
// Every expected word below is worked out by hand from the RGB9E5 definition (EXT_texture_shared_exponent,
// VK_FORMAT_E5B9G9R9_UFLOAT_PACK32): red in bits 0-8, green 9-17, blue 18-26, shared exponent 27-31,
// bias 15, 9-bit mantissas, value = mantissa * 2^(exponent - 15 - 9). The shared exponent is
// max(-16, floor(log2(brightest))) + 16; each mantissa is floor(channel / 2^(exponent - 24) + 0.5); when the
// brightest mantissa comes out as 512 the exponent goes up by one and the mantissas are recomputed.
#include <doctest/doctest.h>

#include "test_random.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "raycache/raycache.hpp"

namespace {

using raycache::CctTexel;
using raycache::CdctTexel;
using raycache::DepthSample;
using raycache::shared::raycache_pack_rgb9e5;
using raycache::shared::raycache_unpack_rgb9e5;

constexpr float inf = std::numeric_limits<float>::infinity();
constexpr float nan_value = std::numeric_limits<float>::quiet_NaN();

// The RGB9E5 bit layout, written from the format definition (not from the library).
constexpr std::uint32_t rgb9e5(std::uint32_t r, std::uint32_t g, std::uint32_t b, std::uint32_t exponent) {
    return r | g << 9 | b << 18 | exponent << 27;
}

// The documented round-trip bound (texel_encoding.h, texel.hpp): at most max(r, g, b) * 2^-9 per channel,
// or 2^-25 absolute for colours under 2^-16, measured against the clamped colour.
double documented_bound(double brightest) {
    return std::max(brightest * std::ldexp(1.0, -9) * 1024.0 / 1023.0, std::ldexp(1.0, -25));
}

// The documented clamp: NaN and negatives -> 0, above 65280 (and +inf) -> 65280.
double clamped(float x) {
    if (std::isnan(x) || x < 0.0f) return 0.0;
    return std::min(static_cast<double>(x), 65280.0);
}

// Deterministic pseudo-random numbers (64-bit LCG), so a failure reproduces.
struct RoundTripSweep {
    std::uint64_t colours = 0;
    std::uint64_t violations = 0;
    glm::vec3 first_violation{0.0f};
    double first_error = 0.0;
    double first_bound = 0.0;

    void check(const glm::vec3& c) {
        ++colours;
        const glm::vec3 decoded = raycache_unpack_rgb9e5(raycache_pack_rgb9e5(c));
        const double expected[3] = {clamped(c.x), clamped(c.y), clamped(c.z)};
        const double bound = documented_bound(std::max(expected[0], std::max(expected[1], expected[2])));
        for (int i = 0; i < 3; ++i) {
            const double error = std::fabs(static_cast<double>(decoded[i]) - expected[i]);
            if (!(error <= bound)) {
                if (violations == 0) {
                    first_violation = c;
                    first_error = error;
                    first_bound = bound;
                }
                ++violations;
                break;
            }
        }
    }
};

} // namespace

TEST_CASE("RGB9E5 packs hand-computed colours into the format's words") {
    SUBCASE("black is the zero word") { CHECK(raycache_pack_rgb9e5(glm::vec3(0.0f)) == 0x00000000u); }
    SUBCASE("white: exponent 16, mantissas 256") {
        // floor(log2 1) = 0 -> exponent 16, step 2^-8, 1 / 2^-8 = 256.
        CHECK(rgb9e5(256, 256, 256, 16) == 0x84020100u);
        CHECK(raycache_pack_rgb9e5(glm::vec3(1.0f)) == 0x84020100u);
    }
    SUBCASE("grey 0.5: exponent 15, mantissas 256") {
        CHECK(raycache_pack_rgb9e5(glm::vec3(0.5f)) == 0x7C020100u);
    }
    SUBCASE("(1, 0.5, 0.25) shares exponent 16: mantissas 256, 128, 64") {
        CHECK(raycache_pack_rgb9e5(glm::vec3(1.0f, 0.5f, 0.25f)) == 0x81010100u);
    }
    SUBCASE("the brightest channel picks the exponent, whichever channel it is") {
        CHECK(raycache_pack_rgb9e5(glm::vec3(1.0f, 0.0f, 0.0f)) == rgb9e5(256, 0, 0, 16));
        CHECK(raycache_pack_rgb9e5(glm::vec3(0.0f, 1.0f, 0.0f)) == rgb9e5(0, 256, 0, 16));
        CHECK(raycache_pack_rgb9e5(glm::vec3(0.0f, 0.0f, 1.0f)) == rgb9e5(0, 0, 256, 16));
        // 3 -> floor(log2) = 1, exponent 17, step 2^-7: 3 * 128 = 384, 0.75 * 128 = 96, 0.1 * 128 = 12.8 -> 13.
        CHECK(raycache_pack_rgb9e5(glm::vec3(0.75f, 3.0f, 0.1f)) == rgb9e5(96, 384, 13, 17));
    }
    SUBCASE("mantissas round to nearest, halves up") {
        // Exponent 16, step 2^-8: 0.3 * 256 = 76.8 -> 77; 2.5/256 -> 2.5 + 0.5 = 3; 1.49/256 -> 1.
        CHECK(raycache_pack_rgb9e5(glm::vec3(1.0f, 0.3f, 2.5f / 256.0f)) == rgb9e5(256, 77, 3, 16));
        CHECK(raycache_pack_rgb9e5(glm::vec3(1.0f, 1.49f / 256.0f, 0.0f)) == rgb9e5(256, 1, 0, 16));
    }
}

TEST_CASE("a brightest channel that rounds up to mantissa 512 moves to the next exponent") {
    // x = 511.9/512 * 2^k: floor(log2 x) = k - 1, exponent k + 15, x / step = 511.9 -> 512, so the
    // exponent becomes k + 16 with mantissa 256 (x decodes to 2^k). k in [-15, 15] keeps the exponent in range.
    for (int k = -15; k <= 15; ++k) {
        CAPTURE(k);
        const float x = std::ldexp(511.9f / 512.0f, k);
        CHECK(raycache_pack_rgb9e5(glm::vec3(x, 0.0f, 0.0f)) == rgb9e5(256, 0, 0, static_cast<std::uint32_t>(k + 16)));
        // Exactly half way (511.5) rounds up too.
        const float half = std::ldexp(511.5f / 512.0f, k);
        CHECK(raycache_pack_rgb9e5(glm::vec3(0.0f, half, 0.0f)) == rgb9e5(0, 256, 0, static_cast<std::uint32_t>(k + 16)));
        // 511.4 stays at mantissa 511 of exponent k + 15.
        const float below = std::ldexp(511.4f / 512.0f, k);
        CHECK(raycache_pack_rgb9e5(glm::vec3(0.0f, 0.0f, below)) == rgb9e5(0, 0, 511, static_cast<std::uint32_t>(k + 15)));
    }
    SUBCASE("the other channels are rounded at the new exponent") {
        // 1023.8 -> exponent 25 (step 2), 511.9 -> 512: exponent 26, step 4; 3 / 4 + 0.5 -> 1; 1 / 4 + 0.5 -> 0.
        CHECK(raycache_pack_rgb9e5(glm::vec3(1023.8f, 3.0f, 1.0f)) == 0xD0000300u);
        CHECK(rgb9e5(256, 1, 0, 26) == 0xD0000300u);
    }
}

TEST_CASE("channels below 2^-16 share the smallest exponent, in steps of 2^-24") {
    // Exponent 0, step 2^-24: 2^-20 -> 16, 2^-22 -> 4, 3 * 2^-25 = 1.5 steps -> 2.
    CHECK(raycache_pack_rgb9e5(glm::vec3(std::ldexp(1.0f, -20), std::ldexp(1.0f, -22), std::ldexp(3.0f, -25))) ==
          0x00080810u);
    CHECK(raycache_pack_rgb9e5(glm::vec3(std::ldexp(1.0f, -16), 0.0f, 0.0f)) == 0x00000100u); // 256 steps
    CHECK(raycache_pack_rgb9e5(glm::vec3(std::ldexp(511.0f, -24), 0.0f, 0.0f)) == 0x000001FFu);
    CHECK(raycache_pack_rgb9e5(glm::vec3(std::ldexp(511.5f, -24), 0.0f, 0.0f)) == rgb9e5(256, 0, 0, 1));
    CHECK(raycache_pack_rgb9e5(glm::vec3(std::ldexp(1.0f, -25), 0.0f, 0.0f)) == 0x00000001u); // half a step, up
    CHECK(raycache_pack_rgb9e5(glm::vec3(std::ldexp(1.0f, -26), 0.0f, 0.0f)) == 0x00000000u); // a quarter, down
    CHECK(raycache_pack_rgb9e5(glm::vec3(1e-40f, 1e-45f, std::ldexp(1.0f, -30))) == 0x00000000u); // subnormals
}

TEST_CASE("colour channels clamp: above 65280 and +inf to 65280, negatives, -inf and NaN to 0") {
    // 65280 = 510 * 2^7: exponent 31, step 2^7, mantissa 510.
    SUBCASE("the maximum itself") { CHECK(raycache_pack_rgb9e5(glm::vec3(65280.0f, 0.0f, 0.0f)) == 0xF80001FEu); }
    SUBCASE("huge values") {
        CHECK(raycache_pack_rgb9e5(glm::vec3(65300.0f, 0.0f, 0.0f)) == 0xF80001FEu);
        CHECK(raycache_pack_rgb9e5(glm::vec3(65408.0f, 0.0f, 0.0f)) == 0xF80001FEu);
        CHECK(raycache_pack_rgb9e5(glm::vec3(1e6f)) == 0xFFFBFDFEu);
        CHECK(rgb9e5(510, 510, 510, 31) == 0xFFFBFDFEu);
        CHECK(raycache_pack_rgb9e5(glm::vec3(std::numeric_limits<float>::max())) == 0xFFFBFDFEu);
    }
    SUBCASE("+inf") {
        CHECK(raycache_pack_rgb9e5(glm::vec3(inf, 0.0f, 0.0f)) == 0xF80001FEu);
        CHECK(raycache_pack_rgb9e5(glm::vec3(inf)) == 0xFFFBFDFEu);
        // Next to the maximum, 1 is 1/128 of a step: mantissa 0.
        CHECK(raycache_pack_rgb9e5(glm::vec3(0.0f, inf, 1.0f)) == rgb9e5(0, 510, 0, 31));
    }
    SUBCASE("negatives") {
        CHECK(raycache_pack_rgb9e5(glm::vec3(-1.0f, 0.5f, -3.0f)) == 0x78020000u);
        CHECK(raycache_pack_rgb9e5(glm::vec3(-1e30f, -std::ldexp(1.0f, -30), -0.0f)) == 0u);
        CHECK(raycache_pack_rgb9e5(glm::vec3(-0.0f, 1.0f, -0.0f)) == rgb9e5(0, 256, 0, 16));
    }
    SUBCASE("-inf") { CHECK(raycache_pack_rgb9e5(glm::vec3(-inf)) == 0u); }
    SUBCASE("NaN") {
        CHECK(raycache_pack_rgb9e5(glm::vec3(nan_value, 1.0f, 0.0f)) == 0x80020000u);
        CHECK(raycache_pack_rgb9e5(glm::vec3(nan_value)) == 0u);
        CHECK(raycache_pack_rgb9e5(glm::vec3(-nan_value, glm::uintBitsToFloat(0x7FC12345u), glm::uintBitsToFloat(0xFFFFFFFFu))) == 0u);
    }
}

TEST_CASE("RGB9E5 words unpack to mantissa * 2^(exponent - 24)") {
    auto unpacks_to = [](std::uint32_t word, glm::vec3 expected) {
        CAPTURE(word);
        const glm::vec3 v = raycache_unpack_rgb9e5(word);
        CHECK(v.x == expected.x);
        CHECK(v.y == expected.y);
        CHECK(v.z == expected.z);
    };
    unpacks_to(0x00000000u, glm::vec3(0.0f));
    unpacks_to(0x84020100u, glm::vec3(1.0f));
    unpacks_to(0x7C020100u, glm::vec3(0.5f));
    unpacks_to(0x81010100u, glm::vec3(1.0f, 0.5f, 0.25f));
    unpacks_to(0xA00C0401u, glm::vec3(0.0625f, 0.125f, 0.1875f)); // mantissas 1, 2, 3 at exponent 20: step 2^-4
    unpacks_to(0xF80001FEu, glm::vec3(65280.0f, 0.0f, 0.0f));
    unpacks_to(0x00080810u, glm::vec3(std::ldexp(1.0f, -20), std::ldexp(1.0f, -22), std::ldexp(1.0f, -23)));
    unpacks_to(0x00000001u, glm::vec3(std::ldexp(1.0f, -24), 0.0f, 0.0f));
    unpacks_to(0x07FC0000u, glm::vec3(0.0f, 0.0f, std::ldexp(511.0f, -24))); // blue 511 at exponent 0
    unpacks_to(0xFFFFFFFFu, glm::vec3(65408.0f));                               // 511 * 2^7 (the CCT's invalid word)
}

TEST_CASE("RGB9E5 round trips stay within the documented bound over a dense sweep") {
    RoundTripSweep sweep;
    SUBCASE("one channel, every 509th float from 0 to +inf, in each position") {
        for (std::uint32_t u = 0; u <= 0x7F800000u; u += 509u) {
            const float x = glm::uintBitsToFloat(u);
            sweep.check(glm::vec3(x, 0.0f, 0.0f));
            sweep.check(glm::vec3(0.0f, x, 0.0f));
            sweep.check(glm::vec3(0.0f, 0.0f, x));
        }
    }
    SUBCASE("grey levels, every 997th float up to 2^17") {
        for (std::uint32_t u = 0; u <= glm::floatBitsToUint(131072.0f); u += 997u) sweep.check(glm::vec3(glm::uintBitsToFloat(u)));
    }
    SUBCASE("mantissas 256 to 512 in 1/16 steps across binades, with dimmer channels") {
        for (int k = -20; k <= 16; k += 3) {
            for (int i = 0; i < 4096; ++i) {
                const float brightest = std::ldexp(256.0f + static_cast<float>(i) / 16.0f, k - 8);
                for (int j = 0; j < 37; ++j) {
                    const float dim = brightest * static_cast<float>(j) / 37.0f;
                    sweep.check(glm::vec3(brightest, dim, brightest / 3.0f));
                }
            }
        }
    }
    SUBCASE("random colours over 40 binades") {
        Lcg rng{12345};
        for (int n = 0; n < 400000; ++n) {
            const float scale = std::ldexp(1.0f, static_cast<int>(rng.next() % 40u) - 25);
            sweep.check(glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * scale);
        }
    }
    INFO("colours checked: " << sweep.colours << ", first violation at (" << sweep.first_violation.x << ", "
                             << sweep.first_violation.y << ", " << sweep.first_violation.z << "): error "
                             << sweep.first_error << " > bound " << sweep.first_bound);
    CHECK(sweep.colours > 0u);
    CHECK(sweep.violations == 0u);
}

TEST_CASE("the round-trip error stays within 2^-9 * 1024/1023 of the brightest channel when the shared exponent rounds up") {
    // (1023/1024, 2^-9, 0): brightest / 2^-9 = 511.5 -> 512, so the exponent goes from 15 to 16 (step 2^-8).
    // Green, 2^-9 = half of the new step, rounds up to mantissa 1 = 2^-8: error 2^-9.
    // Whenever the exponent rounds up the worst case is half the new step, 1024/1023 times
    // max(r, g, b) * 2^-9: this colour reaches that worst case exactly, the documented bound.
    const glm::vec3 colour(1023.0f / 1024.0f, std::ldexp(1.0f, -9), 0.0f);
    const std::uint32_t word = raycache_pack_rgb9e5(colour);
    CHECK(word == rgb9e5(256, 1, 0, 16));
    const glm::vec3 decoded = raycache_unpack_rgb9e5(word);
    const double error = std::fabs(static_cast<double>(decoded.y) - static_cast<double>(colour.y));
    CHECK(error == std::ldexp(1.0, -9));
    CHECK(error <= std::ldexp(static_cast<double>(decoded.x), -9));
    CHECK(error <= documented_bound(colour.x));
    CHECK(error > std::ldexp(static_cast<double>(colour.x), -9)); // the plain 2^-9 bound would be broken
}

TEST_CASE("the encoder never produces the CCT invalid word 0xFFFFFFFF") {
    CHECK(CctTexel::invalid == 0xFFFFFFFFu);
    CHECK_FALSE(CctTexel::is_valid(0xFFFFFFFFu));
    CHECK(CctTexel::is_valid(0u));
    std::uint64_t invalid_words = 0;
    std::uint64_t checked = 0;
    auto check = [&](const glm::vec3& c) {
        ++checked;
        const std::uint32_t w = CctTexel::encode(c);
        if (w == 0xFFFFFFFFu || !CctTexel::is_valid(w)) ++invalid_words;
    };
    // Every 257th float bit pattern, positive and negative, NaNs and infinities included, in all channels at once
    // and alone.
    for (std::uint64_t u = 0; u <= 0xFFFFFFFFull; u += 257u) {
        const float x = glm::uintBitsToFloat(static_cast<std::uint32_t>(u));
        check(glm::vec3(x));
        check(glm::vec3(x, 0.0f, 0.0f));
    }
    const float specials[] = {inf, -inf, nan_value, 65280.0f, 65281.0f, 65408.0f, 65407.9f, 65535.0f,
                              65536.0f, 1e30f, std::numeric_limits<float>::max(), 0.0f, -0.0f, 1.0f};
    for (float a : specials)
        for (float b : specials)
            for (float c : specials) check(glm::vec3(a, b, c));
    INFO("checked " << checked << " colours");
    CHECK(invalid_words == 0u);
}

TEST_CASE("a CDCT word holds the colour in its low 32 bits and the distance's float bits in the high 32") {
    CHECK(glm::floatBitsToUint(3.75f) == 0x40700000u); // 1.875 * 2^1: exponent 128, fraction 0.875
    const DepthSample sample{glm::vec3(1.0f, 0.5f, 0.25f), 3.75f};
    CHECK(CdctTexel::encode(sample) == 0x4070000081010100ull);
    const raycache::shared::uvec2 pair = raycache::shared::raycache_cdct_pack(sample.color, sample.distance);
    CHECK(pair.x == 0x81010100u);
    CHECK(pair.y == 0x40700000u);
    SUBCASE("the invalid word is colour 0 at distance -1.0") {
        CHECK(CdctTexel::invalid == 0xBF80000000000000ull);
        CHECK_FALSE(CdctTexel::is_valid(CdctTexel::invalid));
    }
    SUBCASE("decoding a hand-built word") {
        const DepthSample d = CdctTexel::decode(0x42C80000ull << 32 | 0x7C020100ull); // 100.0f, grey 0.5
        CHECK(d.distance == 100.0f);
        CHECK(d.color.x == 0.5f);
        CHECK(d.color.y == 0.5f);
        CHECK(d.color.z == 0.5f);
    }
}

TEST_CASE("a CDCT sample round-trips: distance exactly, colour within the RGB9E5 bound") {
    const float distances[] = {0.0f, 1e-45f, std::numeric_limits<float>::min(), 1e-3f, 0.123456789f, 3.75f,
                               100.0f, 12345.678f, std::numeric_limits<float>::max()};
    const glm::vec3 colours[] = {glm::vec3(0.0f), glm::vec3(1.0f, 0.5f, 0.25f), glm::vec3(0.123456789f, 0.9f, 0.3f),
                                 glm::vec3(70000.0f, 2.0f, 1e-9f)};
    for (float distance : distances) {
        for (const glm::vec3& colour : colours) {
            CAPTURE(distance);
            const std::uint64_t word = CdctTexel::encode(DepthSample{colour, distance});
            REQUIRE(CdctTexel::is_valid(word));
            CHECK((word >> 32) == glm::floatBitsToUint(distance));
            const DepthSample back = CdctTexel::decode(word);
            CHECK(glm::floatBitsToUint(back.distance) == glm::floatBitsToUint(distance));
            const double expected[3] = {clamped(colour.x), clamped(colour.y), clamped(colour.z)};
            const double bound = documented_bound(std::max(expected[0], std::max(expected[1], expected[2])));
            for (int i = 0; i < 3; ++i) CHECK(std::fabs(back.color[i] - expected[i]) <= bound);
        }
    }
    SUBCASE("an exactly representable colour comes back exactly") {
        const DepthSample back = CdctTexel::decode(CdctTexel::encode(DepthSample{glm::vec3(1.0f, 0.5f, 0.25f), 2.0f}));
        CHECK(back.color.x == 1.0f);
        CHECK(back.color.y == 0.5f);
        CHECK(back.color.z == 0.25f);
        CHECK(back.distance == 2.0f);
    }
}

TEST_CASE("negative, NaN and infinite CDCT distances encode as the invalid word") {
    const float bad[] = {-1.0f, -1e-30f, -1e-45f, -std::numeric_limits<float>::max(), -inf, inf, nan_value,
                         -nan_value, glm::uintBitsToFloat(0x7F800001u)};
    for (float distance : bad) {
        CAPTURE(glm::floatBitsToUint(distance));
        const std::uint64_t word = CdctTexel::encode(DepthSample{glm::vec3(1.0f), distance});
        CHECK(word == 0xBF80000000000000ull);
        CHECK_FALSE(CdctTexel::is_valid(word));
    }
}

TEST_CASE("a CDCT distance of -0.0 encodes as a valid distance +0") {
    const std::uint64_t word = CdctTexel::encode(DepthSample{glm::vec3(1.0f, 0.5f, 0.25f), -0.0f});
    CHECK(CdctTexel::is_valid(word));
    CHECK(word == 0x0000000081010100ull);
    const DepthSample back = CdctTexel::decode(word);
    CHECK(back.distance == 0.0f);
    CHECK_FALSE(std::signbit(back.distance));
}

TEST_CASE("CDCT words order like their distances, whatever the colours") {
    // Smaller word wins same-frame ties, so the nearer surface must have the smaller word even when its
    // colour word is larger.
    std::vector<float> distances = {0.0f, 1e-45f, 2e-45f, std::numeric_limits<float>::min(), 1e-20f, 1e-3f, 0.5f,
                                    0.99999994f, 1.0f, 1.0000001f, 2.0f, 99.99999f, 100.0f, 1e20f,
                                    std::numeric_limits<float>::max()};
    Lcg rng{99};
    for (int n = 0; n < 2000; ++n) distances.push_back(std::ldexp(rng.uniform(), static_cast<int>(rng.next() % 60u) - 30));
    const glm::vec3 bright(65280.0f), dark(0.0f);
    std::uint64_t wrong_order = 0;
    for (float a : distances) {
        for (float b : distances) {
            if (!(a < b)) continue;
            const std::uint64_t near_bright = CdctTexel::encode(DepthSample{bright, a});
            const std::uint64_t far_dark = CdctTexel::encode(DepthSample{dark, b});
            if (!(near_bright < far_dark)) ++wrong_order;
        }
    }
    CHECK(wrong_order == 0u);
    // Same distance: the colour word decides (dark, the smaller word, first).
    CHECK(CdctTexel::encode(DepthSample{dark, 5.0f}) < CdctTexel::encode(DepthSample{bright, 5.0f}));
}

TEST_CASE("a channel just under half a mantissa step rounds down, one at half a step rounds up") {
    // Below 2^-16 the step is 2^-24. 2^-25 - 2^-49 (the float just under half a step) must give mantissa 0;
    // floor(x / step + 0.5) in float gave 1 (found by the texel_encoding fuzz target). 2^-25 itself gives 1.
    const float under_half = std::nextafter(std::ldexp(1.0f, -25), 0.0f);
    CHECK(under_half == std::ldexp(1.0f, -25) - std::ldexp(1.0f, -49));
    CHECK(raycache::CctTexel::encode(glm::vec3(0.0f, 0.0f, under_half)) == 0x00000000u);
    CHECK(raycache::CctTexel::encode(glm::vec3(0.0f, 0.0f, std::ldexp(1.0f, -25))) == 0x00040000u);
    // At exponent 0 (channels in [2^-16, 2^-15)) the step is 2^-24 too: 2^-16 + 1.5 steps is 0x1.0001800p-16.
    const float one_and_half = std::ldexp(1.0f, -16) + 1.5f * std::ldexp(1.0f, -24);
    const float just_under = std::nextafter(one_and_half, 0.0f);
    const std::uint32_t at = raycache::CctTexel::encode(glm::vec3(one_and_half, 0.0f, 0.0f));
    const std::uint32_t under = raycache::CctTexel::encode(glm::vec3(just_under, 0.0f, 0.0f));
    CHECK((at & 0x1FFu) == 258u);    // 256 + 1.5 rounds up to 258
    CHECK((under & 0x1FFu) == 257u); // just under rounds down to 257
}

namespace {
// RGB9E5 as the format defines it, in double precision, where channel * 2^k and + 0.5 are exact for every
// float channel, so floor(... + 0.5) is exactly half-up rounding: the reference the encoder must equal word
// for word (it rounds from the float's bits instead).
std::uint32_t reference_rgb9e5(const glm::vec3& colour) {
    double c[3];
    for (int i = 0; i < 3; ++i) c[i] = clamped(colour[i]);
    const double brightest = std::max(c[0], std::max(c[1], c[2]));
    int floor_log2 = -16;
    if (brightest >= std::ldexp(1.0, -16)) {
        int e = 0;
        std::frexp(brightest, &e); // brightest = f * 2^e, f in [0.5, 1)
        floor_log2 = e - 1;
    }
    int shared = floor_log2 + 16;
    auto mantissa = [&](double x) { return static_cast<std::uint32_t>(std::floor(std::ldexp(x, 24 - shared) + 0.5)); };
    if (mantissa(brightest) == 512u) ++shared;
    return rgb9e5(mantissa(c[0]), mantissa(c[1]), mantissa(c[2]), static_cast<std::uint32_t>(shared));
}
} // namespace

TEST_CASE("RGB9E5 words equal the format's definition computed in double precision, over every exponent and rounding edge") {
    std::uint64_t checked = 0, differ = 0;
    glm::vec3 first{0.0f};
    auto check = [&](const glm::vec3& c) {
        ++checked;
        if (raycache_pack_rgb9e5(c) != reference_rgb9e5(c)) {
            if (differ == 0) first = c;
            ++differ;
        }
    };
    // Every 509th float bit pattern as a grey and as one channel beside others (NaN, inf, negatives,
    // subnormals and -0 included): 25 million colours through every exponent.
    for (std::uint64_t bits = 0; bits <= 0xFFFFFFFFull; bits += 509) {
        float x;
        const std::uint32_t b = static_cast<std::uint32_t>(bits);
        std::memcpy(&x, &b, 4);
        check(glm::vec3(x));
        check(glm::vec3(x, 1.0f, 0.0f));
        check(glm::vec3(0.25f, 0.0f, x));
    }
    // Channels exactly at, and one float either side of, half a mantissa step at every shared exponent.
    for (int shared = 0; shared <= 31; ++shared)
        for (int m = 0; m <= 512; ++m) {
            const float half = static_cast<float>(std::ldexp(m + 0.5, shared - 24));
            const float top = static_cast<float>(std::ldexp(256.0, shared - 24)); // a brightest channel of that exponent
            for (float x : {half, std::nextafter(half, 0.0f), std::nextafter(half, inf)}) {
                check(glm::vec3(x, 0.0f, 0.0f));
                check(glm::vec3(top, x, x));
            }
        }
    Lcg rng{2026};
    for (int i = 0; i < 1000000; ++i) {
        const float scale = std::ldexp(1.0f, static_cast<int>(rng.next() % 48) - 30);
        check(glm::vec3(rng.uniform() * scale, rng.uniform() * scale, rng.uniform() * scale));
    }
    CAPTURE(first.x);
    CAPTURE(first.y);
    CAPTURE(first.z);
    CHECK(checked > 25000000u);
    CHECK(differ == 0u);
}
