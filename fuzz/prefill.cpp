// Fuzz target: pre-filling (raycache::prefill) CCT and CDCT cubes with a trace that returns NaN, infinite,
// negative, subnormal and arbitrary distances and colours, and arbitrary boxes and parameters. Checked: each
// texel is traced once, from the box's centre, along a unit direction into that texel; the CCT stores every
// colour; the CDCT stores a texel exactly when it can hold what was traced: nothing for a negative distance
// (a hit behind the centre), max_depth for an escape (infinity or NaN), and never more than max_depth.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_input.hpp"
#include "raycache/raycache.hpp"

namespace {

using raycache::TexelAddress;
using raycache::TracedRay;

struct Call {
    glm::vec3 origin, direction;
    TracedRay answer;
};

// Traces every texel of `cube` through prefill(); returns the calls, in the order made.
template <class Texel>
std::vector<Call> prefill_with(raycache::CacheCube<Texel>& cube, const raycache::CubeBounds& bounds, const raycache::ReliefParameters& p,
                               FuzzInput& in) {
    std::vector<Call> calls;
    const std::size_t stored = raycache::prefill(cube, bounds, p, [&](glm::vec3 origin, glm::vec3 direction) {
        const TracedRay answer{in.vec3(), in.number()};
        calls.push_back({origin, direction, answer});
        return answer;
    });
    FUZZ_CHECK(stored == cube.valid_texels());
    FUZZ_CHECK(calls.size() == cube.texel_count()); // the cube started empty: every texel traced once
    const int n = cube.face_size();
    std::size_t k = 0;
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column, ++k) {
                const Call& c = calls[k];
                FUZZ_CHECK(glm::floatBitsToUint(c.origin) == glm::floatBitsToUint(bounds.centre));
                FUZZ_CHECK(std::abs(glm::length(c.direction) - 1.0f) < 1e-5f);
                FUZZ_CHECK(raycache::texel_of(c.direction, n) == TexelAddress({face, column, row}));
            }
    return calls;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    FuzzInput in(data, size);
    const int n = in.in_range(1, 12);
    const raycache::CubeBounds bounds{in.vec3(), in.number()};
    raycache::ReliefParameters p;
    p.step = in.number();
    p.epsilon = in.number();
    p.max_depth = in.number();
    if (in.u8() & 1) {
        raycache::CctCube cube(n);
        const std::vector<Call> calls = prefill_with(cube, bounds, p, in);
        FUZZ_CHECK(cube.valid_texels() == cube.texel_count()); // every colour can be stored (clamped)
        std::size_t k = 0;
        cube.for_each_valid_texel([&](const TexelAddress& t) {
            FUZZ_CHECK(cube.load_word(t) == raycache::CctTexel::encode(calls[k++].answer.color));
        });
    } else {
        raycache::CdctCube cube(n);
        const std::vector<Call> calls = prefill_with(cube, bounds, p, in);
        const bool depth_storable = p.max_depth >= 0.0f && std::isfinite(p.max_depth);
        std::size_t k = 0;
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column, ++k) {
                    const std::optional<raycache::DepthSample> s = cube.load({face, column, row});
                    const float d = calls[k].answer.distance;
                    if (d < 0.0f) FUZZ_CHECK(!s); // behind the centre: not stored
                    if (std::isnan(d) || d == std::numeric_limits<float>::infinity())
                        FUZZ_CHECK(s.has_value() == depth_storable && (!s || s->distance == p.max_depth + 0.0f));
                    if (s) {
                        FUZZ_CHECK(std::isfinite(s->distance) && s->distance >= 0.0f);
                        if (depth_storable) FUZZ_CHECK(s->distance <= p.max_depth);
                        FUZZ_CHECK(static_cast<std::uint32_t>(cube.load_word({face, column, row})) ==
                                   raycache::CctTexel::encode(calls[k].answer.color));
                    }
                }
    }
    return 0;
}
