// raycache/texel.hpp: what a texel type must provide, and the two that RayCache ships (CCT and CDCT).
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <atomic>
#include <cstdint>
#include <type_traits>

#include <glm/glm.hpp>

#include "raycache/shared/cdct_store.h"
#include "raycache/shared/texel_encoding.h"

namespace raycache {

// A Texel type tells CacheCube<Texel> how one texel is packed into a machine word.
// Bring your own by providing exactly this (checked by static_assert in CacheCube):
//
//   struct MyTexel {
//       using Word = std::uint32_t;                  // or std::uint64_t; std::atomic<Word> must be lock-free
//       using Value = ...;                           // what lookups return and stores take
//       static constexpr Word invalid = ...;         // every texel starts as this word
//       static bool is_valid(Word) noexcept;         // false for `invalid`
//       static Word encode(const Value&) noexcept;   // a valid word, or `invalid` when the value can't be stored
//       static Value decode(Word) noexcept;          // called on valid words only
//   };
//
// When several stores reach one texel in the same frame, the smallest Word wins (so the result does not
// depend on thread timing): pick an encoding whose integer order means something.
template <class Texel>
struct TexelTraits {
    using Word = typename Texel::Word;
    using Value = typename Texel::Value;
    static_assert(std::is_same_v<Word, std::uint32_t> || std::is_same_v<Word, std::uint64_t>,
                  "RayCache Texel::Word must be std::uint32_t or std::uint64_t");
    static_assert(std::atomic<Word>::is_always_lock_free,
                  "RayCache Texel::Word must be lock-free as std::atomic on this platform");
    static_assert(std::is_same_v<decltype(Texel::invalid), const Word>,
                  "RayCache Texel needs `static constexpr Word invalid`");
    static_assert(std::is_same_v<decltype(Texel::is_valid(Word{})), bool>,
                  "RayCache Texel needs `static bool is_valid(Word)`");
    static_assert(std::is_same_v<decltype(Texel::encode(std::declval<const Value&>())), Word>,
                  "RayCache Texel needs `static Word encode(const Value&)`");
    static_assert(std::is_same_v<decltype(Texel::decode(Word{})), Value>,
                  "RayCache Texel needs `static Value decode(Word)`");
    static_assert(std::is_copy_constructible_v<Value>, "RayCache Texel::Value must be copyable");
};

// CCT texel: the colour a ray brought back, 4 bytes (RGB9E5, see shared/texel_encoding.h).
// Colour error after a round trip: at most 2^-9 * 1024/1023 of the brightest channel; channels clamp
// to [0, 65280].
struct CctTexel {
    using Word = std::uint32_t;
    using Value = glm::vec3;
    static constexpr Word invalid = RAYCACHE_CCT_INVALID;
    static bool is_valid(Word word) noexcept { return shared::raycache_cct_is_valid(word); }
    static Word encode(const Value& color) noexcept { return shared::raycache_pack_rgb9e5(color); }
    static Value decode(Word word) noexcept { return shared::raycache_unpack_rgb9e5(word); }
};

// What a CDCT texel holds: the colour seen from the cube's centre and the distance to where it was seen.
struct DepthSample {
    glm::vec3 color{0.0f};
    float distance = -1.0f;
};

// CDCT texel: RGB9E5 colour + float32 distance from the centre, 8 bytes (see shared/texel_encoding.h).
// The distance is in the high half, so among same-frame stores into one texel the nearest surface wins.
// Distances must be finite and >= 0; anything else encodes as invalid. Distance error: none (float32).
struct CdctTexel {
    using Word = std::uint64_t;
    using Value = DepthSample;
    static constexpr Word invalid = Word{RAYCACHE_CDCT_INVALID_DISTANCE} << 32 | RAYCACHE_CDCT_INVALID_COLOR;

    static shared::uvec2 to_pair(Word word) noexcept {
        return shared::uvec2(static_cast<std::uint32_t>(word), static_cast<std::uint32_t>(word >> 32));
    }
    static Word from_pair(shared::uvec2 pair) noexcept { return Word{pair.y} << 32 | pair.x; }

    static bool is_valid(Word word) noexcept { return shared::raycache_cdct_is_valid(to_pair(word)); }
    static Word encode(const Value& sample) noexcept {
        return from_pair(shared::raycache_cdct_store_texel(sample.color, sample.distance)); // the GLSL store's rule
    }
    static Value decode(Word word) noexcept {
        const shared::uvec2 pair = to_pair(word);
        return DepthSample{shared::raycache_cdct_color(pair), shared::raycache_cdct_distance(pair)};
    }
};

} // namespace raycache
