// CacheCube<CctTexel>: the colour caching technique's cube (thesis ch. 3), its frame rule, counters,
// clear/invalidate, Algorithm 1 (cached_trace), and a user-defined texel type.
//
// Texels of the directions used here are worked out by hand from the face table
// (raycache/shared/cube_face.h, the OpenGL/Vulkan cube-map convention), in the thesis's form:
// +X: tu = (-z/|x| + 1)/2, tv = (-y/|x| + 1)/2; -X: tu = (z/|x| + 1)/2, tv = (-y/|x| + 1)/2;
// -Z: tu = (-x/|z| + 1)/2, tv = (-y/|z| + 1)/2; column = floor(tu * N), row = floor(tv * N).
// Colour words and decoded colours are worked out from the RGB9E5 definition (see test_texel_encoding.cpp).
#include <doctest/doctest.h>

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "raycache/raycache.hpp"

namespace {

using raycache::CacheCube;
using raycache::CctCube;
using raycache::CubeStatistics;
using raycache::TexelAddress;

// True when `text` contains `number` as a whole token (not part of a longer number, sign included).
bool mentions_number(const std::string& text, const std::string& number) {
    for (std::size_t at = text.find(number); at != std::string::npos; at = text.find(number, at + 1)) {
        const bool starts = at == 0 || (!std::isdigit(static_cast<unsigned char>(text[at - 1])) && text[at - 1] != '-');
        const std::size_t end = at + number.size();
        const bool ends = end == text.size() || !std::isdigit(static_cast<unsigned char>(text[end]));
        if (starts && ends) return true;
    }
    return false;
}

void check_colour(const std::optional<glm::vec3>& got, const glm::vec3& expected) {
    REQUIRE(got.has_value());
    CHECK(got->x == expected.x);
    CHECK(got->y == expected.y);
    CHECK(got->z == expected.z);
}

// Every texel of the cube that holds a value (via load(), so this frame's stores count).
std::vector<TexelAddress> filled_texels(const CctCube& cube) {
    std::vector<TexelAddress> filled;
    const int n = cube.face_size();
    for (int f = 0; f < 6; ++f)
        for (int r = 0; r < n; ++r)
            for (int c = 0; c < n; ++c)
                if (cube.load(TexelAddress{f, c, r})) filled.push_back(TexelAddress{f, c, r});
    return filled;
}

// N = 4, texel (+X, column 1, row 1): tu = (-0.3 + 1)/2 = 0.35 -> 1.4 -> 1; tv = (-0.2 + 1)/2 = 0.4 -> 1.6 -> 1.
const glm::vec3 dir_a(1.0f, 0.2f, 0.3f);
const TexelAddress texel_a{0, 1, 1};
// Same texel: tu = tv = 0.45 -> 1.8 -> 1.
const glm::vec3 dir_a_too(1.0f, 0.1f, 0.1f);
// Neighbours of texel_a on a 4 x 4 face.
const glm::vec3 dir_right(1.0f, 0.2f, -0.1f); // tu = 0.55 -> 2.2: (+X, 2, 1)
const glm::vec3 dir_up(1.0f, 0.6f, 0.3f);     // tv = 0.2 -> 0.8: (+X, 1, 0)
const glm::vec3 dir_back(-1.0f, 0.2f, 0.3f);  // -X: tu = 0.65 -> 2.6, tv = 0.4 -> 1.6: (-X, 2, 1)

// Exactly representable colours and their words (exponent e, step 2^(e - 24)).
const glm::vec3 red(1.0f, 0.0f, 0.0f);         // r 256 at exponent 16: 0x80000100
const glm::vec3 blue(0.0f, 0.0f, 1.0f);        // b 256 at exponent 16: 0x84000000
const glm::vec3 dim_red(0.25f, 0.0f, 0.0f);    // r 256 at exponent 14: 0x70000100
const glm::vec3 half_blue(0.0f, 0.0f, 0.5f);   // b 256 at exponent 15: 0x7C000000
const glm::vec3 colour_a(0.5f, 0.25f, 1.0f);   // 128, 64, 256 at exponent 16

// A user-defined texel: just a distance, 32 bits. Non-negative float bits order like the floats, so among
// same-frame stores the nearest distance wins.
struct DistanceTexel {
    using Word = std::uint32_t;
    using Value = float;
    static constexpr Word invalid = 0xFFFFFFFFu;
    static bool is_valid(Word word) noexcept { return word < 0x7F800000u; }
    static Word encode(const Value& distance) noexcept {
        if (!(distance >= 0.0f) || !(distance < std::numeric_limits<float>::infinity())) return invalid;
        const float positive = distance + 0.0f;
        Word word;
        std::memcpy(&word, &positive, sizeof word);
        return word;
    }
    static Value decode(Word word) noexcept {
        float distance;
        std::memcpy(&distance, &word, sizeof distance);
        return distance;
    }
};

} // namespace

TEST_CASE("a CCT cube has 6 N^2 texels of 4 bytes for every N from 1 to 4096") {
    auto check_size = [](int n) {
        CAPTURE(n);
        const std::size_t nn = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
        CctCube cube(n);
        CHECK(cube.face_size() == n);
        CHECK(cube.texel_count() == 6 * nn);
        CHECK(cube.texel_bytes() == 24 * nn);
        CHECK(cube.allocated_bytes() == 0u); // tiles come with their first store
        CHECK(cube.bytes() >= cube.allocated_bytes());
        const CubeStatistics s = cube.statistics();
        CHECK(s.texel_count == 6 * nn);
        CHECK(s.valid_texels == 0u);
        CHECK(cube.valid_fraction() == 0.0);
    };
    SUBCASE("N = 1") {
        check_size(1);
        CHECK(CctCube(1).texel_count() == 6u);
        CHECK(CctCube(1).texel_bytes() == 24u);
    }
    SUBCASE("N = 2") {
        check_size(2);
        CHECK(CctCube(2).texel_bytes() == 96u);
    }
    SUBCASE("N = 128") {
        check_size(128);
        CHECK(CctCube(128).texel_bytes() == 393216u);
    }
    SUBCASE("N = 4096") {
        CctCube cube(4096);
        CHECK(cube.texel_count() == 100663296u);
        CHECK(cube.texel_bytes() == 402653184u);
        // -Z, tu = tv = (0.9999 + 1)/2 = 0.99995 -> 4095.8: the last texel of the last face.
        CHECK(cube.store(glm::vec3(-0.9999f, -0.9999f, -1.0f), red));
        check_colour(cube.load(TexelAddress{5, 4095, 4095}), red);
        CHECK(cube.valid_texels() == 1u);
    }
}

TEST_CASE("a CCT cube starts with every texel empty") {
    CctCube cube(1);
    // With N = 1 each axis direction is the only texel of its face.
    const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int face = 0; face < 6; ++face) {
        CAPTURE(face);
        CHECK_FALSE(cube.lookup(axes[face]).has_value());
        CHECK_FALSE(cube.load(TexelAddress{face, 0, 0}).has_value());
    }
    CHECK(cube.statistics().misses == 6u);
    CHECK(cube.statistics().hits == 0u);
}

TEST_CASE("face sizes outside 1 to 4096 throw std::invalid_argument naming the size") {
    for (int n : {0, -1, 4097, -4096, 8192, std::numeric_limits<int>::min(), std::numeric_limits<int>::max()}) {
        CAPTURE(n);
        bool thrown = false;
        try {
            CctCube cube(n);
        } catch (const std::invalid_argument& e) {
            thrown = true;
            INFO("message: " << e.what());
            CHECK(mentions_number(e.what(), std::to_string(n)));
        }
        CHECK(thrown);
    }
    CHECK_THROWS_AS(CacheCube<raycache::CdctTexel>(0), std::invalid_argument);
}

TEST_CASE("a store becomes visible only after begin_frame") {
    CctCube cube(4);
    CHECK(cube.store(dir_a, colour_a));
    CHECK_FALSE(cube.lookup(dir_a).has_value());
    CHECK_FALSE(cube.peek(dir_a).has_value());
    CHECK_FALSE(cube.lookup(dir_a_too).has_value());
    cube.begin_frame();
    check_colour(cube.lookup(dir_a), colour_a);
    check_colour(cube.peek(dir_a), colour_a);
    SUBCASE("and stays visible in later frames") {
        cube.begin_frame();
        cube.begin_frame();
        check_colour(cube.lookup(dir_a), colour_a);
    }
}

TEST_CASE("load sees a value in the frame it was stored") {
    CctCube cube(4);
    CHECK_FALSE(cube.load(texel_a).has_value());
    CHECK(cube.store(dir_a, colour_a));
    check_colour(cube.load(texel_a), colour_a);
    CHECK_FALSE(cube.lookup(dir_a).has_value());
    cube.begin_frame();
    check_colour(cube.load(texel_a), colour_a);
}

TEST_CASE("a store into a visible texel is refused and the old value kept") {
    CctCube cube(4);
    CHECK(cube.store(dir_a, red));
    cube.begin_frame();
    // Blue's word (0x84000000) is larger than red's, dim red's (0x70000100) smaller: both refused.
    CHECK_FALSE(cube.store(dir_a, blue));
    CHECK_FALSE(cube.store(dir_a_too, dim_red));
    check_colour(cube.lookup(dir_a), red);
    check_colour(cube.load(texel_a), red);
    const CubeStatistics s = cube.begin_frame();
    CHECK(s.stores == 0u);
    CHECK(s.refused_stores == 2u);
    check_colour(cube.lookup(dir_a), red);
}

TEST_CASE("same-frame stores into one texel: the smaller packed word wins in any order") {
    // Words: dim red 0x70000100 < half blue 0x7C000000 < red 0x80000100 < blue 0x84000000.
    CctCube cube(4);
    SUBCASE("red then blue") {
        CHECK(cube.store(dir_a, red));
        CHECK_FALSE(cube.store(dir_a_too, blue));
        cube.begin_frame();
        check_colour(cube.lookup(dir_a), red);
    }
    SUBCASE("blue then red") {
        CHECK(cube.store(dir_a, blue));
        CHECK(cube.store(dir_a_too, red));
        cube.begin_frame();
        check_colour(cube.lookup(dir_a), red);
    }
    SUBCASE("a dimmer colour at a lower exponent beats a brighter one") {
        CHECK(cube.store(dir_a, half_blue));
        CHECK(cube.store(dir_a, dim_red));
        CHECK_FALSE(cube.store(dir_a, half_blue));
        cube.begin_frame();
        check_colour(cube.lookup(dir_a), dim_red);
    }
    SUBCASE("four colours, every rotation of the order") {
        const glm::vec3 colours[4] = {blue, red, half_blue, dim_red};
        for (int start = 0; start < 4; ++start) {
            CAPTURE(start);
            cube.clear();
            for (int i = 0; i < 4; ++i) cube.store(dir_a, colours[(start + i) % 4]);
            CHECK(cube.valid_texels() == 1u);
            cube.begin_frame();
            check_colour(cube.lookup(dir_a), dim_red);
        }
    }
    SUBCASE("an equal word is refused") {
        CHECK(cube.store(dir_a, red));
        CHECK_FALSE(cube.store(dir_a, red));
        CHECK(cube.statistics().stores == 1u);
        CHECK(cube.statistics().refused_stores == 1u);
    }
    CHECK(cube.valid_texels() == 1u);
}

TEST_CASE("any direction vector in the stored texel hits it") {
    CctCube cube(4);
    REQUIRE(cube.store(dir_a, colour_a));
    cube.begin_frame();
    check_colour(cube.lookup(dir_a * 7.5f), colour_a);
    check_colour(cube.lookup(dir_a * 0.001f), colour_a);
    check_colour(cube.lookup(dir_a * 1e6f), colour_a);
    check_colour(cube.lookup(dir_a_too), colour_a);
    CHECK(cube.statistics().hits == 4u);
}

TEST_CASE("a store leaves the neighbouring texels empty") {
    CctCube cube(4);
    REQUIRE(cube.store(dir_a, colour_a));
    const std::vector<TexelAddress> filled = filled_texels(cube);
    REQUIRE(filled.size() == 1u);
    CHECK(filled[0] == texel_a);
    cube.begin_frame();
    CHECK_FALSE(cube.lookup(dir_right).has_value());
    CHECK_FALSE(cube.lookup(dir_up).has_value());
    CHECK_FALSE(cube.lookup(dir_back).has_value());
    SUBCASE("and the neighbours can take their own values") {
        CHECK(cube.store(dir_right, red));
        CHECK(cube.store(dir_up, blue));
        CHECK(cube.store(dir_back, half_blue));
        CHECK(cube.load(TexelAddress{0, 2, 1}).has_value());
        CHECK(cube.load(TexelAddress{0, 1, 0}).has_value());
        CHECK(cube.load(TexelAddress{1, 2, 1}).has_value());
        cube.begin_frame();
        check_colour(cube.lookup(dir_a), colour_a);
        check_colour(cube.lookup(dir_right), red);
        check_colour(cube.lookup(dir_up), blue);
        check_colour(cube.lookup(dir_back), half_blue);
        CHECK(cube.valid_texels() == 4u);
    }
}

TEST_CASE("clear empties every texel and resets the counters") {
    CctCube cube(4);
    REQUIRE(cube.store(dir_a, colour_a));
    REQUIRE(cube.store(dir_back, red));
    cube.begin_frame();
    REQUIRE(cube.store(dir_up, blue)); // written this frame, not yet visible
    (void)cube.lookup(dir_a);
    (void)cube.lookup(dir_right);
    CHECK_FALSE(cube.store(dir_a, red));
    cube.clear();
    const CubeStatistics s = cube.statistics();
    CHECK(s.lookups == 0u);
    CHECK(s.hits == 0u);
    CHECK(s.misses == 0u);
    CHECK(s.stores == 0u);
    CHECK(s.refused_stores == 0u);
    CHECK(s.valid_texels == 0u);
    CHECK(cube.valid_fraction() == 0.0);
    CHECK(filled_texels(cube).empty());
    CHECK_FALSE(cube.lookup(dir_a).has_value());
    cube.begin_frame();
    CHECK_FALSE(cube.lookup(dir_a).has_value());
    CHECK_FALSE(cube.lookup(dir_up).has_value());
    SUBCASE("and the cube fills again under the frame rule") {
        CHECK(cube.store(dir_a, blue));
        CHECK_FALSE(cube.lookup(dir_a).has_value());
        cube.begin_frame();
        check_colour(cube.lookup(dir_a), blue);
    }
}

TEST_CASE("invalidate empties one texel and lets it be stored again") {
    CctCube cube(4);
    REQUIRE(cube.store(dir_a, colour_a));
    REQUIRE(cube.store(dir_right, red));
    cube.begin_frame();
    REQUIRE(cube.valid_texels() == 2u);
    cube.invalidate(texel_a);
    CHECK(cube.valid_texels() == 1u);
    CHECK_FALSE(cube.load(texel_a).has_value());
    CHECK_FALSE(cube.lookup(dir_a).has_value());
    check_colour(cube.lookup(dir_right), red);
    SUBCASE("invalidating an empty texel changes nothing") {
        cube.invalidate(texel_a);
        cube.invalidate(TexelAddress{5, 3, 3});
        CHECK(cube.valid_texels() == 1u);
    }
    SUBCASE("the emptied texel takes a new value from the next frame on") {
        CHECK(cube.store(dir_a, blue));
        CHECK(cube.valid_texels() == 2u);
        CHECK_FALSE(cube.lookup(dir_a).has_value());
        cube.begin_frame();
        check_colour(cube.lookup(dir_a), blue);
    }
}

TEST_CASE("statistics count lookups, hits, misses, stores and refused stores per frame") {
    CctCube cube(4);
    // Frame 1: three misses, two stores, one store refused (a larger word into a texel written this frame).
    CHECK_FALSE(cube.lookup(dir_a).has_value());
    CHECK_FALSE(cube.lookup(dir_right).has_value());
    CHECK_FALSE(cube.lookup(dir_a_too).has_value());
    CHECK(cube.store(dir_a, red));
    CHECK(cube.store(dir_right, red));
    CHECK_FALSE(cube.store(dir_a_too, blue));
    const CubeStatistics during = cube.statistics();
    CHECK(during.lookups == 3u);
    CHECK(during.misses == 3u);
    CHECK(during.valid_texels == 2u);

    const CubeStatistics frame1 = cube.begin_frame();
    CHECK(frame1.lookups == 3u);
    CHECK(frame1.hits == 0u);
    CHECK(frame1.misses == 3u);
    CHECK(frame1.stores == 2u);
    CHECK(frame1.refused_stores == 1u);
    CHECK(frame1.valid_texels == 2u);
    CHECK(frame1.texel_count == 96u);
    CHECK(frame1.hit_rate() == 0.0);

    // begin_frame reset the counters but kept the texels.
    const CubeStatistics reset = cube.statistics();
    CHECK(reset.lookups == 0u);
    CHECK(reset.hits == 0u);
    CHECK(reset.misses == 0u);
    CHECK(reset.stores == 0u);
    CHECK(reset.refused_stores == 0u);
    CHECK(reset.valid_texels == 2u);

    // Frame 2: two hits, one miss, one refused store into a visible texel, one new store.
    CHECK(cube.lookup(dir_a).has_value());
    CHECK(cube.lookup(dir_right).has_value());
    CHECK_FALSE(cube.lookup(dir_up).has_value());
    CHECK_FALSE(cube.store(dir_a, dim_red));
    CHECK(cube.store(dir_up, blue));
    (void)cube.peek(dir_a); // not counted
    const CubeStatistics frame2 = cube.begin_frame();
    CHECK(frame2.lookups == 3u);
    CHECK(frame2.hits == 2u);
    CHECK(frame2.misses == 1u);
    CHECK(frame2.stores == 1u);
    CHECK(frame2.refused_stores == 1u);
    CHECK(frame2.valid_texels == 3u);
    CHECK(frame2.hit_rate() == doctest::Approx(2.0 / 3.0));

    SUBCASE("record_lookup counts a hit or a miss without reading a texel") {
        cube.record_lookup(true);
        cube.record_lookup(false);
        cube.record_lookup(false);
        const CubeStatistics s = cube.statistics();
        CHECK(s.hits == 1u);
        CHECK(s.misses == 2u);
        CHECK(s.lookups == 3u);
    }
    SUBCASE("reset_statistics zeroes the counters only") {
        (void)cube.lookup(dir_a);
        cube.reset_statistics();
        CHECK(cube.statistics().lookups == 0u);
        CHECK(cube.valid_texels() == 3u);
    }
}

TEST_CASE("filling the four texels of +X on an N = 2 cube makes it 4/24 valid") {
    CctCube cube(2);
    // +X on N = 2: column 0 when z > 0 (tu = 0.25), 1 when z < 0; row 0 when y > 0, 1 when y < 0.
    const struct {
        glm::vec3 direction;
        TexelAddress texel;
        glm::vec3 colour;
    } quadrants[4] = {
        {{1.0f, 0.5f, 0.5f}, {0, 0, 0}, red},
        {{1.0f, 0.5f, -0.5f}, {0, 1, 0}, blue},
        {{1.0f, -0.5f, 0.5f}, {0, 0, 1}, dim_red},
        {{1.0f, -0.5f, -0.5f}, {0, 1, 1}, half_blue},
    };
    for (const auto& q : quadrants) CHECK(cube.store(q.direction, q.colour));
    CHECK(cube.valid_texels() == 4u);
    CHECK(cube.valid_fraction() == doctest::Approx(4.0 / 24.0));
    CHECK(cube.statistics().valid_fraction() == doctest::Approx(4.0 / 24.0));
    for (const auto& q : quadrants) check_colour(cube.load(q.texel), q.colour);
    CHECK(filled_texels(cube).size() == 4u);
    const CubeStatistics frame = cube.begin_frame();
    CHECK(frame.valid_fraction() == doctest::Approx(4.0 / 24.0));
    for (const auto& q : quadrants) check_colour(cube.lookup(q.direction), q.colour);
    // Storing again into a full face changes nothing.
    CHECK_FALSE(cube.store(glm::vec3(1.0f, 0.1f, 0.1f), blue));
    CHECK(cube.valid_fraction() == doctest::Approx(4.0 / 24.0));
}

TEST_CASE("cached_trace on a miss calls trace once and returns its exact, unquantized value") {
    CctCube cube(4);
    // (0.123456789, 0.987654321, 0.5): brightest 0.98765 -> exponent 15, step 2^-9:
    // 0.123456789 * 512 = 63.21 -> 63, 0.987654321 * 512 = 505.68 -> 506, 0.5 * 512 = 256.
    const glm::vec3 traced(0.123456789f, 0.987654321f, 0.5f);
    const glm::vec3 cached(63.0f / 512.0f, 506.0f / 512.0f, 0.5f);
    int calls = 0;
    auto trace = [&] {
        ++calls;
        return traced;
    };
    const glm::vec3 first = raycache::cached_trace(cube, dir_a, trace);
    CHECK(calls == 1);
    CHECK(glm::floatBitsToUint(first.x) == glm::floatBitsToUint(0.123456789f));
    CHECK(glm::floatBitsToUint(first.y) == glm::floatBitsToUint(0.987654321f));
    CHECK(glm::floatBitsToUint(first.z) == glm::floatBitsToUint(0.5f));
    CHECK(cube.statistics().misses == 1u);
    CHECK(cube.statistics().stores == 1u);

    SUBCASE("a second call in the same frame traces again") {
        const glm::vec3 again = raycache::cached_trace(cube, dir_a_too, trace);
        CHECK(calls == 2);
        CHECK(glm::floatBitsToUint(again.x) == glm::floatBitsToUint(0.123456789f));
        CHECK(cube.statistics().misses == 2u);
        CHECK(cube.statistics().refused_stores == 1u); // the same word again
    }
    SUBCASE("after begin_frame the stored colour answers without tracing") {
        cube.begin_frame();
        const glm::vec3 hit = raycache::cached_trace(cube, dir_a * 3.0f, trace);
        CHECK(calls == 1);
        CHECK(hit.x == cached.x);
        CHECK(hit.y == cached.y);
        CHECK(hit.z == cached.z);
        // And within the documented bound: 2^-9 of the brightest channel.
        const float bound = 0.987654321f * (1.0f / 512.0f);
        CHECK(std::fabs(hit.x - traced.x) <= bound);
        CHECK(std::fabs(hit.y - traced.y) <= bound);
        CHECK(std::fabs(hit.z - traced.z) <= bound);
        CHECK(cube.statistics().hits == 1u);
        CHECK(cube.statistics().misses == 0u);
    }
}

TEST_CASE("a user-defined 32-bit distance texel works with CacheCube") {
    CacheCube<DistanceTexel> cube(4);
    CHECK(cube.texel_bytes() == 6u * 16u * 4u);
    CHECK(cube.store(dir_a, 7.5f));
    CHECK(cube.store(dir_a_too, 2.25f)); // nearer: smaller word, wins
    CHECK_FALSE(cube.store(dir_a, 3.0f));
    CHECK_FALSE(cube.store(dir_right, -1.0f)); // encodes as invalid: refused
    CHECK_FALSE(cube.store(dir_right, std::numeric_limits<float>::infinity()));
    CHECK_FALSE(cube.lookup(dir_a).has_value());
    CHECK(cube.valid_texels() == 1u);
    const CubeStatistics frame = cube.begin_frame();
    CHECK(frame.stores == 2u);
    CHECK(frame.refused_stores == 3u);
    const std::optional<float> hit = cube.lookup(dir_a);
    REQUIRE(hit.has_value());
    CHECK(*hit == 2.25f);
    int calls = 0;
    CHECK(raycache::cached_trace(cube, dir_a, [&] { ++calls; return 1.0f; }) == 2.25f);
    CHECK(raycache::cached_trace(cube, dir_back, [&] { ++calls; return 4.0f; }) == 4.0f);
    CHECK(calls == 1);
    cube.begin_frame();
    const std::optional<float> back = cube.lookup(dir_back);
    REQUIRE(back.has_value());
    CHECK(*back == 4.0f);
}

TEST_CASE("filtered_cached_trace hits when the direction's own texel is visible, with the filled neighbours' weighted mean") {
    // +X on an N = 2 cube: the direction (1, -0.1, -0.1) has u = v = (0.1 + 1)/2 = 0.55, position 0.6 on
    // both axes from the centre of texel 0: columns and rows 0 and 1 weigh 0.4 and 0.6, and it lies in
    // texel (1, 1). Filled: (1, 1) red (weight 0.36) and (0, 1) blue (0.24): mean = (0.6, 0, 0.4).
    CctCube cube(2);
    cube.store_at(TexelAddress{0, 1, 1}, glm::vec3(1, 0, 0));
    cube.store_at(TexelAddress{0, 0, 1}, glm::vec3(0, 0, 1));
    cube.begin_frame();
    int traced = 0;
    auto trace = [&] {
        ++traced;
        return glm::vec3(0, 1, 0);
    };
    const glm::vec3 mean = raycache::filtered_cached_trace(cube, glm::vec3(1, -0.1f, -0.1f), trace);
    CHECK(traced == 0);
    CHECK(mean.x == doctest::Approx(0.6f));
    CHECK(mean.y == doctest::Approx(0.0f));
    CHECK(mean.z == doctest::Approx(0.4f));
    // (1, 0.1, 0.1) lies in the empty texel (0, 0), though filled texels weigh 0.4 of its footprint: a miss,
    // traced and stored into (0, 0), so the next frame hits.
    const glm::vec3 traced_colour = raycache::filtered_cached_trace(cube, glm::vec3(1, 0.1f, 0.1f), trace);
    CHECK(traced == 1);
    CHECK(traced_colour == glm::vec3(0, 1, 0));
    const CubeStatistics s = cube.statistics();
    CHECK(s.hits == 1u);
    CHECK(s.misses == 1u);
    CHECK(s.stores == 1u);
    CHECK(cube.load(TexelAddress{0, 0, 0}));
}
