// raycache/gpu_buffers.hpp: the host side of RayCache's GPU buffers (raycache/shared/gpu_layout.h), with no
// graphics API: where each cube's texels lie in a technique's texel buffer (and its pending twin), how big
// the buffers are, the word they must be filled with, and a C++ cube's texels as GPU words and back. The
// frame buffer, statistics and end-of-frame pass: raycache/gpu_frame.hpp (included).
//
// Every texel and pending buffer must hold gpu_clear_word in every 32-bit word before its first frame
// (vkCmdFillBuffer(cmd, buffer, 0, VK_WHOLE_SIZE, raycache::gpu_clear_word), or fill_gpu_words on mapped
// memory). Zeros are valid texels, black (CCT; the CDCT's at distance 0): a zero-filled cube answers every
// lookup with black and refuses every store, without an error.
//
// The confidence test (shaders that define RAYCACHE_CONFIDENCE) adds, per technique, a doubtful-bit buffer
// (GpuBufferLayout::doubtful_bytes; fill it with gpu_doubtful_clear_word whenever the texel buffers are
// filled) and, for the end-of-frame mark pass, a cube table: GpuBufferLayout::cubes as it stands.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "raycache/cache_cube.hpp"
#include "raycache/cdct.hpp"
#include "raycache/gpu_frame.hpp"
#include "raycache/shared/gpu_layout.h"
#include "raycache/shared/origin_rule.h"

namespace raycache {

// The 32-bit word that empties texel and pending buffers (an empty texel, larger than every stored word).
inline constexpr std::uint32_t gpu_clear_word = RAYCACHE_GPU_CLEAR_WORD;

// 32-bit words per texel in GPU buffers: 1 for the CCT (uint), 2 for the CDCT (uvec2: colour, distance).
template <class Texel>
inline constexpr std::size_t gpu_words_per_texel = sizeof(typename Texel::Word) / sizeof(std::uint32_t);

// One cube to place in a buffer: its face size and (CDCT; the CCT ignores it) its box.
struct GpuCubeShape {
    int face_size = 1;
    CubeBounds bounds{};
};

// Cubes of one technique in one texel buffer and its pending twin, one after another.
struct GpuBufferLayout {
    std::vector<shared::raycache_gpu_cube> cubes; // a descriptor per cube, in the order given: the shader's cube array
    std::uint64_t texels = 0;                     // elements of each buffer: the sum of 6 N^2
    std::uint64_t words = 0;                      // 32-bit words of each buffer
    std::uint64_t bytes = 0;                      // bytes of each buffer (create both this size, fill with gpu_clear_word)
    // The confidence test's doubtful-bit buffer (RAYCACHE_CONFIDENCE): one bit per texel, in uint words;
    // create it this size (at least 4 bytes) and fill it with gpu_doubtful_clear_word. Its cube table is
    // `cubes` as it stands (cubes.size() * sizeof(raycache_gpu_cube) bytes).
    std::uint64_t doubtful_words = 0;
    std::uint64_t doubtful_bytes = 0;
    // The CCT's origin test (RAYCACHE_ORIGINS): a record of RAYCACHE_ORIGIN_RECORD_WORDS words per tile of 16 x
    // 16 texels (raycache/shared/origin_rule.h), cube k's from cubes[k].first_tile on; create the buffer
    // origin_bytes long (at least 4) and fill it with gpu_clear_word whenever the texel buffers are filled.
    // Its tiles also enter the store list: size the list for texels + origin_tiles entries.
    std::uint64_t origin_tiles = 0;
    std::uint64_t origin_words = 0;
    std::uint64_t origin_bytes = 0;
};

// A GPU byte budget for one technique's cubes: the most bytes its texel buffer may take so that the texel
// buffer, its pending twin and the doubtful bits (GpuBufferLayout::doubtful_bytes) together stay within
// `budget_bytes`. Give it (or the device's maxStorageBufferRange, if smaller) to fit_gpu_face_sizes and
// next_gpu_face_sizes as their cap: when the cubes reach it, the largest are lowered until they fit
// (coarser faces, largest first; no cube is dropped). The frame buffer comes on top. With origin_records
// (the CCT's origin test), the origin records are counted too: 64 bytes a tile of up to 16 x 16 texels, at
// most gpu_origin_bytes_per_texel(smallest_face) a texel on faces of smallest_face texels or more.
// Give the smallest face size the cubes may take (adaptive: AdaptiveResolution::min_face_size).
inline constexpr std::uint64_t gpu_origin_bytes_per_texel(int smallest_face) noexcept {
    // 64 ceil(N / 16)^2 / N^2 bytes a texel: 64 / N^2 up to N = 8, and at most 1 from there on (N = 8: one
    // tile of 64 texels; N = 17: 4 tiles of 289; the ratio falls towards 1/4).
    const std::uint64_t n = smallest_face < 1 ? 1 : static_cast<std::uint64_t>(smallest_face);
    return n >= 8 ? 1 : (64 + n * n - 1) / (n * n);
}
template <class Texel>
constexpr std::uint64_t gpu_texel_bytes_within(std::uint64_t budget_bytes, bool origin_records = false, int smallest_face = 8) noexcept {
    // t texels take 8w t bytes, 4 ceil(t / 32) <= t / 8 + 4 bytes of bits and, with origin records, at most
    // c t bytes of those (c = gpu_origin_bytes_per_texel): at most budget when t (64w + 1 + 8c) / 8 <= budget - 4.
    // floor(8 b / d) as 8 floor(b / d) + floor(8 (b mod d) / d), so that no budget overflows it, and the
    // bytes saturate where t texels' would pass 2^64.
    constexpr std::uint64_t w = gpu_words_per_texel<Texel>;
    if (budget_bytes < 4) return 0;
    const std::uint64_t b = budget_bytes - 4, d = 64 * w + 1 + (origin_records ? 8 * gpu_origin_bytes_per_texel(smallest_face) : 0);
    const std::uint64_t t = b / d * 8 + b % d * 8 / d;
    return t > ~std::uint64_t{0} / (4 * w) ? ~std::uint64_t{0} / (4 * w) * (4 * w) : t * 4 * w;
}

// The bytes a layout's buffers take: texels, their pending twin and doubtful bits, and with origin_records
// the origin records (what gpu_texel_bytes_within bounds).
inline std::uint64_t gpu_cube_bytes(const GpuBufferLayout& layout, bool origin_records) noexcept {
    return 2 * layout.bytes + layout.doubtful_bytes + (origin_records ? layout.origin_bytes : 0);
}

// The word that empties a doubtful-bit buffer (no texel doubtful); clear it with the texel buffers.
inline constexpr std::uint32_t gpu_doubtful_clear_word = 0u;

// Places the cubes: cube k's texels start at element sum_{j<k} 6 N_j^2, and its counters in the frame buffer
// are number first_index + k (give the other technique's cubes other numbers), its origin records start at
// record sum_{j<k} 6 ceil(N_j / 16)^2. Throws std::invalid_argument for a face size outside 1..4096 or more
// than 2^30 texels in all (store-list entries keep two flag bits beside an element; a storage buffer of
// 4-byte texels holds no more anyway where maxStorageBufferRange is below 4 GiB).
template <class Texel>
GpuBufferLayout gpu_buffer_layout(const std::vector<GpuCubeShape>& shapes, std::uint32_t first_index = 0) {
    GpuBufferLayout layout;
    for (std::size_t k = 0; k < shapes.size(); ++k) {
        const GpuCubeShape& s = shapes[k];
        if (!is_valid_face_size(s.face_size))
            throw std::invalid_argument("RayCache: GPU cube " + std::to_string(k) + " has face size " +
                                        std::to_string(s.face_size) + "; it must be 1 to 4096");
        const std::uint64_t count = shared::raycache_gpu_cube_texel_count(s.face_size);
        if (layout.texels + count > std::uint64_t{RAYCACHE_FRAME_TILE_ENTRY})
            throw std::invalid_argument("RayCache: GPU cubes 0 to " + std::to_string(k) +
                                        " hold more than 2^30 texels, past what a store-list entry addresses");
        layout.cubes.push_back(shared::raycache_make_gpu_cube(s.bounds.centre, s.bounds.half_size,
                                                              static_cast<std::uint32_t>(layout.texels), s.face_size));
        layout.cubes.back().index = first_index + static_cast<std::uint32_t>(k);
        layout.cubes.back().first_tile = static_cast<std::uint32_t>(layout.origin_tiles);
        layout.texels += count;
        layout.origin_tiles += shared::raycache_origin_tile_count(s.face_size);
        if (layout.origin_tiles * RAYCACHE_ORIGIN_RECORD_WORDS > (std::uint64_t{1} << 32)) // the shaders' uint word index
            throw std::invalid_argument("RayCache: GPU cubes 0 to " + std::to_string(k) + " have more than 2^28 tiles of origin records");
    }
    layout.words = layout.texels * gpu_words_per_texel<Texel>;
    layout.bytes = layout.words * sizeof(std::uint32_t);
    layout.doubtful_words = std::max<std::uint64_t>((layout.texels + 31) / 32, 1);
    layout.doubtful_bytes = layout.doubtful_words * sizeof(std::uint32_t);
    layout.origin_words = std::max<std::uint64_t>(layout.origin_tiles * RAYCACHE_ORIGIN_RECORD_WORDS, 1);
    layout.origin_bytes = layout.origin_words * sizeof(std::uint32_t);
    return layout;
}

// Sets `count` words to gpu_clear_word (mapped or staging memory of a texel or pending buffer).
inline void fill_gpu_words(std::uint32_t* words, std::size_t count) noexcept {
    for (std::size_t i = 0; i < count; ++i) words[i] = gpu_clear_word;
}

// The contents of one of the layout's buffers before its first frame, ready to upload.
inline std::vector<std::uint32_t> cleared_gpu_words(const GpuBufferLayout& layout) {
    return std::vector<std::uint32_t>(static_cast<std::size_t>(layout.words), gpu_clear_word);
}

namespace detail {
// Throws unless `at` describes `cube` and its texels fit in `word_count` words.
template <class Texel>
void check_gpu_face_size(const CacheCube<Texel>& cube, const shared::raycache_gpu_cube& at) {
    if (at.face_size != cube.face_size())
        throw std::invalid_argument("RayCache: a GPU cube of face size " + std::to_string(at.face_size) +
                                    " cannot hold a cube of face size " + std::to_string(cube.face_size()));
}
template <class Texel>
void check_gpu_cube(const CacheCube<Texel>& cube, const shared::raycache_gpu_cube& at, std::size_t word_count) {
    check_gpu_face_size(cube, at);
    const std::uint64_t end = (std::uint64_t{at.first_texel} + cube.texel_count()) * gpu_words_per_texel<Texel>;
    if (end > word_count)
        throw std::invalid_argument("RayCache: a GPU cube ending at word " + std::to_string(end) + " does not fit in " +
                                    std::to_string(word_count) + " words");
}
} // namespace detail

// Writes the texels of `cube` (visible or written this frame; empty ones as gpu_clear_word) into `words`, a
// texel buffer's contents of `word_count` 32-bit words, where descriptor `at` places them. A CDCT texel is two
// words, colour then distance (GLSL's uvec2). Throws std::invalid_argument when `at` has another face size
// or the cube does not fit.
template <class Texel>
void write_gpu_words(const CacheCube<Texel>& cube, const shared::raycache_gpu_cube& at, std::uint32_t* words,
                     std::size_t word_count) {
    detail::check_gpu_cube(cube, at, word_count);
    constexpr std::size_t per_texel = gpu_words_per_texel<Texel>;
    const int n = cube.face_size();
    std::size_t i = static_cast<std::size_t>(at.first_texel) * per_texel;
    for (int face = 0; face < RAYCACHE_FACE_COUNT; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column, i += per_texel) {
                const typename Texel::Word word = cube.load_word(TexelAddress{face, column, row});
                for (std::size_t k = 0; k < per_texel; ++k)
                    words[i + k] = Texel::is_valid(word) ? static_cast<std::uint32_t>(word >> (32 * k)) : gpu_clear_word;
            }
}

// Stores every valid texel found in `words` where descriptor `at` places them into the same texel of `cube`
// (store_word_at: visible after the cube's next begin_frame(); texels the cube already holds are kept).
// Returns how many words were valid. Throws as write_gpu_words.
template <class Texel>
std::size_t read_gpu_words(CacheCube<Texel>& cube, const shared::raycache_gpu_cube& at, const std::uint32_t* words,
                           std::size_t word_count) {
    detail::check_gpu_cube(cube, at, word_count);
    constexpr std::size_t per_texel = gpu_words_per_texel<Texel>;
    const int n = cube.face_size();
    std::size_t valid = 0, i = static_cast<std::size_t>(at.first_texel) * per_texel;
    for (int face = 0; face < RAYCACHE_FACE_COUNT; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column, i += per_texel) {
                typename Texel::Word word = 0;
                for (std::size_t k = 0; k < per_texel; ++k) word |= typename Texel::Word{words[i + k]} << (32 * k);
                if (!Texel::is_valid(word)) continue;
                cube.store_word_at(TexelAddress{face, column, row}, word);
                ++valid;
            }
    return valid;
}

// The element of texel `t` of the cube descriptor `at` places: its index in the texel and doubtful-bit buffers.
inline std::uint32_t gpu_element(const shared::raycache_gpu_cube& at, const TexelAddress& t) noexcept {
    return at.first_texel + static_cast<std::uint32_t>(texel_linear_index(t, at.face_size));
}

// Sets `element`'s bit in a doubtful-bit buffer's contents (`words`, which must hold it): that texel is doubtful.
inline void set_gpu_doubtful(std::uint32_t* words, std::uint32_t element) noexcept {
    words[shared::raycache_doubtful_word(element)] |= shared::raycache_doubtful_bit(element);
}

// Whether `element`'s bit is set in a doubtful-bit buffer's contents (`words`, `word_count` of them, as
// read back): whether that texel is doubtful. False past the buffer's end.
inline bool gpu_doubtful(const std::uint32_t* words, std::size_t word_count, std::uint32_t element) noexcept {
    const std::uint32_t w = shared::raycache_doubtful_word(element);
    return w < word_count && (words[w] & shared::raycache_doubtful_bit(element)) != 0u;
}

namespace detail {
// Throws unless the origin records of a cube placed by `at` fit in `word_count` words.
inline std::size_t first_origin_word(const shared::raycache_gpu_cube& at, std::size_t word_count) {
    const std::uint64_t first = std::uint64_t{at.first_tile} * RAYCACHE_ORIGIN_RECORD_WORDS;
    const std::uint64_t end = first + std::uint64_t{shared::raycache_origin_tile_count(at.face_size)} * RAYCACHE_ORIGIN_RECORD_WORDS;
    if (end > word_count)
        throw std::invalid_argument("RayCache: origin records ending at word " + std::to_string(end) + " do not fit in " +
                                    std::to_string(word_count) + " words");
    return static_cast<std::size_t>(first);
}
// Calls f(first texel of the tile, record's first word) for each tile of a cube of face size n.
template <class F>
void for_each_gpu_tile(int n, std::size_t first_word, F&& f) {
    constexpr int edge = static_cast<int>(RAYCACHE_ORIGIN_TILE_EDGE);
    for (int face = 0; face < RAYCACHE_FACE_COUNT; ++face)
        for (int row = 0; row < n; row += edge)
            for (int column = 0; column < n; column += edge) {
                const TexelAddress first{face, column, row};
                f(first, first_word + std::size_t{shared::raycache_origin_tile_index({face, column, row}, n)} *
                                          RAYCACHE_ORIGIN_RECORD_WORDS);
            }
}
} // namespace detail

// Writes the visible origin boxes and nearest distances of `cube`'s tiles (CacheCube::origin_box,
// nearest_hit) into the origin records `words` (word_count 32-bit words) where descriptor `at` places them,
// as the GPU keeps them between frames; a tile without a box gets clear words. Throws std::invalid_argument
// when `at` has another face size or the records do not fit.
template <class Texel>
void write_gpu_origins(const CacheCube<Texel>& cube, const shared::raycache_gpu_cube& at, std::uint32_t* words,
                       std::size_t word_count) {
    detail::check_gpu_face_size(cube, at);
    detail::for_each_gpu_tile(cube.face_size(), detail::first_origin_word(at, word_count), [&](const TexelAddress& first, std::size_t w) {
        for (std::uint32_t i = 0; i < RAYCACHE_ORIGIN_RECORD_WORDS; ++i) words[w + i] = gpu_clear_word;
        const auto box = cube.origin_box(first);
        if (!box) return;
        for (int k = 0; k < 3; ++k) {
            words[w + RAYCACHE_ORIGIN_LO + k] = shared::raycache_origin_corner_word(box->first[k], false);
            words[w + RAYCACHE_ORIGIN_HI + k] = shared::raycache_origin_corner_word(box->second[k], true);
        }
        const float nearest = cube.nearest_hit(first);
        if (nearest < std::numeric_limits<float>::infinity()) words[w + RAYCACHE_ORIGIN_NEAREST] = shared::raycache_ordered_key(nearest);
    });
}

// The visible origin box of a GPU record (its first word at `record`); std::nullopt when it has none.
inline std::optional<std::pair<glm::vec3, glm::vec3>> gpu_origin_box(const std::uint32_t* record) noexcept {
    if (!shared::raycache_origin_has_box(record[RAYCACHE_ORIGIN_LO])) return std::nullopt;
    const std::uint32_t* lo = record + RAYCACHE_ORIGIN_LO;
    const std::uint32_t* hi = record + RAYCACHE_ORIGIN_HI;
    return std::make_pair(shared::raycache_origin_corner(lo[0], lo[1], lo[2], false), shared::raycache_origin_corner(hi[0], hi[1], hi[2], true));
}

// Sets the origin box and nearest distance of each tile of `cube` that holds a texel from the visible part
// of the records `words` where `at` places them (tiles with no box are left as they are). For reading a
// GPU cube back after read_gpu_words. Throws as write_gpu_origins. Between frames.
template <class Texel>
void read_gpu_origins(CacheCube<Texel>& cube, const shared::raycache_gpu_cube& at, const std::uint32_t* words,
                      std::size_t word_count) {
    detail::check_gpu_face_size(cube, at);
    detail::for_each_gpu_tile(cube.face_size(), detail::first_origin_word(at, word_count), [&](const TexelAddress& first, std::size_t w) {
        if (const auto box = gpu_origin_box(words + w))
            cube.set_origin_box(first, box->first, box->second, shared::raycache_origin_nearest(words[w + RAYCACHE_ORIGIN_NEAREST]));
    });
}

} // namespace raycache
