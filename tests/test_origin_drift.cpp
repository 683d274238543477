// Origins in the CCT: a tile keeps the box of the origins its texels were stored from; a lookup from an
// origin more than `drift` outside it misses and marks the tile, which begin_frame() drops. Directions by
// hand from the face table: (1, 0, 0) is +X's centre, texel (32, 32) of a 64-texel face, tile (2, 2).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <limits>
#include <optional>

#include "raycache/raycache.hpp"

namespace {
using raycache::CctCube;
using raycache::TexelAddress;
const glm::vec3 grey(0.5f), plus_x(1.0f, 0.0f, 0.0f);
} // namespace

TEST_CASE("a texel answers rays leaving within drift of its tile's origins, and a farther one drops the tile") {
    CctCube cube(64);
    CHECK(cube.store(plus_x, grey, glm::vec3(0.0f, 0.0f, 0.0f)));
    cube.begin_frame();
    CHECK(cube.lookup(plus_x, glm::vec3(0.05f, -0.1f, 0.0f), 0.1f));  // within 0.1 of the box {0}
    CHECK(cube.allocated_tiles() == 1u);
    CHECK_FALSE(cube.lookup(plus_x, glm::vec3(0.2f, 0.0f, 0.0f), 0.1f)); // 0.2 away: a miss
    CHECK(cube.statistics().misses == 1u);
    CHECK(cube.allocated_tiles() == 1u); // dropped only between frames
    cube.begin_frame();
    CHECK(cube.allocated_tiles() == 0u);
    CHECK(cube.valid_texels() == 0u);
    CHECK(cube.dropped_tiles() == 1u);
    CHECK_FALSE(cube.lookup(plus_x, glm::vec3(0.0f), 0.1f)); // empty now: refills from the current rays
}

TEST_CASE("the origin box a lookup reads is the one from before the frame: this frame's stores widen it next frame") {
    CctCube cube(64);
    cube.store(plus_x, grey, glm::vec3(0.0f));
    cube.begin_frame();
    // Another texel of the same tile, (33, 32), stored this frame from x = 1.
    CHECK(cube.store_at(TexelAddress{0, 33, 32}, grey)); // no origin: no widening
    CHECK(cube.store(texel_direction(TexelAddress{0, 34, 32}, 64), grey, glm::vec3(1.0f, 0.0f, 0.0f)));
    CHECK_FALSE(cube.lookup(plus_x, glm::vec3(1.0f, 0.0f, 0.0f), 0.1f)); // the visible box is still {0}
    cube.begin_frame();
    CHECK(cube.dropped_tiles() == 1u); // the miss above marked it
    // A fresh tile: stored from 0 and from 1 in one frame, its box is [0, 1] on x from the next frame on.
    cube.store(plus_x, grey, glm::vec3(0.0f));
    cube.store(texel_direction(TexelAddress{0, 34, 32}, 64), grey, glm::vec3(1.0f, 0.0f, 0.0f));
    cube.begin_frame();
    CHECK(cube.lookup(plus_x, glm::vec3(0.5f, 0.0f, 0.0f), 0.01f));
    CHECK(cube.lookup(plus_x, glm::vec3(1.05f, 0.0f, 0.0f), 0.1f));
    cube.begin_frame();
    CHECK(cube.dropped_tiles() == 1u);
}

TEST_CASE("tiles stored without origins answer rays from anywhere, and a bad origin is refused") {
    CctCube cube(16);
    cube.store(plus_x, grey);
    cube.begin_frame();
    CHECK(cube.lookup(plus_x, glm::vec3(100.0f), 0.0f));
    const float nan = std::numeric_limits<float>::quiet_NaN();
    CHECK_FALSE(cube.store(glm::vec3(0, 1, 0), grey, glm::vec3(nan)));
    CHECK(cube.statistics().refused_stores == 1u);
}

TEST_CASE("a store refused because its texel is already visible leaves the box alone: the box bounds the origins of the values kept") {
    CctCube cube(64);
    const glm::vec3 neighbour = texel_direction(TexelAddress{0, 33, 32}, 64); // same tile as plus_x
    CHECK(cube.store(plus_x, grey, glm::vec3(0.0f)));
    CHECK(cube.store(neighbour, grey, glm::vec3(0.0f)));
    cube.begin_frame();
    cube.set_doubtful(TexelAddress{0, 32, 32}); // traced every frame from now on, as a colour edge's texels are
    cube.begin_frame();
    // The doubtful texel's ray, from x = 0.5 now, is traced; its store is refused (the texel holds a value).
    CHECK_FALSE(cube.lookup(plus_x, glm::vec3(0.5f, 0.0f, 0.0f), 1.0f));
    CHECK_FALSE(cube.store(plus_x, glm::vec3(0.9f), glm::vec3(0.5f, 0.0f, 0.0f)));
    cube.begin_frame();
    // The neighbour's value still comes from x = 0 only: a ray from 0.5 is 0.4 beyond drift 0.1 of it.
    CHECK_FALSE(cube.lookup(neighbour, glm::vec3(0.5f, 0.0f, 0.0f), 0.1f));
    CHECK(cube.lookup(neighbour, glm::vec3(0.05f, 0.0f, 0.0f), 0.1f));
}

TEST_CASE("with a parallax bound a tile answers origins within parallax x its nearest hit distance, capped by drift") {
    CctCube cube(64);
    const glm::vec3 neighbour = texel_direction(TexelAddress{0, 33, 32}, 64); // same tile as plus_x
    const raycache::OriginTolerance tolerance{1.0f, 0.05f};
    CHECK(cube.store(plus_x, grey, glm::vec3(0.0f), 10.0f));
    CHECK(cube.store(neighbour, grey, glm::vec3(0.0f), 2.0f)); // the nearest: 2, so 0.05 x 2 = 0.1 of drift
    cube.begin_frame();
    CHECK(cube.nearest_hit(TexelAddress{0, 40, 40}) == 2.0f); // any texel of the tile
    CHECK(cube.lookup(plus_x, glm::vec3(0.09f, 0.0f, 0.0f), tolerance));
    CHECK(cube.lookup(plus_x, glm::vec3(0.0f, -0.09f, 0.09f), tolerance)); // per axis, as the box is
    cube.begin_frame();
    CHECK(cube.dropped_tiles() == 0u);
    CHECK_FALSE(cube.lookup(plus_x, glm::vec3(0.11f, 0.0f, 0.0f), tolerance));
    cube.begin_frame();
    CHECK(cube.dropped_tiles() == 1u);

    // Rays that escaped (infinite distance) leave only the drift: 0.3 away is answered with drift 0.5.
    CHECK(cube.store(plus_x, grey, glm::vec3(0.0f), std::numeric_limits<float>::infinity()));
    cube.begin_frame();
    CHECK(cube.lookup(plus_x, glm::vec3(0.3f, 0.0f, 0.0f), raycache::OriginTolerance{0.5f, 0.05f}));
    CHECK_FALSE(cube.lookup(plus_x, glm::vec3(0.3f, 0.0f, 0.0f), raycache::OriginTolerance{0.25f, 0.05f}));
    // A NaN or negative distance is refused.
    CHECK_FALSE(cube.store(neighbour, grey, glm::vec3(0.0f), -1.0f));
    CHECK_FALSE(cube.store(neighbour, grey, glm::vec3(0.0f), std::numeric_limits<float>::quiet_NaN()));
}

TEST_CASE("a store whose origin would stretch its tile's visible box beyond the tolerance is refused, so the box stays tight") {
    CctCube cube(64);
    const glm::vec3 a = texel_direction(TexelAddress{0, 33, 32}, 64), b = texel_direction(TexelAddress{0, 34, 32}, 64);
    const raycache::OriginTolerance tolerance{0.1f, std::numeric_limits<float>::infinity()};
    CHECK(cube.store(plus_x, grey, glm::vec3(0.0f), 5.0f, tolerance)); // a fresh tile takes any origin
    cube.begin_frame();
    // Empty texels of the tile: 0.08 from the box {0} makes it 0.08 wide (<= 0.1): kept; 0.15 would not.
    CHECK(cube.store(a, grey, glm::vec3(0.08f, 0.0f, 0.0f), 5.0f, tolerance));
    CHECK_FALSE(cube.store(b, grey, glm::vec3(0.15f, 0.0f, 0.0f), 5.0f, tolerance));
    CHECK(cube.statistics().refused_stores == 1u);
    cube.begin_frame();
    CHECK(cube.lookup(a, glm::vec3(0.08f, 0.0f, 0.0f), tolerance));
    CHECK_FALSE(cube.lookup(b, glm::vec3(0.08f, 0.0f, 0.0f), tolerance)); // b was never written
    // The box is [0, 0.08] on x: 0.17 is 0.09 beyond it, within drift; 0.19 is not.
    CHECK(cube.lookup(plus_x, glm::vec3(0.17f, 0.0f, 0.0f), tolerance));
    CHECK_FALSE(cube.lookup(plus_x, glm::vec3(0.19f, 0.0f, 0.0f), tolerance));
}

TEST_CASE("texel_of, lookup_at and store_at act as lookup and store by direction, with the face found once") {
    CctCube cube(64);
    const std::optional<TexelAddress> t = cube.texel_of(plus_x);
    REQUIRE(t);
    CHECK(t->face == 0); // +X's centre: texel (32, 32), by hand from the face table
    CHECK(t->column == 32);
    CHECK(t->row == 32);
    CHECK_FALSE(cube.texel_of(glm::vec3(0.0f)));
    const raycache::OriginTolerance tolerance{0.1f, 0.05f};
    CHECK(cube.store_at(*t, grey, glm::vec3(0.0f), 1.0f, tolerance));
    CHECK_FALSE(cube.store_at(*t, grey, glm::vec3(0.0f), -1.0f, tolerance)); // a negative distance
    cube.begin_frame();
    CHECK(cube.lookup(plus_x, glm::vec3(0.04f, 0.0f, 0.0f), tolerance)); // allowed: min(0.1, 0.05 x 1)
    CHECK(cube.lookup_at(*t, glm::vec3(0.04f, 0.0f, 0.0f), tolerance));
    CHECK(cube.lookup_at(*t)); // no origin test
    CHECK(cube.statistics().hits == 3u);
    CHECK_FALSE(cube.lookup_at(*t, glm::vec3(0.06f, 0.0f, 0.0f), tolerance));
    CHECK(cube.statistics().misses == 1u);
}

// Origin boxes and path unions keep floats as ordered keys (raycache/shared/origin_rule.h): keys by hand from
// the IEEE bits (a non-negative float gains the top bit, a negative one is inverted; -0 counts as +0), their
// order that of the floats, and every key decoded back to its float, over every exponent's extremes and
// a stride through all 2^32 bit patterns (NaNs aside).
TEST_CASE("ordered keys of floats: by hand, in the floats' order, and decoded back bit for bit") {
    using raycache::shared::raycache_key_float;
    using raycache::shared::raycache_ordered_key;
    const float inf = std::numeric_limits<float>::infinity();
    CHECK(raycache_ordered_key(1.0f) == 0xBF800000u);  // 0x3F800000 with the top bit
    CHECK(raycache_ordered_key(-1.0f) == 0x407FFFFFu); // ~0xBF800000
    CHECK(raycache_ordered_key(0.0f) == 0x80000000u);
    CHECK(raycache_ordered_key(-0.0f) == 0x80000000u);
    CHECK(raycache_ordered_key(inf) == 0xFF800000u);
    CHECK(raycache_ordered_key(-inf) == 0x007FFFFFu);
    CHECK(raycache_key_float(0xBF800000u) == 1.0f);
    CHECK(raycache_key_float(0x407FFFFFu) == -1.0f);
    CHECK(raycache_key_float(0xFF800000u) == inf);
    CHECK(raycache_key_float(0x007FFFFFu) == -inf);
    CHECK(raycache_key_float(0x80000000u) == 0.0f);
    std::uint64_t checked = 0;
    for (std::uint64_t step = 0; step < (std::uint64_t{1} << 32); step += 65521u) {
        for (const std::uint32_t bits : {static_cast<std::uint32_t>(step), static_cast<std::uint32_t>(step) | 0x7F7FFFFFu,
                                         static_cast<std::uint32_t>(step) & 0x80800000u}) {
            float f;
            std::memcpy(&f, &bits, sizeof f);
            if (std::isnan(f)) continue;
            const std::uint32_t key = raycache_ordered_key(f);
            const float back = raycache_key_float(key);
            std::uint32_t back_bits;
            std::memcpy(&back_bits, &back, sizeof back);
            CHECK(back_bits == (bits == 0x80000000u ? 0u : bits)); // -0 comes back as +0
            const bool negative = (bits & 0x80000000u) != 0u && bits != 0x80000000u;
            CHECK(key == (negative ? ~bits : ((bits & 0x7FFFFFFFu) | 0x80000000u)));
            ++checked;
        }
    }
    CHECK(checked > 150000u);
    // Order: keys compare as their floats do.
    const float ordered[] = {-inf, -3.0e38f, -1.0f, -1.0e-38f, -1.0e-45f, 0.0f, 1.0e-45f, 1.0e-38f, 1.0f, 3.0e38f, inf};
    for (std::size_t i = 0; i + 1 < std::size(ordered); ++i) CHECK(raycache_ordered_key(ordered[i]) < raycache_ordered_key(ordered[i + 1]));
}
