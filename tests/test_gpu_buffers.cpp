// raycache/gpu_buffers.hpp: buffer sizes and cube offsets, the fill word, and cubes to GPU words and back,
// against values worked out by hand:
// - 6 N^2 texels a cube: N = 1, 2, 16 hold 6, 24 and 1536, so they start at elements 0, 6 and 30 and the
//   buffer holds 1566 elements: 6264 bytes of CCT words (4 bytes), 12528 of CDCT words (8 bytes).
// - Direction (0, 0, 1) lies on face +Z (4), sc = x = 0, tc = -y = 0, so tu = tv = 0.5 and, for N = 2,
//   column = row = floor(0.5 * 2) = 1: linear index (4 * 2 + 1) * 2 + 1 = 19.
// - RGB9E5 of (1, 0, 0): brightest 1 = 2^0, shared exponent 0 + 16 = 16 (bits 27..31), step 2^(16 - 24) =
//   2^-8, red mantissa 1 / 2^-8 = 256: 16 << 27 | 256 = 0x80000100. Distance 2.5 = 1.25 * 2^1 as float
//   bits: sign 0, exponent 128, mantissa 0.25 * 2^23: 0x40200000.
// - Doubtful bits: one per texel in 32-bit words, ceil(1566 / 32) = 49 words (196 bytes) whatever the
//   technique; element 37 is bit 37 - 32 = 5 of word 1.
#include <doctest/doctest.h>

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "raycache/raycache.hpp"

using namespace raycache;

namespace {

const std::vector<GpuCubeShape> three_cubes = {{1, CubeBounds{glm::vec3(1.0f, 2.0f, 3.0f), 0.5f}}, {2, CubeBounds{}}, {16, CubeBounds{}}};

constexpr std::uint32_t red = 0x80000100u;      // RGB9E5 of (1, 0, 0)
constexpr std::uint32_t two_and_a_half = 0x40200000u; // float bits of 2.5
constexpr std::uint32_t sentinel = 0x12345678u; // words outside a cube's range must keep it

} // namespace

TEST_CASE("gpu_buffer_layout places cubes one after another, 6 N^2 texels each, with 4- or 8-byte words") {
    const GpuBufferLayout cct = gpu_buffer_layout<CctTexel>(three_cubes);
    REQUIRE(cct.cubes.size() == 3);
    CHECK(cct.cubes[0].first_texel == 0u);
    CHECK(cct.cubes[1].first_texel == 6u);
    CHECK(cct.cubes[2].first_texel == 30u);
    CHECK(cct.cubes[2].face_size == 16);
    CHECK(cct.texels == 1566u);
    CHECK(cct.words == 1566u);
    CHECK(cct.bytes == 6264u);
    // The box travels into the descriptor (the CDCT's searches read it); padding is zero.
    CHECK(cct.cubes[0].centre == glm::vec3(1.0f, 2.0f, 3.0f));
    CHECK(cct.cubes[0].half_size == 0.5f);
    // Origin records (the CCT's origin test): one per tile of 16 x 16 texels, 6 t^2 a cube, t = ceil(N / 16).
    CHECK(cct.cubes[0].first_tile == 0u);
    CHECK(cct.cubes[1].first_tile == 6u);
    CHECK(cct.cubes[2].first_tile == 12u);
    CHECK(cct.origin_tiles == 18u);
    CHECK(cct.origin_words == 18u * 16u);
    CHECK(cct.origin_bytes == 18u * 64u);
    // Counters: cube k is number k, or first_index + k.
    CHECK(cct.cubes[0].index == 0u);
    CHECK(cct.cubes[2].index == 2u);
    CHECK(gpu_buffer_layout<CctTexel>(three_cubes, 7).cubes[1].index == 8u);

    const GpuBufferLayout cdct = gpu_buffer_layout<CdctTexel>(three_cubes);
    CHECK(cdct.cubes[2].first_texel == 30u); // elements, not words: a uvec2 is one element
    CHECK(cdct.texels == 1566u);
    CHECK(cdct.words == 3132u);
    CHECK(cdct.bytes == 12528u);
    CHECK(gpu_buffer_layout<CctTexel>({}).bytes == 0u);
}

TEST_CASE("the confidence test's doubtful-bit buffer holds a bit per texel, and gpu_doubtful reads element k's bit") {
    for (const GpuBufferLayout& layout : {gpu_buffer_layout<CctTexel>(three_cubes), gpu_buffer_layout<CdctTexel>(three_cubes)}) {
        CHECK(layout.doubtful_words == 49u);
        CHECK(layout.doubtful_bytes == 196u);
    }
    CHECK(gpu_buffer_layout<CctTexel>({{1, CubeBounds{}}}).doubtful_words == 1u); // 6 texels: one word
    CHECK(gpu_doubtful_clear_word == 0u);
    std::vector<std::uint32_t> words(49, 0u);
    words[1] = 1u << 5;
    CHECK(gpu_doubtful(words.data(), words.size(), 37));
    CHECK_FALSE(gpu_doubtful(words.data(), words.size(), 36));
    CHECK_FALSE(gpu_doubtful(words.data(), words.size(), 5)); // bit 5 of word 0
    CHECK_FALSE(gpu_doubtful(words.data(), 1, 37));           // past the buffer's end
    CHECK(gpu_bindings.cct_doubtful == 5u);
    CHECK(gpu_bindings.cdct_doubtful == 6u);
    CHECK(gpu_bindings.cct_cubes == 7u);
    CHECK(gpu_bindings.cdct_cubes == 8u);
}

TEST_CASE("gpu_buffer_layout refuses face sizes outside 1..4096 and more texels than a store-list entry addresses") {
    CHECK_THROWS_WITH_AS(gpu_buffer_layout<CctTexel>({{4, {}}, {0, {}}}), doctest::Contains("GPU cube 1 has face size 0"),
                         std::invalid_argument);
    CHECK_THROWS_AS(gpu_buffer_layout<CctTexel>({{4097, {}}}), std::invalid_argument);
    // 6 * 4096^2 = 100,663,296 texels a cube: 10 cubes hold 1,006,632,960 < 2^30 = 1,073,741,824; 11 do not.
    const std::vector<GpuCubeShape> largest(10, GpuCubeShape{4096, {}});
    const GpuBufferLayout fits = gpu_buffer_layout<CctTexel>(largest);
    CHECK(fits.texels == 1006632960u);
    CHECK(fits.cubes.back().first_texel == 905969664u);
    CHECK(fits.cubes.back().first_tile == 9u * 6u * 256u * 256u);
    std::vector<GpuCubeShape> too_many = largest;
    too_many.push_back({4096, {}});
    CHECK_THROWS_WITH_AS(gpu_buffer_layout<CctTexel>(too_many), doctest::Contains("2^30"), std::invalid_argument);
}

TEST_CASE("the fill word reads as an empty texel in both techniques, and zeros read as valid black texels") {
    const GpuBufferLayout layout = gpu_buffer_layout<CdctTexel>(three_cubes);
    const std::vector<std::uint32_t> words = cleared_gpu_words(layout);
    REQUIRE(words.size() == 3132u);
    for (std::uint32_t w : words) REQUIRE(w == 0xFFFFFFFFu);
    std::vector<std::uint32_t> filled(5, 0u);
    fill_gpu_words(filled.data(), 4);
    CHECK(filled == std::vector<std::uint32_t>{0xFFFFFFFFu, 0xFFFFFFFFu, 0xFFFFFFFFu, 0xFFFFFFFFu, 0u});

    // The CCT marks empty texels with the all-ones word; a CDCT pair of all-ones words has a distance with
    // its sign bit set (a negative NaN), which no store writes.
    CHECK_FALSE(CctTexel::is_valid(gpu_clear_word));
    CHECK_FALSE(CdctTexel::is_valid(std::uint64_t{gpu_clear_word} << 32 | gpu_clear_word));
    // Why the fill cannot be skipped: zero is RGB9E5 black, and the CDCT's zero pair black at distance 0.
    CHECK(CctTexel::is_valid(0u));
    CHECK(CctTexel::decode(0u) == glm::vec3(0.0f));
    CHECK(CdctTexel::is_valid(0u));
    CHECK(CdctTexel::decode(0u).distance == 0.0f);
}

TEST_CASE("write_gpu_words puts a CCT cube's texels at its descriptor's place, empty ones as the fill word") {
    CctCube cube(2);
    REQUIRE(cube.store(glm::vec3(0.0f, 0.0f, 1.0f), glm::vec3(1.0f, 0.0f, 0.0f))); // written this frame: still written
    const GpuBufferLayout layout = gpu_buffer_layout<CctTexel>(three_cubes);
    std::vector<std::uint32_t> words(layout.words, sentinel);
    write_gpu_words(cube, layout.cubes[1], words.data(), words.size());
    for (std::size_t i = 0; i < words.size(); ++i) {
        CAPTURE(i);
        if (i < 6 || i >= 30)
            CHECK(words[i] == sentinel); // other cubes' words untouched
        else
            CHECK(words[i] == (i == 6 + 19 ? red : 0xFFFFFFFFu));
    }
}

TEST_CASE("write_gpu_words writes a CDCT texel as two words, colour then distance, and read_gpu_words reads it back") {
    CdctCube cube(2);
    REQUIRE(cube.store(glm::vec3(0.0f, 0.0f, 1.0f), DepthSample{glm::vec3(1.0f, 0.0f, 0.0f), 2.5f}));
    const GpuBufferLayout layout = gpu_buffer_layout<CdctTexel>(three_cubes);
    std::vector<std::uint32_t> words(layout.words, sentinel);
    write_gpu_words(cube, layout.cubes[1], words.data(), words.size());
    for (std::size_t i = 0; i < words.size(); ++i) {
        CAPTURE(i);
        if (i < 12 || i >= 60)
            CHECK(words[i] == sentinel);
        else if (i == 2 * (6 + 19))
            CHECK(words[i] == red);
        else if (i == 2 * (6 + 19) + 1)
            CHECK(words[i] == two_and_a_half);
        else
            CHECK(words[i] == 0xFFFFFFFFu);
    }

    CdctCube back(2);
    CHECK(read_gpu_words(back, layout.cubes[1], words.data(), words.size()) == 1u);
    CHECK_FALSE(back.lookup(glm::vec3(0.0f, 0.0f, 1.0f))); // stored, visible next frame
    back.begin_frame();
    const std::optional<DepthSample> texel = back.lookup(glm::vec3(0.0f, 0.0f, 1.0f));
    REQUIRE(texel);
    CHECK(texel->color == glm::vec3(1.0f, 0.0f, 0.0f));
    CHECK(texel->distance == 2.5f);
    CHECK(back.valid_texels() == 1u);
}

TEST_CASE("read_gpu_words of a CCT buffer stores every valid word and skips fill words") {
    const GpuBufferLayout layout = gpu_buffer_layout<CctTexel>(three_cubes);
    std::vector<std::uint32_t> words = cleared_gpu_words(layout);
    words[6 + 19] = red;
    words[6 + 0] = 0u; // black: a valid word
    CctCube cube(2);
    CHECK(read_gpu_words(cube, layout.cubes[1], words.data(), words.size()) == 2u);
    cube.begin_frame();
    CHECK(cube.lookup(glm::vec3(0.0f, 0.0f, 1.0f)) == glm::vec3(1.0f, 0.0f, 0.0f));
    CHECK(cube.load({0, 0, 0}) == glm::vec3(0.0f));
    CHECK(cube.valid_texels() == 2u);
}

TEST_CASE("write_gpu_words and read_gpu_words refuse a descriptor of another face size or past the buffer's end") {
    CctCube cube(2);
    const GpuBufferLayout layout = gpu_buffer_layout<CctTexel>(three_cubes);
    std::vector<std::uint32_t> words = cleared_gpu_words(layout);
    CHECK_THROWS_WITH_AS(write_gpu_words(cube, layout.cubes[2], words.data(), words.size()),
                         doctest::Contains("face size 16"), std::invalid_argument);
    CHECK_THROWS_AS(read_gpu_words(cube, layout.cubes[0], words.data(), words.size()), std::invalid_argument);
    // Cube 1 ends at element 30: 29 words are one short.
    CHECK_THROWS_WITH_AS(write_gpu_words(cube, layout.cubes[1], words.data(), 29), doctest::Contains("does not fit"),
                         std::invalid_argument);
    CHECK_NOTHROW(write_gpu_words(cube, layout.cubes[1], words.data(), 30));
}

// Origin records by hand: a cube of N = 20 has t = 2 tiles a face edge; texels (face 1, column 17, row 3) and
// (1, 18, 4) lie in tile (1 x 2 + 0) x 2 + 1 = 5, so with a cube of N = 1 (6 tiles) before it, record 11,
// words 176..191. Ordered keys set the sign bit of a positive float and complement a negative one:
// 1.0 = 0x3F800000 -> 0xBF800000, -2.0 = 0xC0000000 -> 0x3FFFFFFF, 0.5 -> 0xBF000000, 4.0 -> 0xC0800000;
// upper corners are stored complemented: 1.5 -> ~0xBFC00000 = 0x403FFFFF, -1.0 -> ~0x407FFFFF = 0xBF800000,
// 0.5 -> ~0xBF000000 = 0x40FFFFFF.
TEST_CASE("write_gpu_origins writes a tile's origin box and nearest hit as ordered keys, and read_gpu_origins reads them back") {
    const GpuBufferLayout layout = gpu_buffer_layout<CctTexel>({{1, CubeBounds{}}, {20, CubeBounds{}}});
    REQUIRE(layout.cubes[1].first_tile == 6u);
    REQUIRE(layout.origin_words == (6u + 6u * 4u) * 16u);
    CctCube cube(20);
    REQUIRE(cube.store(texel_direction(TexelAddress{1, 17, 3}, 20), glm::vec3(0.5f), glm::vec3(1.0f, -2.0f, 0.5f), 4.0f));
    REQUIRE(cube.store(texel_direction(TexelAddress{1, 18, 4}, 20), glm::vec3(0.5f), glm::vec3(1.5f, -1.0f, 0.5f), 6.0f));
    cube.begin_frame();
    std::vector<std::uint32_t> records(static_cast<std::size_t>(layout.origin_words), sentinel);
    write_gpu_origins(cube, layout.cubes[1], records.data(), records.size());
    const std::uint32_t expected[16] = {0xBF800000u, 0x3FFFFFFFu, 0xBF000000u, 0x403FFFFFu, 0xBF800000u, 0x40FFFFFFu,
                                        0xC0800000u, gpu_clear_word, gpu_clear_word, gpu_clear_word, gpu_clear_word,
                                        gpu_clear_word, gpu_clear_word, gpu_clear_word, gpu_clear_word, gpu_clear_word};
    for (std::size_t w = 0; w < 16; ++w) {
        CAPTURE(w);
        CHECK(records[176 + w] == expected[w]);
    }
    for (std::size_t w = 96; w < records.size(); ++w)
        if (w < 176 || w >= 192) CHECK(records[w] == gpu_clear_word); // the cube's other tiles: no box
    for (std::size_t w = 0; w < 96; ++w) CHECK(records[w] == sentinel); // cube 0's records are left alone

    CctCube back(20);
    std::vector<std::uint32_t> words(static_cast<std::size_t>(layout.words), gpu_clear_word);
    write_gpu_words(cube, layout.cubes[1], words.data(), words.size());
    read_gpu_words(back, layout.cubes[1], words.data(), words.size());
    read_gpu_origins(back, layout.cubes[1], records.data(), records.size());
    back.begin_frame();
    const auto box = back.origin_box(TexelAddress{1, 17, 3});
    REQUIRE(box);
    CHECK(box->first == glm::vec3(1.0f, -2.0f, 0.5f));
    CHECK(box->second == glm::vec3(1.5f, -1.0f, 0.5f));
    CHECK(back.nearest_hit(TexelAddress{1, 17, 3}) == 4.0f);
    CHECK_FALSE(back.origin_box(TexelAddress{1, 0, 0}));
    CHECK_THROWS_AS(write_gpu_origins(cube, layout.cubes[0], records.data(), records.size()), std::invalid_argument);
    CHECK_THROWS_WITH_AS(write_gpu_origins(cube, layout.cubes[1], records.data(), 191), doctest::Contains("do not fit"),
                         std::invalid_argument);
}
