// The direction cells of raycache/direction_cells.hpp: 3 x 3 cells on each cube face, cut at face
// coordinates -1/3 and 1/3. Expected cells are worked by hand from the face table (sc, tc and the major
// axis m of SPEC-style cube maps: +X sc = -z, tc = -y; +Y sc = x, tc = z; +Z sc = x, tc = -y; -Z sc = -x,
// tc = -y), and checked against an independent brute force: the cell of each sampled direction, found by
// comparing |components| and dividing, must be named.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include <glm/glm.hpp>

#include "raycache/direction_cells.hpp"
#include "raycache/path_record.hpp"
#include "raycache/shared/cube_face.h"
#include "raycache/shared/cube_filter.h"
#include "test_random.hpp"

using raycache::direction_cell_bit;
using raycache::direction_cells_of_box;
using raycache::direction_cells_of_texels;
using raycache::every_direction_cell;

namespace {

std::uint64_t cells_of(const glm::vec3& d) { return direction_cells_of_box(d, d); }

// The cell of a direction worked without the library's face code: the largest |component| names the face
// (ties do not occur for the random directions used), then u and v by the table, then thirds.
std::uint64_t brute_cell(const glm::vec3& d) {
    const glm::vec3 a = glm::abs(d);
    int face;
    float sc, tc, m;
    if (a.x >= a.y && a.x >= a.z) {
        face = d.x > 0 ? 0 : 1, m = a.x;
        sc = d.x > 0 ? -d.z : d.z, tc = -d.y;
    } else if (a.y >= a.z) {
        face = d.y > 0 ? 2 : 3, m = a.y;
        sc = d.x, tc = d.y > 0 ? d.z : -d.z;
    } else {
        face = d.z > 0 ? 4 : 5, m = a.z;
        sc = d.z > 0 ? d.x : -d.x, tc = -d.y;
    }
    auto third = [](float u) { return u < -1.0f / 3.0f ? 0 : (u < 1.0f / 3.0f ? 1 : 2); };
    return direction_cell_bit(face, third(sc / m), third(tc / m));
}

} // namespace

TEST_CASE("a direction names the cell of its face it falls in, and cell edges and cube corners name every cell they touch") {
    CHECK(cells_of({1, 0, 0}) == direction_cell_bit(0, 1, 1));      // +X centre: bit 4
    CHECK(direction_cell_bit(0, 1, 1) == (std::uint64_t{1} << 4));
    CHECK(cells_of({2, 1, 0}) == direction_cell_bit(0, 1, 0));      // +X, tc = -y / x = -0.5: row 0
    CHECK(cells_of({1, 0, -0.9f}) == direction_cell_bit(0, 2, 1));  // +X, sc = -z / x = 0.9: column 2
    CHECK(cells_of({0, 0, -5}) == direction_cell_bit(5, 1, 1));     // -Z centre: bit 49
    CHECK(cells_of({0.5f, 0, -1}) == direction_cell_bit(5, 0, 1));  // -Z, sc = -x / |z| = -0.5
    CHECK(cells_of({0, -1, 0.6f}) == direction_cell_bit(3, 1, 0));  // -Y, sc = x = 0, tc = -z / |y| = -0.6
    // On the edge between columns 1 and 2 of +X (sc = 1/3): both.
    CHECK(cells_of({3, 0, -1}) == (direction_cell_bit(0, 1, 1) | direction_cell_bit(0, 2, 1)));
    // The corner (1, 1, 1) of three faces: +X (sc = -1, tc = -1), +Y (sc = 1, tc = 1), +Z (sc = 1, tc = -1).
    CHECK(cells_of({1, 1, 1}) == (direction_cell_bit(0, 0, 0) | direction_cell_bit(2, 2, 2) | direction_cell_bit(4, 2, 0)));
    // Not directions: every cell for anything not finite, none for an empty box.
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    CHECK(cells_of({nan, 0, 1}) == every_direction_cell);
    CHECK(cells_of({inf, 0, 0}) == every_direction_cell);
    CHECK(direction_cells_of_box({1, 0, 0}, {0, 0, 0}) == 0u);
    CHECK(raycache::direction_cell_count == 54);
    CHECK(every_direction_cell == (std::uint64_t{1} << 54) - 1);
}

TEST_CASE("a box of directions names the cells its cone crosses: a narrow one few, one holding the zero vector all") {
    // Around +X within 0.01: its centre cell alone.
    CHECK(direction_cells_of_box({1, -0.01f, -0.01f}, {1, 0.01f, 0.01f}) == direction_cell_bit(0, 1, 1));
    // Between 26.6 and 63.4 degrees from +X towards +Y in the xy-plane (z = 0): on +X (up to 45 degrees)
    // sc = -z = 0 (column 1) and tc = -y / x in [-1, -1/2] (row 0); on +Y sc = x / y in [1/2, 1]
    // (column 2) and tc = z / y = 0 (row 1); the Z faces have m = 0 and hold none of them.
    CHECK(direction_cells_of_box({0.5f, 0.5f, 0}, {1, 1, 0}) == (direction_cell_bit(0, 1, 0) | direction_cell_bit(2, 2, 1)));
    // A box holding the zero vector reaches every face's axis at m -> 0: every cell.
    CHECK(direction_cells_of_box({-1, -1, -1}, {1, 1, 1}) == every_direction_cell);
}

TEST_CASE("random boxes of directions name the cell of every direction inside them") {
    Lcg rng{54};
    for (int trial = 0; trial < 20000; ++trial) {
        const glm::vec3 a(rng.signed_uniform(), rng.signed_uniform(), rng.signed_uniform());
        const float size = trial % 2 ? 0.05f : 0.5f;
        const glm::vec3 b = a + size * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
        const std::uint64_t cells = direction_cells_of_box(a, b);
        for (int k = 0; k < 8; ++k) {
            const glm::vec3 d = a + (b - a) * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
            if (glm::length(d) < 1e-3f) continue;
            CAPTURE(trial);
            REQUIRE((cells & brute_cell(d)) != 0u);
        }
    }
}

TEST_CASE("the cells of texels, grown by one, hold every direction whose lookup or filtered lookup reads one of them") {
    // Hand-worked: face +X of a 12-texel cube, texels columns 0..1, rows 4..5. Grown by a texel: sc from
    // 2 * (-1) / 12 - 1 = -7/6 to 2 * 3 / 12 - 1 = -1/2 (column 0 of +X; past sc = -1 it reaches +Z),
    // tc from -1/2 to 1/6 (rows 0 and 1). On +Z those directions (1, -tc, -sc) have m = z = -sc in
    // [1, 7/6] (at least x = 1), sc' = x / z in [6/7, 1] (column 2) and tc' = -y / z = tc / z in
    // [-1/2, 1/6] (rows 0 and 1).
    CHECK(direction_cells_of_texels(0, 0, 4, 2, 6, 12) ==
          (direction_cell_bit(0, 0, 0) | direction_cell_bit(0, 0, 1) | direction_cell_bit(4, 2, 0) | direction_cell_bit(4, 2, 1)));
    // Brute force over cube sizes: for random directions, every texel a nearest or filtered lookup reads
    // names (as a one-texel region) the direction's cell.
    Lcg rng{7};
    for (int n : {1, 2, 3, 8, 17, 64, 1024}) {
        CAPTURE(n);
        for (int trial = 0; trial < 20000; ++trial) {
            const glm::vec3 d(rng.signed_uniform(), rng.signed_uniform(), rng.signed_uniform());
            if (glm::length(d) < 1e-3f) continue;
            const std::uint64_t cell = brute_cell(d);
            const raycache::shared::raycache_texel_address t = raycache::shared::raycache_texel_of(d, n);
            REQUIRE((direction_cells_of_texels(t.face, t.column, t.row, t.column + 1, t.row + 1, n) & cell) != 0u);
            const raycache::shared::raycache_filter_taps taps = raycache::shared::raycache_filter_taps_of(d, n);
            for (int k = 0; k < taps.count; ++k) {
                const raycache::shared::raycache_texel_address& a = taps.texel[k];
                CAPTURE(k);
                REQUIRE((direction_cells_of_texels(a.face, a.column, a.row, a.column + 1, a.row + 1, n) & cell) != 0u);
            }
        }
    }
}

TEST_CASE("a path record knows nothing of its cached reads until told to track them, and unions start from none") {
    raycache::PathRecord fresh;
    CHECK(fresh.cached_reads == every_direction_cell);
    CHECK(raycache::PathRecord::empty().cached_reads == 0u);
    raycache::PathRecord tracked;
    tracked.track_cached_reads();
    CHECK(tracked.cached_reads == 0u);
    tracked.read_cached({1, 0, 0}, {1, 0, 0});
    CHECK(tracked.cached_reads == direction_cell_bit(0, 1, 1));
    raycache::PathRecord other;
    other.track_cached_reads();
    other.read_cached({0, 0, -1}, {0, 0, -1});
    raycache::PathRecord u = raycache::PathRecord::empty();
    u.merge(tracked);
    u.merge(other);
    CHECK(u.cached_reads == (direction_cell_bit(0, 1, 1) | direction_cell_bit(5, 1, 1)));
    u.merge(fresh); // a path that did not track them may have read anywhere
    CHECK(u.cached_reads == every_direction_cell);
}

TEST_CASE("the cells of texels clear of the face's edges, hand-worked: a span's edge on a cell edge names both cells") {
    // Texel i's edge lies at 3 i / n in cells. Grown by a texel, columns [c0, c1) span the texel edges
    // c0 - 1 to c1 + 1.
    // n = 30, columns and rows [12, 14) and [14, 16) of +Y: spans 11..15 and 13..17, at 1.1..1.5 and 1.3..1.7:
    // the middle cell alone.
    CHECK(direction_cells_of_texels(2, 12, 14, 14, 16, 30) == direction_cell_bit(2, 1, 1));
    // n = 12, columns [5, 7), rows [4, 6) of -Z: spans 4..8 (1 and 2 exactly: all three columns) and 3..7
    // (0.75..1.75: rows 0 and 1).
    std::uint64_t expected = 0;
    for (int row = 0; row <= 1; ++row)
        for (int column = 0; column <= 2; ++column) expected |= direction_cell_bit(5, column, row);
    CHECK(direction_cells_of_texels(5, 5, 4, 7, 6, 12) == expected);
    // n = 12, column [6, 7) and row [5, 6) of -X: spans 5..8 (1.25..2: columns 1 and 2) and 4..7 (1..1.75:
    // rows 0 and 1).
    CHECK(direction_cells_of_texels(1, 6, 5, 7, 6, 12) ==
          (direction_cell_bit(1, 1, 0) | direction_cell_bit(1, 2, 0) | direction_cell_bit(1, 1, 1) | direction_cell_bit(1, 2, 1)));
}

TEST_CASE("the cells of texels clear of the face's edges are those of their grown rectangle's box, on every face size") {
    // The box of the grown rectangle in the plane |m| = 1 (direction_cells_of_box, checked by brute force
    // above) names the same cells: only its own face's, from the same coordinates. Every face size, every
    // interior block of 1 or 2 texels a side along a row and a column, and random wider ranges.
    Lcg rng{11};
    auto coordinate = [](int texel, int n) { return 2.0f * static_cast<float>(texel) / static_cast<float>(n) - 1.0f; };
    auto by_box = [&](int face, int c0, int r0, int c1, int r1, int n) {
        const glm::vec3 a = raycache::shared::raycache_face_point(face, 1.0f, coordinate(c0 - 1, n), coordinate(r0 - 1, n));
        const glm::vec3 b = raycache::shared::raycache_face_point(face, 1.0f, coordinate(c1 + 1, n), coordinate(r1 + 1, n));
        return direction_cells_of_box(glm::min(a, b), glm::max(a, b));
    };
    long checked = 0;
    for (int n = 1; n <= 4096; n += (n < 320 ? 1 : 97)) {
        CAPTURE(n);
        for (int width = 1; width <= 2; ++width)
            for (int c0 = 0; c0 + width <= n; ++c0) {
                const int face = c0 % RAYCACHE_FACE_COUNT;
                const int r0 = static_cast<int>(rng.uniform() * static_cast<float>(n - width + 1)) % (n - width + 1);
                const std::uint64_t cells = direction_cells_of_texels(face, c0, r0, c0 + width, r0 + width, n);
                REQUIRE(cells == by_box(face, c0, r0, c0 + width, r0 + width, n));
                REQUIRE(direction_cells_of_texels(face, r0, c0, r0 + width, c0 + width, n) == by_box(face, r0, c0, r0 + width, c0 + width, n));
                ++checked;
            }
        for (int trial = 0; trial < 64 && n > 1; ++trial) {
            const int face = trial % RAYCACHE_FACE_COUNT;
            const int c0 = static_cast<int>(rng.uniform() * static_cast<float>(n)) % n, r0 = static_cast<int>(rng.uniform() * static_cast<float>(n)) % n;
            const int c1 = c0 + 1 + static_cast<int>(rng.uniform() * static_cast<float>(n - c0)) % (n - c0);
            const int r1 = r0 + 1 + static_cast<int>(rng.uniform() * static_cast<float>(n - r0)) % (n - r0);
            REQUIRE(direction_cells_of_texels(face, c0, r0, c1, r1, n) == by_box(face, c0, r0, c1, r1, n));
        }
    }
    CHECK(checked > 100000);
}
