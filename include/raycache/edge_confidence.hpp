// raycache/edge_confidence.hpp: the CCT's confidence test. A texel holds one ray's colour and answers
// every ray that falls in it; where the surroundings change within a texel (a checker edge, a sphere's
// rim seen in the mirror) that answer is often the wrong side of the edge, and those pixels carry most
// of a cached frame's error. So texels whose colour differs from a filled neighbour's by more than a
// threshold are marked doubtful (CacheCube::set_doubtful): their rays are traced, the rest are answered.
//
// Marks only ever need setting: a visible texel's value does not change until clear() or invalidate(),
// so each pair of neighbours is compared once, when the second of them is stored. The test compares
// neighbours on the same face (a texel on a face's edge is not compared across it).
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <cstddef>
#include <optional>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"
#include "raycache/shared/edge_rule.h"

namespace raycache {

// True when two cached colours differ by more than `threshold` in some channel (linear radiance); the rule
// lives in raycache/shared/edge_rule.h, which the GPU's mark pass (raycache/end_frame.glsl) compiles too.
inline bool colours_differ(const glm::vec3& a, const glm::vec3& b, float threshold) noexcept {
    return shared::raycache_colours_differ(a, b, threshold);
}

// The colour a texel value carries: a CCT texel is one, a CDCT texel holds one beside its distance.
inline const glm::vec3& colour_of(const glm::vec3& color) noexcept { return color; }
inline const glm::vec3& colour_of(const DepthSample& sample) noexcept { return sample.color; }

// mark_doubtful_edges() for the texels written in bands [first, last) of the cube (CacheCube::tile_bands())
// alone, to spread one cube's test over threads: calls on disjoint bands may run at once (a mark is an
// atomic bit set, and which texels end up marked does not depend on the order of the tests). Call
// cube.settle_budget() before the first band.
template <class Texel>
void mark_doubtful_edges_in_bands(CacheCube<Texel>& cube, float threshold, int first, int last) {
    if (!shared::raycache_edge_test_enabled(threshold)) return;
    const int n = cube.face_size();
    cube.for_each_written_texel_in_bands(first, last, [&](const TexelAddress& t) {
        const auto own = cube.load(t);
        if (!own) return;
        const TexelAddress neighbours[4] = {{t.face, t.column - 1, t.row}, {t.face, t.column + 1, t.row},
                                            {t.face, t.column, t.row - 1}, {t.face, t.column, t.row + 1}};
        for (const TexelAddress& other : neighbours) {
            if (!is_on_cube(other, n)) continue;
            const auto value = cube.load(other);
            if (value && colours_differ(colour_of(*own), colour_of(*value), threshold)) {
                cube.set_doubtful(t);
                cube.set_doubtful(other);
            }
        }
    });
}

// Marks doubtful every texel written this frame, and every filled neighbour of one (left, right, up,
// down on its face), whose colours differ by more than `threshold`. Call it between frames, before the
// cube's begin_frame() (it reads the frame's written texels). Returns the texels newly marked.
// threshold < 0 (or NaN): nothing is marked. Works on CCT and CDCT cubes alike: a CDCT texel holds one
// ray's colour at one point, and a search answered at a point near a colour edge (a checker line seen in
// the mirror) gets the wrong side as often as a CCT lookup does; its doubtful texels read as empty, so
// such searches miss and are traced.
template <class Texel>
std::size_t mark_doubtful_edges(CacheCube<Texel>& cube, float threshold) {
    if (!shared::raycache_edge_test_enabled(threshold)) return 0;
    cube.settle_budget(); // which new tiles the frame keeps must not depend on thread timing
    const std::size_t before = cube.doubtful_texels();
    mark_doubtful_edges_in_bands(cube, threshold, 0, cube.tile_bands());
    return cube.doubtful_texels() - before;
}

} // namespace raycache
