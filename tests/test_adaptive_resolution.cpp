// Adaptive face sizes: the ladder of sizes, the ideal size for a frame's rays, hysteresis, the coverage
// of directions, and resampling a fine cube into a coarse one. Expected values are worked by hand.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <thread>
#include <vector>

#include "raycache/raycache.hpp"

namespace {

using raycache::AdaptiveResolution;
using raycache::CctCube;
using raycache::DirectionCoverage;
using raycache::TexelAddress;

} // namespace

TEST_CASE("the face-size ladder goes up by half octaves from 8: 8, 11, 16, 23, 32, 45, 64, 91, 128, 181, 256, 362, 512") {
    const int expected[] = {8, 11, 16, 23, 32, 45, 64, 91, 128, 181, 256, 362, 512, 724, 1024};
    for (int i = 0; i < 15; ++i) CHECK(raycache::face_size_step(i) == expected[i]);
}

TEST_CASE("the ideal face size puts rays_per_texel rays on each covered texel") {
    // 6144 rays over every direction, one a texel: 6 N^2 = 6144 -> N = 32.
    CHECK(raycache::ideal_face_size(6144, 1.0, 1.0f) == doctest::Approx(32.0));
    // The same rays over a quarter of the directions: 6 N^2 / 4 = 6144 -> N = 64.
    CHECK(raycache::ideal_face_size(6144, 0.25, 1.0f) == doctest::Approx(64.0));
    // Four rays a texel: 6 N^2 * 4 = 6144 -> N = 16.
    CHECK(raycache::ideal_face_size(6144, 1.0, 4.0f) == doctest::Approx(16.0));
    CHECK(raycache::ideal_face_size(0, 1.0, 1.0f) == 0.0);
    CHECK(raycache::ideal_face_size(100, 0.0, 1.0f) == 0.0);
}

TEST_CASE("the next face size moves to the nearest step only when the ideal is far enough, within the limits") {
    AdaptiveResolution a; // hysteresis 2 half octaves, sizes 8..1024
    // From 256, an ideal of 32 (6144 rays, full coverage) is 6 half octaves away: move to 32.
    CHECK(raycache::next_face_size(256, 6144, 1.0, a) == 32);
    // From 32, an ideal of 40 (9600 rays: sqrt(1600)) is 0.64 half octaves away: stay.
    CHECK(raycache::next_face_size(32, 9600, 1.0, a) == 32);
    // From 32, an ideal of 64 (24576 rays) is 2 half octaves away: move.
    CHECK(raycache::next_face_size(32, 24576, 1.0, a) == 64);
    // An ideal of 50 from 32 (15000 rays): 1.29 half octaves: stay; with hysteresis 1: the nearest step, 45.
    CHECK(raycache::next_face_size(32, 15000, 1.0, a) == 32);
    AdaptiveResolution eager = a;
    eager.hysteresis_steps = 1;
    CHECK(raycache::next_face_size(32, 15000, 1.0, eager) == 45);
    // No rays: keep the size. Limits: an ideal of 2 gives the minimum, of 100,000 the largest step <= max.
    CHECK(raycache::next_face_size(181, 0, 0.0, a) == 181);
    CHECK(raycache::next_face_size(256, 24, 1.0, a) == 8);
    AdaptiveResolution capped = a;
    capped.max_face_size = 600;
    CHECK(raycache::next_face_size(256, 60000000000ull, 1.0, capped) == 512);
}

TEST_CASE("the first sizing, after the first counted frame, goes straight to the nearest step") {
    AdaptiveResolution a; // first size 256, hysteresis 2 half octaves
    // 6 * 362^2 = 786,264 rays over every direction: ideal 362, one half octave above 256. A later frame
    // stays at 256 (hysteresis); the first sizing moves, since the cube holds only one cold frame's texels.
    CHECK(raycache::next_face_size(256, 786264, 1.0, a) == 256);
    CHECK(raycache::first_face_size(256, 786264, 1.0, a) == 362);
    // Half the directions covered, 2 rays a texel: 6 N^2 * 0.5 * 2 = 6 N^2, so 1536 rays give N = 16.
    AdaptiveResolution two = a;
    two.rays_per_texel = 2.0f;
    CHECK(raycache::first_face_size(256, 1536, 0.5, two) == 16);
    // No rays: keep the size.
    CHECK(raycache::first_face_size(256, 0, 0.0, a) == 256);
}

TEST_CASE("a still camera's finer faces take the largest step whose rays' tiles fit the budget's room") {
    // By hand, 1000-byte tiles and 8-byte table entries: N = 91 has 216 tiles, so its table is 1728 bytes and
    // its tiles 216000; rays over a quarter of the directions reach a quarter of them: 1728 + 54000 = 55728.
    // N = 64: 96 tiles, 768 + 96000 x covered; N = 45: 54 tiles, 432 + 54000 x covered.
    CHECK(raycache::rays_cube_bytes(91, 1.0, 1000, 8) == 217728u); // all of it: full_cube_bytes
    CHECK(raycache::rays_cube_bytes(91, 0.25, 1000, 8) == 55728u);
    CHECK(raycache::rays_cube_bytes(64, 0.5, 1000, 8) == 48768u);
    CHECK(raycache::rays_cube_bytes(64, 2.0, 1000, 8) == 96768u); // shares clamp to [0, 1]
    CHECK(raycache::rays_cube_bytes(64, -1.0, 1000, 8) == 768u);
    // From 32 towards 91, every direction covered: 91 at its bytes, one byte less 64, then 45, then none
    // above the floor (32 stays).
    CHECK(raycache::largest_face_size_within(32, 91, 1.0, 217728, 1000, 8) == 91);
    CHECK(raycache::largest_face_size_within(32, 91, 1.0, 217727, 1000, 8) == 64);
    CHECK(raycache::largest_face_size_within(32, 91, 1.0, 96767, 1000, 8) == 45);
    CHECK(raycache::largest_face_size_within(32, 91, 1.0, 54431, 1000, 8) == 32);
    // A quarter covered: 91 fits 55728 bytes; one byte less, 64 (24768).
    CHECK(raycache::largest_face_size_within(32, 91, 0.25, 55728, 1000, 8) == 91);
    CHECK(raycache::largest_face_size_within(32, 91, 0.25, 55727, 1000, 8) == 64);
    // Only ladder steps up to `wanted` (100: 91 at most), and never below the floor.
    CHECK(raycache::largest_face_size_within(32, 100, 1.0, 1u << 30, 1000, 8) == 91);
    CHECK(raycache::largest_face_size_within(91, 64, 1.0, 1u << 30, 1000, 8) == 91);
}

TEST_CASE("the first face size is the largest step at which every cube sharing the budget could fill all its tiles") {
    const raycache::AdaptiveResolution a; // first 256, min 8
    // By hand: a cube of N texels a face has 6 ceil(N/16)^2 tiles; with 1000-byte tiles and 8-byte table
    // entries, N = 64 takes 96 x 1008 = 96768 bytes, N = 91 (the next step) 216 x 1008 = 217728, N = 256
    // 1536 x 1008 = 1548288.
    CHECK(raycache::full_cube_bytes(64, 1000, 8) == 96768u);
    CHECK(raycache::full_cube_bytes(91, 1000, 8) == 217728u);
    CHECK(raycache::full_cube_bytes(256, 1000, 8) == 1548288u);
    CHECK(raycache::full_cube_bytes(1, 1000, 8) == 6048u);
    // Ten cubes: a budget of ten full 64-cubes gives 64; one byte less, the step below (45: 3 x 3 tiles).
    CHECK(raycache::first_face_size_within(a, 10, 967680, 1000, 8) == 64);
    CHECK(raycache::first_face_size_within(a, 10, 967679, 1000, 8) == 45);
    CHECK(raycache::first_face_size_within(a, 10, 2177280, 1000, 8) == 91);
    // Room for the configured first size: it stays, and so for one cube or no cube counted.
    CHECK(raycache::first_face_size_within(a, 10, 15482880, 1000, 8) == 256);
    CHECK(raycache::first_face_size_within(a, 1, 1548288, 1000, 8) == 256);
    CHECK(raycache::first_face_size_within(a, 0, 1548288, 1000, 8) == 256);
    // Not even the smallest step fits: the minimum (8: one tile a face, 6048 bytes).
    CHECK(raycache::first_face_size_within(a, 1000, 1000, 1000, 8) == 8);
    // A share just short of 32's 24 tiles: 16 (23 has 24 tiles too); with a minimum of 32, the minimum.
    CHECK(raycache::first_face_size_within(a, 10, 241910, 1000, 8) == 16);
    raycache::AdaptiveResolution b;
    b.min_face_size = 32;
    CHECK(raycache::first_face_size_within(b, 10, 241910, 1000, 8) == 32);
    CHECK(raycache::first_face_size_within(b, 10, 967679, 1000, 8) == 45);
    // No limit: the configured size.
    CHECK(raycache::first_face_size_within(a, 1000, std::numeric_limits<std::size_t>::max(), 1000, 8) == 256);
}

TEST_CASE("adaptive settings are validated with a message naming the field") {
    AdaptiveResolution a;
    a.rays_per_texel = 0.0f;
    CHECK_THROWS_WITH_AS(raycache::validate(a), doctest::Contains("rays_per_texel"), std::invalid_argument);
    a = AdaptiveResolution{};
    a.min_face_size = 64;
    a.max_face_size = 32;
    CHECK_THROWS_WITH_AS(raycache::validate(a), doctest::Contains("min_face_size"), std::invalid_argument);
    a = AdaptiveResolution{};
    a.hysteresis_steps = 0;
    CHECK_THROWS_WITH_AS(raycache::validate(a), doctest::Contains("hysteresis_steps"), std::invalid_argument);
    a = AdaptiveResolution{};
    a.still_rays_per_texel = std::numeric_limits<float>::infinity();
    CHECK_THROWS_WITH_AS(raycache::validate(a), doctest::Contains("still_rays_per_texel"), std::invalid_argument);
    a = AdaptiveResolution{};
    a.still_frames = 0;
    CHECK_THROWS_WITH_AS(raycache::validate(a), doctest::Contains("still_frames"), std::invalid_argument);
    // Cubes never leave [min_face_size, max_face_size]: they cannot start outside it either.
    a = AdaptiveResolution{};
    a.min_face_size = 64;
    a.first_face_size = 8;
    CHECK_THROWS_WITH_AS(raycache::validate(a), doctest::Contains("first_face_size (8) must lie within min_face_size (64)"), std::invalid_argument);
    a = AdaptiveResolution{};
    a.first_face_size = 2048; // max_face_size 1024
    CHECK_THROWS_WITH_AS(raycache::validate(a), doctest::Contains("max_face_size (1024)"), std::invalid_argument);
}

TEST_CASE("a cube's rays hold still after still_frames frames of at most 5% empty texels, and move on at more than 20% empty") {
    AdaptiveResolution a; // still_frames 3
    using raycache::StillRays;
    auto after = [&](StillRays s, std::uint64_t looked_up, std::uint64_t empty) { return raycache::next_still_rays(s, looked_up, empty, a); };
    // The threshold, at its edge: 5 empty of 100 settle, 6 do not. Whatever the other 95 met (hits, or
    // texels at colour edges, which finer faces thin), they came back to texels that hold values.
    CHECK(after({}, 100, 5).settled_frames == 1);
    CHECK(after({}, 100, 6).settled_frames == 0);
    CHECK(after({}, 0, 0).settled_frames == 0); // no lookups: nothing to go by
    // Three settled frames in a row make it fine; one unsettled frame between starts the count again.
    StillRays s;
    s = after(s, 100, 0);
    s = after(s, 100, 0);
    CHECK_FALSE(s.fine);
    s = after(s, 100, 10); // too many empty texels
    s = after(s, 100, 0);
    s = after(s, 100, 0);
    CHECK_FALSE(s.fine);
    s = after(s, 100, 0);
    CHECK(s.fine);
    CHECK(s.settled_frames == 3);
    // Unsettled frames keep it fine while at most 20% of the lookups find empty texels; 21% end it.
    s = after(s, 100, 20);
    CHECK(s.fine);
    CHECK(s.settled_frames == 0);
    s = after(s, 100, 21);
    CHECK_FALSE(s.fine);
    // The frame after a resize (or an emptying) is not judged: the state stays, and the next frame counts.
    StillRays resized;
    resized.fine = true;
    resized.settled_frames = 2;
    resized.resized = true;
    const StillRays skipped = after(resized, 100, 100);
    CHECK(skipped.fine);
    CHECK(skipped.settled_frames == 2);
    CHECK_FALSE(skipped.resized);
    CHECK_FALSE(after(skipped, 100, 100).fine);
}

TEST_CASE("a cube whose rays hold still takes the size of still_rays_per_texel at once, then moves with the hysteresis") {
    AdaptiveResolution a; // hysteresis 2 half octaves
    a.still_rays_per_texel = 0.5f;
    raycache::StillRays s;
    s.fine = true;
    // 6144 rays over every direction: 32 at one ray a texel; at half a ray an ideal of 45.25, one half octave
    // finer, which the hysteresis alone would not take: the step 45, at once.
    CHECK(raycache::still_face_size(32, 32, s, 6144, 1.0, a) == 45);
    CHECK(s.refined);
    // Then with the hysteresis at half a ray a texel: 45 stays for the same rays, and for 9000 (ideal 54.8,
    // 0.55 half octaves away); 24576 rays (ideal 90.5, 2 half octaves) move it to 91.
    CHECK(raycache::still_face_size(45, 32, s, 6144, 1.0, a) == 45);
    CHECK(raycache::still_face_size(45, 32, s, 9000, 1.0, a) == 45);
    CHECK(raycache::still_face_size(45, 64, s, 24576, 1.0, a) == 91);
    // Never coarser than the size at one ray a texel; no rays: that size.
    CHECK(raycache::still_face_size(45, 128, s, 6144, 1.0, a) == 128);
    CHECK(raycache::still_face_size(45, 45, s, 0, 0.0, a) == 45);
    // Not fine: the size at one ray a texel, and it is no longer refined.
    s.fine = false;
    CHECK(raycache::still_face_size(45, 32, s, 6144, 1.0, a) == 32);
    CHECK_FALSE(s.refined);
    // Off (still_rays_per_texel >= rays_per_texel): always the size at one ray a texel.
    s.fine = true;
    a.still_rays_per_texel = 1.0f;
    CHECK(raycache::still_face_size(32, 32, s, 6144, 1.0, a) == 32);
}

TEST_CASE("direction coverage counts the 16 x 16 cells per face that rays took, from many threads") {
    DirectionCoverage coverage;
    CHECK(coverage.fraction() == 0.0);
    coverage.mark(glm::vec3(1, 0, 0));
    coverage.mark(glm::vec3(2, -0.001f, 0)); // same cell: +X, tv = (0.001/2 + 1)/2 -> row 8, column 8
    coverage.mark(glm::vec3(0, 0, 0));      // not a direction: ignored
    CHECK(coverage.fraction() == doctest::Approx(1.0 / 1536.0));
    coverage.reset();
    // Every cell's centre direction, split over four threads: the whole sphere.
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&coverage, t] {
            for (int face = 0; face < 6; ++face)
                for (int row = t; row < 16; row += 4)
                    for (int column = 0; column < 16; ++column) coverage.mark(texel_direction(TexelAddress{face, column, row}, 16));
        });
    for (std::thread& th : threads) th.join();
    CHECK(coverage.fraction() == 1.0);
}

TEST_CASE("direction coverage marked by texel: a texel of a face of 16 or more marks the cell its centre falls in, smaller faces' texels mark every cell they span") {
    for (int n : {1, 2, 3, 5, 8, 16, 17, 20, 48, 64, 100}) {
        CAPTURE(n);
        for (int face = 0; face < 6; face += 5)
            for (int row = 0; row < n; row += (n > 20 ? 7 : 1))
                for (int column = 0; column < n; column += (n > 20 ? 5 : 1)) {
                    const TexelAddress t{face, column, row};
                    DirectionCoverage by_texel, by_direction;
                    by_texel.mark(t, n);
                    if (n >= 16) { // one cell: the one the direction through the texel's centre marks
                        by_direction.mark(texel_direction(t, n));
                        CHECK(by_texel.fraction() == doctest::Approx(1.0 / 1536.0));
                        CHECK(by_texel.marked_cells() == by_direction.marked_cells());
                    } else { // the cells [column * 16 / n, ceil((column + 1) * 16 / n)) by hand, and rows alike
                        const int c0 = column * 16 / n, c1 = ((column + 1) * 16 + n - 1) / n;
                        const int r0 = row * 16 / n, r1 = ((row + 1) * 16 + n - 1) / n;
                        CHECK(by_texel.fraction() == doctest::Approx((c1 - c0) * (r1 - r0) / 1536.0));
                        for (int r = r0; r < r1; ++r)
                            for (int c = c0; c < c1; ++c) by_direction.mark(texel_direction(TexelAddress{face, c, r}, 16));
                        CHECK(by_texel.marked_cells() == by_direction.marked_cells());
                    }
                }
        // Every texel of the cube covers the whole sphere, whatever the size.
        DirectionCoverage all;
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column) all.mark(TexelAddress{face, column, row}, n);
        CHECK(all.fraction() == 1.0);
    }
}

TEST_CASE("resampling takes, for each coarse texel, the fine texel whose centre is nearest its centre") {
    // 48 -> 16: each coarse texel covers 3 x 3 fine texels; the middle one's centre is the coarse centre.
    CctCube fine(48), coarse(16);
    const glm::vec3 middle(0.25f, 0.5f, 0.75f), side(1.0f, 0.0f, 0.0f), corner(0.0f, 0.0f, 1.0f);
    // Coarse (2, 5) of +Y: fine (7, 16) is its middle, (6, 15) a corner.
    fine.store_at(TexelAddress{2, 7, 16}, middle);
    fine.store_at(TexelAddress{2, 6, 15}, side);
    // Coarse (0, 0) of -Z: only a corner fine texel, (2, 2).
    fine.store_at(TexelAddress{5, 2, 2}, corner);
    CHECK(raycache::resample_into(fine, coarse) == 2u);
    CHECK_FALSE(coarse.peek_at(TexelAddress{2, 2, 5})); // invisible until the next frame
    coarse.begin_frame();
    const auto a = coarse.peek_at(TexelAddress{2, 2, 5});
    const auto b = coarse.peek_at(TexelAddress{5, 0, 0});
    REQUIRE(a);
    REQUIRE(b);
    CHECK(a->x == doctest::Approx(0.25f).epsilon(0.005));
    CHECK(a->y == doctest::Approx(0.5f).epsilon(0.005));
    CHECK(b->z == doctest::Approx(1.0f).epsilon(0.005));
    CHECK(coarse.valid_texels() == 2u);
}

TEST_CASE("resampling carries the origin boxes and nearest hit distances of the fine tiles into the coarse ones") {
    // 64 -> 32: fine tiles (0, 0) and (1, 0) of +X (columns 0..15 and 16..31, rows 0..15) both fall into
    // coarse tile (0, 0) (columns 0..15 at half the resolution).
    CctCube fine(64), coarse(32);
    const glm::vec3 grey(0.5f);
    fine.store(texel_direction(TexelAddress{0, 5, 5}, 64), grey, glm::vec3(0.0f, 0.0f, 0.0f), 3.0f);
    fine.store(texel_direction(TexelAddress{0, 20, 5}, 64), grey, glm::vec3(0.2f, 0.1f, 0.0f), 2.0f);
    // Another face's tile, stored without an origin, gives no box.
    fine.store(texel_direction(TexelAddress{1, 5, 5}, 64), grey);
    fine.begin_frame();
    CHECK(raycache::resample_into(fine, coarse) == 3u);
    coarse.begin_frame();
    const auto box = coarse.origin_box(TexelAddress{0, 0, 0});
    REQUIRE(box);
    CHECK(box->first == glm::vec3(0.0f, 0.0f, 0.0f));
    CHECK(box->second == glm::vec3(0.2f, 0.1f, 0.0f));
    CHECK(coarse.nearest_hit(TexelAddress{0, 0, 0}) == 2.0f);
    CHECK_FALSE(coarse.origin_box(TexelAddress{1, 0, 0}));
    // So a ray from either fine tile's origins is answered (a resampled tile without its box would answer
    // any origin, then take the first frame's stores as its whole box).
    const raycache::OriginTolerance tight{0.01f};
    CHECK(coarse.lookup(texel_direction(TexelAddress{0, 2, 2}, 32), glm::vec3(0.0f), tight));
    CHECK(coarse.lookup(texel_direction(TexelAddress{0, 10, 2}, 32), glm::vec3(0.2f, 0.1f, 0.0f), tight));
    CHECK_FALSE(coarse.lookup(texel_direction(TexelAddress{0, 2, 2}, 32), glm::vec3(0.5f, 0.0f, 0.0f), tight));
}
