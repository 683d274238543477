// Fuzz target: the CDCT's relief search and stores with arbitrary origins, directions, boxes, parameters and
// texel contents, with and without the DepthPyramid. Checked: every search ends, reads at most
// 1 + min(max_steps, RAYCACHE_MAX_RELIEF_STEPS) + 64 texels or nodes (none when its input is refused), counts
// one lookup, and a hit's colour is one an RGB9E5 word can hold (finite, non-negative); cdct_cached_trace returns the
// trace's colour bit for bit on a miss and never stores an invalid texel; a pyramid kept up to date with
// update() equals one rebuilt from the cube.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "fuzz_input.hpp"
#include "raycache/raycache.hpp"

namespace {

using raycache::CdctCube;
using raycache::CdctTexel;
using raycache::DepthPyramid;
using raycache::TexelAddress;

void check_same(const DepthPyramid& a, const DepthPyramid& b) {
    FUZZ_CHECK(a.levels() == b.levels());
    for (int level = 1; level <= a.levels(); ++level)
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < a.blocks(level); ++row)
                for (int column = 0; column < a.blocks(level); ++column)
                    FUZZ_CHECK(glm::floatBitsToUint(a.min_distance(face, level, column, row)) ==
                               glm::floatBitsToUint(b.min_distance(face, level, column, row)));
}

// What an RGB9E5 word can hold: channels in [0, 511 * 2^7] (the encoder stops at 65280, but words stored
// with store_word_at may use the whole range).
bool storable_colour(const glm::vec3& c) {
    const float most = 65408.0f;
    return finite3(c) && c.x >= 0.0f && c.y >= 0.0f && c.z >= 0.0f && c.x <= most && c.y <= most && c.z <= most;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    FuzzInput in(data, size);
    const int n = in.u8() % 16 == 0 ? in.in_range(1, 48) : in.in_range(1, 16);
    CdctCube cube(n);
    const bool use_pyramid = in.u8() & 1;
    DepthPyramid kept(n);

    // Texel contents: a constant distance everywhere (a closed room), or arbitrary words, or both.
    const std::uint8_t fill = in.u8();
    if (fill & 1) {
        const float distance = in.number();
        const glm::vec3 colour = in.vec3();
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column) cube.store_at({face, column, row}, raycache::DepthSample{colour, distance});
    }
    for (int k = in.u8(); k > 0 && !in.empty(); --k) {
        const TexelAddress t{in.in_range(0, 5), in.in_range(0, n - 1), in.in_range(0, n - 1)};
        const std::uint64_t word = in.u64();
        const bool expected = CdctTexel::is_valid(word) && cube.load_word(t) > word; // all of this frame: smaller wins
        FUZZ_CHECK(cube.store_word_at(t, word) == expected);
    }
    kept.update(cube);
    cube.begin_frame();

    for (int op = 0; op < 16 && !in.empty(); ++op) {
        raycache::CubeBounds bounds{in.vec3(), in.number()};
        raycache::ReliefParameters p;
        p.step = in.number();
        p.epsilon = in.number();
        // Mostly up to a few thousand (searches that fast keep the fuzzer fast), sometimes any int: up to
        // RAYCACHE_MAX_RELIEF_STEPS reads, about a second a search here, or refused above it.
        p.max_steps = in.u8() % 8 == 0 ? static_cast<int>(in.u32()) : in.in_range(-2, 4096);
        p.max_depth = in.number();
        p.max_gap = in.number();
        const glm::vec3 origin = in.vec3(), direction = in.vec3();
        const std::uint64_t lookups = cube.statistics().lookups;
        const std::uint8_t what = in.u8() % 3;
        if (what == 0) {
            const raycache::ReliefResult r = raycache::relief_search(cube, bounds, origin, direction, p, use_pyramid ? &kept : nullptr);
            const long long bound = 1 + std::min<long long>(std::max(p.max_steps, 0), RAYCACHE_MAX_RELIEF_STEPS) + 64;
            FUZZ_CHECK(r.texels_read >= 0 && r.texels_read <= bound);
            if (r.hit) FUZZ_CHECK(storable_colour(r.color));
        } else {
            raycache::TracedRay traced{in.vec3(), in.number()};
            int read = -1;
            bool called = false;
            const std::size_t valid_before = cube.valid_texels();
            const glm::vec3 got = raycache::cdct_cached_trace(
                cube, bounds, origin, direction, p,
                [&] {
                    called = true;
                    return traced;
                },
                &read, use_pyramid ? &kept : nullptr);
            FUZZ_CHECK(read >= 0);
            if (called) FUZZ_CHECK(glm::floatBitsToUint(got) == glm::floatBitsToUint(traced.color));
            else FUZZ_CHECK(storable_colour(got));
            if (!called || traced.distance < 0.0f) FUZZ_CHECK(cube.valid_texels() == valid_before);
        }
        FUZZ_CHECK(cube.statistics().lookups == lookups + 1);
        if (in.u8() % 4 == 0) { // end the frame: the kept pyramid must match a rebuilt one
            kept.update(cube);
            cube.begin_frame();
            DepthPyramid rebuilt(n);
            rebuilt.rebuild(cube);
            check_same(kept, rebuilt);
        }
    }
    cube.for_each_valid_texel([&](const TexelAddress& t) {
        const raycache::DepthSample s = *cube.load(t);
        FUZZ_CHECK(std::isfinite(s.distance) && s.distance >= 0.0f && !std::signbit(s.distance));
        FUZZ_CHECK(storable_colour(s.color));
    });
    return 0;
}
