// Origins in the CCT: a tile keeps the box of the origins its texels were stored from; a lookup from an
// origin more than `drift` outside it misses and marks the tile, which begin_frame() drops. Directions by
// hand from the face table: (1, 0, 0) is +X's centre, texel (32, 32) of a 64-texel face, tile (2, 2).
#include <doctest/doctest.h>

#include <limits>

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
