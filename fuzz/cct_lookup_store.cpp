// Fuzz target: directions to texels, and CCT lookups and stores (plain and filtered) with arbitrary float
// bits, checked against a model of the cube: a store is refused for what is not a direction, a texel that is
// visible keeps its word, same-frame stores to a texel keep the smallest word, a lookup sees a store from the
// next begin_frame() on and returns its colour bit for bit; texel_of and texel_direction invert each other.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>

#include "fuzz_input.hpp"
#include "raycache/raycache.hpp"

namespace {

using raycache::CctCube;
using raycache::CctTexel;
using raycache::TexelAddress;

bool same_bits(const glm::vec3& a, const glm::vec3& b) {
    return glm::floatBitsToUint(a) == glm::floatBitsToUint(b);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    FuzzInput in(data, size);
    // Mostly small faces (fast, many collisions); sometimes any size up to 4096.
    const int n = in.u8() % 32 == 0 ? in.in_range(1, 4096) : in.in_range(1, 40);
    CctCube cube(n);
    std::map<std::size_t, std::uint32_t> visible, pending; // linear index -> word, the model
    for (int op = 0; op < 256 && !in.empty(); ++op) {
        const std::uint8_t what = in.u8() % 5;
        const glm::vec3 d = in.vec3();
        const std::optional<TexelAddress> t = raycache::texel_of(d, n);
        FUZZ_CHECK(t.has_value() == raycache::is_direction(d));
        if (t) {
            FUZZ_CHECK(cube.contains(*t));
            FUZZ_CHECK(raycache::texel_of(raycache::texel_direction(*t, n), n) == *t);
        }
        const std::size_t key = t ? raycache::texel_linear_index(*t, n) : 0;
        if (what == 0 || what == 1) { // store
            const glm::vec3 colour = in.vec3();
            const std::uint32_t word = CctTexel::encode(colour);
            FUZZ_CHECK(CctTexel::is_valid(word));
            bool expected = t.has_value() && !visible.count(key);
            if (expected && pending.count(key)) expected = word < pending[key];
            FUZZ_CHECK(cube.store(d, colour) == expected);
            if (expected) pending[key] = word;
            FUZZ_CHECK(!cube.peek(d).has_value() || visible.count(key)); // not visible in its own frame
        } else if (what == 2) { // lookup
            const std::optional<glm::vec3> got = cube.lookup(d);
            FUZZ_CHECK(got.has_value() == (t && visible.count(key)));
            if (got) FUZZ_CHECK(same_bits(*got, CctTexel::decode(visible[key])));
        } else if (what == 3) { // filtered lookup through cached_trace's filtered twin
            bool traced = false;
            const glm::vec3 traced_colour = in.vec3();
            const glm::vec3 got = raycache::filtered_cached_trace(cube, d, [&] {
                traced = true;
                return traced_colour;
            });
            FUZZ_CHECK(traced == !(t && visible.count(key)));
            if (traced) {
                FUZZ_CHECK(same_bits(got, traced_colour));
                if (t && !pending.count(key)) pending[key] = CctTexel::encode(traced_colour);
                else if (t && CctTexel::encode(traced_colour) < pending[key]) pending[key] = CctTexel::encode(traced_colour);
            } else {
                FUZZ_CHECK(finite3(got) && got.x >= 0.0f && got.y >= 0.0f && got.z >= 0.0f);
                // A weighted mean of stored colours: at most the largest, up to the rounding of weights that
                // sum to 1 (shared/cube_filter.h).
                const float most = 65280.0f * (1.0f + 4.0f * std::numeric_limits<float>::epsilon());
                if (!(got.x <= most && got.y <= most && got.z <= most))
                    std::fprintf(stderr, "filtered (%.9g, %.9g, %.9g)\n", static_cast<double>(got.x), static_cast<double>(got.y),
                                 static_cast<double>(got.z));
                FUZZ_CHECK(got.x <= most && got.y <= most && got.z <= most);
            }
        } else { // end of frame
            cube.begin_frame();
            for (const auto& [k, w] : pending) visible[k] = w;
            pending.clear();
        }
        FUZZ_CHECK(cube.valid_texels() == visible.size() + pending.size());
    }
    std::size_t counted = 0;
    if (n > 64) return 0; // the walk below costs 6 N^2 / 16 tile visits
    cube.for_each_valid_texel([&](const TexelAddress& a) {
        const std::size_t k = raycache::texel_linear_index(a, n);
        const std::uint32_t word = visible.count(k) ? visible[k] : pending.at(k);
        FUZZ_CHECK(cube.load_word(a) == word);
        ++counted;
    });
    FUZZ_CHECK(counted == visible.size() + pending.size());
    return 0;
}
