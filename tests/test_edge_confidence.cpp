// The confidence test (CCT and CDCT cubes): texels whose colour differs from a filled neighbour on the same face by more
// than a threshold are marked doubtful and miss; their values stay loadable. Texels by hand: the cube is
// addressed by (face, column, row) directly, so no direction arithmetic is involved.
#include <doctest/doctest.h>

#include "raycache/raycache.hpp"

namespace {

using raycache::CctCube;
using raycache::TexelAddress;

const glm::vec3 white(1.0f), black(0.0f), near_white(0.95f);

} // namespace

TEST_CASE("neighbours differing by more than the threshold are both marked doubtful and miss, and stay loadable") {
    CctCube cube(4);
    cube.store_at(TexelAddress{0, 1, 1}, white);
    cube.store_at(TexelAddress{0, 2, 1}, black);      // right of white: differs by 1
    cube.store_at(TexelAddress{0, 1, 2}, near_white); // below white: differs by 0.05
    CHECK(raycache::mark_doubtful_edges(cube, 0.1f) == 2u);
    cube.begin_frame();
    CHECK(cube.is_doubtful(TexelAddress{0, 1, 1}));
    CHECK(cube.is_doubtful(TexelAddress{0, 2, 1}));
    CHECK_FALSE(cube.is_doubtful(TexelAddress{0, 1, 2}));
    CHECK_FALSE(cube.peek_at(TexelAddress{0, 1, 1}));
    CHECK_FALSE(cube.lookup(texel_direction(TexelAddress{0, 2, 1}, 4)));
    CHECK(cube.lookup(texel_direction(TexelAddress{0, 1, 2}, 4)));
    CHECK(cube.load(TexelAddress{0, 1, 1}));
    CHECK(cube.doubtful_texels() == 2u);
}

TEST_CASE("a texel stored in a later frame is compared with its visible neighbours") {
    CctCube cube(4);
    cube.store_at(TexelAddress{2, 0, 0}, white);
    CHECK(raycache::mark_doubtful_edges(cube, 0.1f) == 0u); // no neighbour yet
    cube.begin_frame();
    cube.store_at(TexelAddress{2, 0, 1}, black); // below it, a frame later
    CHECK(raycache::mark_doubtful_edges(cube, 0.1f) == 2u);
    cube.begin_frame();
    CHECK_FALSE(cube.peek_at(TexelAddress{2, 0, 0}));
}

TEST_CASE("texels on different faces are not compared, and a negative threshold marks nothing") {
    CctCube cube(2);
    // +X column 1 and +Z... any two faces: no neighbour relation on the same face.
    cube.store_at(TexelAddress{0, 1, 0}, white);
    cube.store_at(TexelAddress{4, 0, 0}, black);
    CHECK(raycache::mark_doubtful_edges(cube, 0.1f) == 0u);
    cube.store_at(TexelAddress{0, 0, 0}, black);
    CHECK(raycache::mark_doubtful_edges(cube, -1.0f) == 0u);
    CHECK(cube.doubtful_texels() == 0u);
}

TEST_CASE("invalidate and clear drop doubtful marks, and set_doubtful refuses an empty texel") {
    CctCube cube(4);
    CHECK_FALSE(cube.set_doubtful(TexelAddress{1, 1, 1}));
    cube.store_at(TexelAddress{1, 1, 1}, white);
    CHECK(cube.set_doubtful(TexelAddress{1, 1, 1}));
    CHECK(cube.set_doubtful(TexelAddress{1, 1, 1})); // again: still one
    CHECK(cube.doubtful_texels() == 1u);
    cube.invalidate(TexelAddress{1, 1, 1});
    CHECK(cube.doubtful_texels() == 0u);
    cube.store_at(TexelAddress{1, 1, 1}, white);
    cube.begin_frame();
    CHECK(cube.peek_at(TexelAddress{1, 1, 1})); // stored again: no mark left over
    cube.set_doubtful(TexelAddress{1, 1, 1});
    cube.clear();
    CHECK(cube.doubtful_texels() == 0u);
}

TEST_CASE("CDCT texels are compared by colour alone, and a doubtful one reads as empty") {
    raycache::CdctCube cube(4);
    using raycache::DepthSample;
    cube.store_at(TexelAddress{0, 1, 1}, DepthSample{white, 3.0f});
    cube.store_at(TexelAddress{0, 2, 1}, DepthSample{black, 3.0f});      // same depth, colour differs by 1
    cube.store_at(TexelAddress{0, 1, 2}, DepthSample{near_white, 9.0f}); // depth differs, colour by 0.05
    CHECK(raycache::mark_doubtful_edges(cube, 0.1f) == 2u);
    cube.begin_frame();
    CHECK(cube.is_doubtful(TexelAddress{0, 1, 1}));
    CHECK(cube.is_doubtful(TexelAddress{0, 2, 1}));
    CHECK_FALSE(cube.is_doubtful(TexelAddress{0, 1, 2}));
    CHECK_FALSE(cube.peek_at(TexelAddress{0, 2, 1}));
    CHECK(cube.peek_at(TexelAddress{0, 1, 2}));
}

TEST_CASE("a CDCT search whose answer lies at a colour edge misses, one away from it answers") {
    // Every texel at distance 5 from the centre; white where x > 0, black where x < 0. The texels either
    // side of the plane x = 0 differ by 1 and are marked. From the centre, a search reads the texel of its
    // own direction first and then (the ray reaching the sphere of radius 5) the same texel again.
    const int n = 64;
    raycache::CdctCube cube(n);
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column) {
                const TexelAddress t{face, column, row};
                cube.store_at(t, raycache::DepthSample{texel_direction(t, n).x > 0.0f ? white : black, 5.0f});
            }
    CHECK(raycache::mark_doubtful_edges(cube, 0.1f) > 0u);
    cube.begin_frame();
    const raycache::CubeBounds bounds{glm::vec3(0.0f), 1.0f};
    raycache::ReliefParameters p;
    p.epsilon = 0.01f;
    // Straight along +Z: the plane x = 0 splits the +Z face between columns 31 and 32, so its texel is one
    // of the two marked ones.
    CHECK_FALSE(raycache::secant_search(cube, bounds, glm::vec3(0.0f), glm::vec3(0, 0, 1), p).hit);
    // 45 degrees towards +X: well inside the white half.
    const raycache::ReliefResult white_side =
        raycache::secant_search(cube, bounds, glm::vec3(0.0f), glm::normalize(glm::vec3(1, 0, 1)), p);
    REQUIRE(white_side.hit);
    CHECK(white_side.color == white);
    CHECK(white_side.distance == doctest::Approx(5.0f).epsilon(0.01));
}
