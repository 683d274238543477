// Fuzz target: the texel encodings (shared/texel_encoding.h). RGB9E5: every colour encodes to a valid
// word whose colour is within the documented error of the clamped input (max(r, g, b) * 2^-9 * 1024/1023, or
// 2^-25 below 2^-16), decodes to finite channels in [0, 65280], and encodes again to the same word; every word
// but the invalid one is valid. CDCT: a texel is valid exactly when its distance is a non-negative finite
// float, keeps the distance bit for bit (-0 stored as +0) and the colour as the CCT does.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "raycache/raycache.hpp"

namespace {

using raycache::CctTexel;
using raycache::CdctTexel;

float storable(float x) {
    if (std::isnan(x)) return 0.0f;
    return std::min(std::max(x, 0.0f), 65280.0f);
}

void check_colour(const glm::vec3& colour) {
    const std::uint32_t word = CctTexel::encode(colour);
    FUZZ_CHECK(CctTexel::is_valid(word));
    const glm::vec3 back = CctTexel::decode(word);
    const glm::vec3 clamped(storable(colour.x), storable(colour.y), storable(colour.z));
    const double brightest = std::max({clamped.x, clamped.y, clamped.z});
    const double allowed = brightest < std::ldexp(1.0, -16) ? std::ldexp(1.0, -25) : brightest * std::ldexp(1.0, -9) * 1024.0 / 1023.0;
    for (int c = 0; c < 3; ++c) {
        FUZZ_CHECK(std::isfinite(back[c]) && back[c] >= 0.0f && back[c] <= 65280.0f);
        if (!(std::abs(static_cast<double>(back[c]) - clamped[c]) <= allowed)) {
            std::fprintf(stderr, "colour (%a, %a, %a) -> word %08x -> (%a, %a, %a): channel %d off by %g, allowed %g\n",
                         static_cast<double>(colour.x), static_cast<double>(colour.y), static_cast<double>(colour.z), word,
                         static_cast<double>(back.x), static_cast<double>(back.y), static_cast<double>(back.z), c,
                         std::abs(static_cast<double>(back[c]) - clamped[c]), allowed);
            FUZZ_CHECK(false);
        }
    }
    FUZZ_CHECK(CctTexel::encode(back) == word); // decoded colours are fixed points of the encoder
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    FuzzInput in(data, size);
    while (!in.empty()) {
        const glm::vec3 colour = in.vec3();
        check_colour(colour);

        const std::uint32_t word = in.u32(); // any word
        FUZZ_CHECK(CctTexel::is_valid(word) == (word != RAYCACHE_CCT_INVALID));
        const glm::vec3 decoded = CctTexel::decode(word);
        FUZZ_CHECK(finite3(decoded) && decoded.x >= 0.0f && decoded.y >= 0.0f && decoded.z >= 0.0f);

        const float distance = in.number();
        const std::uint64_t cdct = CdctTexel::encode(raycache::DepthSample{colour, distance});
        const bool valid = std::isfinite(distance) && distance >= 0.0f;
        FUZZ_CHECK(CdctTexel::is_valid(cdct) == valid);
        if (valid) {
            const raycache::DepthSample s = CdctTexel::decode(cdct);
            FUZZ_CHECK(glm::floatBitsToUint(s.distance) == glm::floatBitsToUint(distance + 0.0f));
            FUZZ_CHECK(static_cast<std::uint32_t>(cdct) == CctTexel::encode(colour));
            FUZZ_CHECK(glm::floatBitsToUint(s.color) == glm::floatBitsToUint(CctTexel::decode(CctTexel::encode(colour))));
        } else {
            FUZZ_CHECK(cdct == CdctTexel::invalid);
        }
        const std::uint64_t any = in.u64();
        const float high = FuzzInput::bits(static_cast<std::uint32_t>(any >> 32));
        FUZZ_CHECK(CdctTexel::is_valid(any) == (std::isfinite(high) && !std::signbit(high)));
        if (CdctTexel::is_valid(any)) FUZZ_CHECK(glm::floatBitsToUint(CdctTexel::decode(any).distance) == any >> 32);
    }
    return 0;
}
