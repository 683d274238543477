// Face selection, texture coordinates and the inverse mapping, against values worked out by hand from the
// cube-map table (SPEC section 1) and against an independent double-precision model of the sampler's
// single-precision arithmetic.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <raycache/cube_face.hpp>

using raycache::TexelAddress;
using raycache::texel_direction;
using raycache::texel_of;

namespace {

struct Case {
    glm::vec3 direction;
    int face_size;
    TexelAddress expected;
};

void check(const Case& c) {
    CAPTURE(c.direction.x);
    CAPTURE(c.direction.y);
    CAPTURE(c.direction.z);
    CAPTURE(c.face_size);
    const auto got = texel_of(c.direction, c.face_size);
    REQUIRE(got.has_value());
    CHECK(got->face == c.expected.face);
    CHECK(got->column == c.expected.column);
    CHECK(got->row == c.expected.row);
}

// One IEEE float rounding of an exact double result. The volatile keeps the compiler from narrowing the
// double arithmetic back to float and then fusing it (GCC does both under -ffp-contract=fast).
float rounded(double exact) {
    volatile float f = static_cast<float>(exact);
    return f;
}

// The sampler's arithmetic for one texel index, t = sc * (0.5 / m) + 0.5, index = floor(t * N): each
// single-precision operation done exactly in double and rounded once to float, which gives the IEEE
// float result (double rounding is innocuous for + - * / because 53 >= 2 * 24 + 2).
int driver_order_index(float sc, float m, int n) {
    const float scale = rounded(0.5 / static_cast<double>(m));
    const float scaled = rounded(static_cast<double>(sc) * scale);
    const float t = rounded(static_cast<double>(scaled) + 0.5);
    const float texels = rounded(static_cast<double>(t) * n);
    return std::min(std::max(static_cast<int>(std::floor(texels)), 0), n - 1);
}

// The thesis's order, t = (sc / m + 1) / 2, likewise in exact float steps.
int thesis_order_index(float sc, float m, int n) {
    const float ratio = rounded(static_cast<double>(sc) / m);
    const float t = rounded((static_cast<double>(ratio) + 1.0) / 2.0);
    const float texels = rounded(static_cast<double>(t) * n);
    return std::min(std::max(static_cast<int>(std::floor(texels)), 0), n - 1);
}

} // namespace

TEST_CASE("each face maps a direction to the texel given by its row of the table") {
    // Major component +-2, so 0.5/|m| = 0.25 and t = sc/4 + 0.5; N = 8. Worked by hand:
    const Case cases[] = {
        // +X: sc = -z = 1.5, tc = -y = -0.5 -> t = (0.875, 0.375) -> (7, 3)
        {{2.0f, 0.5f, -1.5f}, 8, {0, 7, 3}},
        // -X: sc = +z = -1.5, tc = -y = -0.5 -> (0.125, 0.375) -> (1, 3)
        {{-2.0f, 0.5f, -1.5f}, 8, {1, 1, 3}},
        // +Y: sc = +x = 0.5, tc = +z = -1.5 -> (0.625, 0.125) -> (5, 1)
        {{0.5f, 2.0f, -1.5f}, 8, {2, 5, 1}},
        // -Y: sc = +x = 0.5, tc = -z = 1.5 -> (0.625, 0.875) -> (5, 7)
        {{0.5f, -2.0f, -1.5f}, 8, {3, 5, 7}},
        // +Z: sc = +x = 0.5, tc = -y = 1.5 -> (0.625, 0.875) -> (5, 7)
        {{0.5f, -1.5f, 2.0f}, 8, {4, 5, 7}},
        // -Z: sc = -x = -0.5, tc = -y = 1.5 -> (0.375, 0.875) -> (3, 7)
        {{0.5f, -1.5f, -2.0f}, 8, {5, 3, 7}},
        // The face centres: sc = tc = 0 -> t = 0.5 -> N/2 on an even face.
        {{1.0f, 0.0f, 0.0f}, 4, {0, 2, 2}},
        {{-3.0f, 0.0f, 0.0f}, 4, {1, 2, 2}},
        {{0.0f, 0.25f, 0.0f}, 4, {2, 2, 2}},
        {{0.0f, -1.0f, 0.0f}, 4, {3, 2, 2}},
        {{0.0f, 0.0f, 9.0f}, 4, {4, 2, 2}},
        {{0.0f, 0.0f, -1.0f}, 4, {5, 2, 2}},
        // The corners of the face: t = 0 -> index 0, t = 1 -> clamped to N - 1.
        {{1.0f, 1.0f - 1.0f / 64, -(1.0f - 1.0f / 64)}, 16, {0, 15, 0}}, // sc = .984, tc = -.984
        {{1.0f, -(1.0f - 1.0f / 64), 1.0f - 1.0f / 64}, 16, {0, 0, 15}},
        // N = 1: every direction lands on texel (face, 0, 0).
        {{0.3f, -0.2f, 0.1f}, 1, {0, 0, 0}},
        {{0.1f, -0.2f, -0.3f}, 1, {5, 0, 0}},
    };
    for (const Case& c : cases) check(c);
}

TEST_CASE("ties between equal magnitudes go z over y over x, signed by the major component") {
    const Case cases[] = {
        // |x| = |y| = |z|: Z wins. (1,1,1): sc = x = 1 -> t = 1 -> clamped to 3; tc = -y = -1 -> row 0.
        {{1.0f, 1.0f, 1.0f}, 4, {4, 3, 0}},
        {{1.0f, 1.0f, -1.0f}, 4, {5, 0, 0}},   // -Z: sc = -x = -1 -> 0, tc = -y = -1 -> 0
        {{-1.0f, -1.0f, -1.0f}, 4, {5, 3, 3}}, // -Z: sc = 1 -> 3, tc = 1 -> 3
        // |y| = |z| > |x|: Z wins.
        {{0.5f, 1.0f, 1.0f}, 4, {4, 3, 0}}, // sc = 0.5 -> t = .75 -> 3; tc = -1 -> 0
        {{0.5f, -1.0f, -1.0f}, 4, {5, 1, 3}}, // sc = -0.5 -> .25 -> 1; tc = 1 -> 3
        // |x| = |z| > |y|: Z wins.
        {{1.0f, 0.5f, 1.0f}, 4, {4, 3, 1}},  // sc = 1 -> 3; tc = -.5 -> .25 -> 1
        {{-1.0f, 0.5f, -1.0f}, 4, {5, 3, 1}}, // sc = 1 -> 3; tc = -.5 -> 1
        // |x| = |y| > |z|: Y wins.
        {{1.0f, 1.0f, 0.5f}, 4, {2, 3, 3}},   // +Y: sc = x = 1 -> 3; tc = z = .5 -> .75 -> 3
        {{1.0f, -1.0f, 0.5f}, 4, {3, 3, 1}},  // -Y: sc = 1 -> 3; tc = -z = -.5 -> 1
        {{-1.0f, 1.0f, 0.0f}, 4, {2, 0, 2}},  // +Y: sc = -1 -> 0; tc = 0 -> 2
    };
    for (const Case& c : cases) check(c);
}

TEST_CASE("signed zeros in the minor components do not move the texel, and zero vectors miss") {
    const float pz = 0.0f, nz = -0.0f;
    // On +X, sc = -z and tc = -y are +-0, so t = 0.5 either way -> (N/2, N/2).
    for (const glm::vec3 d : {glm::vec3(1, pz, nz), glm::vec3(1, nz, pz), glm::vec3(1, nz, nz), glm::vec3(1, pz, pz)})
        check({d, 8, {0, 4, 4}});
    check({glm::vec3(nz, pz, -1.0f), 8, {5, 4, 4}});
    CHECK_FALSE(texel_of(glm::vec3(pz, pz, pz), 8).has_value());
    CHECK_FALSE(texel_of(glm::vec3(nz, nz, nz), 8).has_value());
    CHECK_FALSE(texel_of(glm::vec3(nz, pz, nz), 8).has_value());
    // The shared function itself reports the zero vector as no face, and its sign-bit test sees -0.
    CHECK(raycache::shared::raycache_face_of(glm::vec3(nz, nz, nz)) == RAYCACHE_NO_FACE);
    CHECK(raycache::shared::raycache_sign_bit(nz));
    CHECK_FALSE(raycache::shared::raycache_sign_bit(pz));
}

TEST_CASE("a direction exactly on a texel edge belongs to the texel on its high side") {
    // +X with m = 1: t_u = -z/2 + 0.5. z = 0.25 gives t = 0.375 = 3/8 exactly: column 3 of 8.
    check({{1.0f, 0.0f, 0.25f}, 8, {0, 3, 4}});
    // Two float steps further from the edge (2^-24) the texel below is chosen: t = 0.375 - 2^-25.
    check({{1.0f, 0.0f, 0.25f + 0x1p-24f}, 8, {0, 2, 4}});
    // One float step (2^-25) is a rounding tie in t = sc * 0.5 + 0.5, resolved to even: back on the edge.
    check({{1.0f, 0.0f, 0.25f + 0x1p-25f}, 8, {0, 3, 4}});
    // Rows likewise: tc = -y; y = -0.25 gives t_v = 0.625 = 5/8: row 5. Near 0.625 a float step is 2^-24,
    // so tc = 0.25 - 2^-24 gives t = 0.625 - 2^-25, a tie rounded back to the edge; 2^-23 moves a texel.
    check({{1.0f, -0.25f, 0.0f}, 8, {0, 4, 5}});
    check({{1.0f, -0.25f + 0x1p-24f, 0.0f}, 8, {0, 4, 5}});
    check({{1.0f, -0.25f + 0x1p-23f, 0.0f}, 8, {0, 4, 4}});
}

TEST_CASE("texel indices follow the driver's rounding order, also where the thesis's order differs") {
    std::mt19937 rng(12345);
    std::uniform_real_distribution<float> minor(-1.0f, 1.0f);
    std::uniform_real_distribution<float> major(0.5f, 4.0f);
    const int n = 4096;
    int disagreements_with_thesis = 0;
    for (int i = 0; i < 200000; ++i) {
        // Direction on +Z (sc = x, tc = -y, m = z), drawn anywhere, and snapped near a texel edge half the time.
        float m = major(rng);
        float x = minor(rng) * m;
        float y = minor(rng) * m * 0.999f;
        if (i % 2) {
            const float edge = std::round((x / m * 0.5f + 0.5f) * n) / n; // a texel edge in t
            x = (edge - 0.5f) * 2.0f * m;
            x = std::nextafter(x, (i % 4 == 1) ? 10.0f : -10.0f);
        }
        if (std::abs(x) >= m || std::abs(y) >= m) continue;
        const auto got = texel_of(glm::vec3(x, y, m), n);
        REQUIRE(got.has_value());
        REQUIRE(got->face == 4);
        const int expected_column = driver_order_index(x, m, n);
        const int expected_row = driver_order_index(-y, m, n);
        if (got->column != expected_column || got->row != expected_row) {
            CAPTURE(x);
            CAPTURE(y);
            CAPTURE(m);
            CHECK(got->column == expected_column);
            CHECK(got->row == expected_row);
        }
        if (thesis_order_index(x, m, n) != expected_column) ++disagreements_with_thesis;
    }
    // The two orders really differ somewhere in this sample, so the check above can tell them apart.
    CHECK(disagreements_with_thesis > 0);
}

TEST_CASE("the direction through a texel's centre maps back to that texel, for every texel") {
    for (int n : {1, 2, 3, 16, 512}) {
        CAPTURE(n);
        long mismatches = 0;
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column) {
                    const TexelAddress t{face, column, row};
                    const glm::vec3 d = texel_direction(t, n);
                    const auto back = texel_of(d, n);
                    if (!back || *back != t) ++mismatches;
                    // The unnormalised direction has its major component at +-1 on the face's axis.
                    const int axis = face / 2;
                    if (d[axis] != (face % 2 ? -1.0f : 1.0f)) ++mismatches;
                }
        CHECK(mismatches == 0);
    }
}

TEST_CASE("texel centre directions match hand-worked values") {
    // N = 2: column/row 0 -> coordinate -0.5, 1 -> +0.5. +X: (1, -tc, -sc).
    CHECK(texel_direction({0, 0, 0}, 2) == glm::vec3(1.0f, 0.5f, 0.5f));
    CHECK(texel_direction({0, 1, 0}, 2) == glm::vec3(1.0f, 0.5f, -0.5f));
    CHECK(texel_direction({1, 1, 1}, 2) == glm::vec3(-1.0f, -0.5f, 0.5f));  // -X: (-1, -tc, sc)
    CHECK(texel_direction({2, 0, 1}, 2) == glm::vec3(-0.5f, 1.0f, 0.5f));   // +Y: (sc, 1, tc)
    CHECK(texel_direction({3, 0, 1}, 2) == glm::vec3(-0.5f, -1.0f, -0.5f)); // -Y: (sc, -1, -tc)
    CHECK(texel_direction({4, 1, 0}, 2) == glm::vec3(0.5f, 0.5f, 1.0f));    // +Z: (sc, -tc, 1)
    CHECK(texel_direction({5, 1, 0}, 2) == glm::vec3(-0.5f, 0.5f, -1.0f));  // -Z: (-sc, -tc, -1)
    // N = 1: the face centre.
    CHECK(texel_direction({3, 0, 0}, 1) == glm::vec3(0.0f, -1.0f, 0.0f));
    // Linear index: (face * N + row) * N + column.
    CHECK(raycache::texel_linear_index({5, 2, 1}, 3) == (5u * 3 + 1) * 3 + 2);
}

TEST_CASE("vectors that are not directions have no texel") {
    const float inf = std::numeric_limits<float>::infinity();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (const glm::vec3 d : {glm::vec3(0.0f), glm::vec3(nan, 1, 0), glm::vec3(1, nan, 0), glm::vec3(0, 0, nan),
                              glm::vec3(inf, 0, 0), glm::vec3(0, -inf, 0), glm::vec3(1e-40f, 0, 0),
                              glm::vec3(0, 0, 5e37f)}) {
        CAPTURE(d.x);
        CAPTURE(d.y);
        CAPTURE(d.z);
        CHECK_FALSE(texel_of(d, 16).has_value());
    }
    // The edges of the accepted magnitude range are directions.
    CHECK(texel_of(glm::vec3(0x1p-64f, 0, 0), 16).has_value());
    CHECK(texel_of(glm::vec3(0, 0x1p64f, 0), 16).has_value());
    // Just beyond them, and a normal but short vector, are not.
    CHECK_FALSE(texel_of(glm::vec3(std::nextafter(0x1p-64f, 0.0f), 0, 0), 16).has_value());
    CHECK_FALSE(texel_of(glm::vec3(0, 0, std::nextafter(0x1p64f, 1e30f)), 16).has_value());
    CHECK_FALSE(texel_of(glm::vec3(1e-30f, 0, 0), 16).has_value());
}
