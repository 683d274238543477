// raycache/gpu_adaptive.hpp and raycache/shared/coverage.h: the direction cells GPU lookups mark, each GPU
// cube's next face size from a frame's counters, and the cubes moved into a layout of new sizes. Expected
// values are worked by hand:
// - cells: (1, 0, 0) falls on +X at tu = tv = 0.5, cell (8, 8) = (0 * 16 + 8) * 16 + 8 = 136; (0, 0, -1) on -Z
//   at (8, 8): (5 * 16 + 8) * 16 + 8 = 1416; (1, 0, -0.5) on +X at sc = 0.5, tu = 0.75: column 12, cell 140;
//   (0, 1, 0.999) on +Y at tc = 0.999, tv = 0.9995: row 15, column 8: (2 * 16 + 15) * 16 + 8 = 760.
// - sizes: 6144 rays over 256 of the 1536 cells (a sixth) want sqrt(6144 / (6 / 6)) = 78.4 texels; the ladder
//   steps around it are 64 (0.29 octave away) and 91 (0.21): 91. The next frame, 24 rays over the same cells
//   want 4.9: more than two half octaves from 91, so the nearest step at or above the minimum, 8.
// - moving 24 -> 8 (3 fine texels a coarse one along each edge): the coarse texel (c, r) takes the fine
//   texel (3c + 1, 3r + 1), whose centre is its centre. A kept 16-texel cube after a 24-texel one starts at
//   element 6 * 576 = 3456, after an 8-texel one at 6 * 64 = 384.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "raycache/raycache.hpp"

using namespace raycache;

namespace {

// A frame's statistics with `rays` lookups on cube `index` and its first `cells` coverage cells marked.
GpuFrameStatistics frame_with(std::size_t cubes, std::uint32_t index, std::uint64_t rays, int cells) {
    GpuFrameStatistics f;
    f.cubes.resize(cubes);
    f.coverage.assign(cubes, 0.0);
    f.cubes[index].lookups = rays;
    f.cubes[index].misses = rays;
    f.coverage[index] = static_cast<double>(cells) / RAYCACHE_COVERAGE_CELLS;
    return f;
}

// A CCT colour for fine texel `t`: its column and row, so the texel a coarse one took can be read back.
glm::vec3 colour_of_texel(const TexelAddress& t) {
    return glm::vec3(static_cast<float>(t.column) / 32.0f, static_cast<float>(t.row) / 32.0f, static_cast<float>(t.face) / 8.0f);
}

} // namespace

TEST_CASE("a direction's coverage cell is its texel on a 16-texel face, by hand") {
    CHECK(shared::raycache_coverage_cell(glm::vec3(1, 0, 0)) == 136u);
    CHECK(shared::raycache_coverage_cell(glm::vec3(0, 0, -1)) == 1416u);
    CHECK(shared::raycache_coverage_cell(glm::vec3(1, 0, -0.5f)) == 140u);
    CHECK(shared::raycache_coverage_cell(glm::vec3(0, 1, 0.999f)) == 760u);
    CHECK(shared::raycache_coverage_cell(glm::vec3(0, 0, 0)) == RAYCACHE_NO_COVERAGE_CELL);
    CHECK(shared::raycache_coverage_cell(glm::vec3(std::nanf(""), 1, 0)) == RAYCACHE_NO_COVERAGE_CELL);
    // The integer form for texels of larger faces: texel (13, 2) of a 32-texel +X face has its centre at
    // tu = 13.5 / 32 = 0.42, tv = 2.5 / 32 = 0.078: cell (6, 1) = 16 + 6 = 22, as its centre direction says.
    CHECK(shared::raycache_coverage_cell_of_texel({0, 13, 2}, 32) == 22u);
    for (int n : {16, 32, 64, 256})
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; row += 3)
                for (int column = 0; column < n; column += 5) {
                    const TexelAddress t{face, column, row};
                    CHECK(shared::raycache_coverage_cell_of_texel({face, column, row}, n) ==
                          shared::raycache_coverage_cell(texel_direction(t, n)));
                }
    // The frame buffer keeps 48 words of cells per cube after its 5 counters, its resting word and its count
    // of misses on empty texels.
    CHECK(RAYCACHE_FRAME_CUBE_WORDS == 55u);
    CHECK(shared::raycache_frame_coverage_word(2, 47) == 8u + 2u * 55u + 7u + 47u);
}

TEST_CASE("GPU cubes take the face size their rays call for: at once the first time, then with hysteresis") {
    const GpuBufferLayout layout = gpu_buffer_layout<CctTexel>({GpuCubeShape{256, {}}, GpuCubeShape{32, {}}});
    std::vector<bool> sized(2, false);
    AdaptiveResolution a;
    // Cube 0 (counters index 0) got 6144 rays over a sixth of the cells; cube 1 none: it waits at the
    // smallest size, 8.
    const GpuFaceSizes first = next_gpu_face_sizes<CctTexel>(a, layout, frame_with(2, 0, 6144, 256), sized, ~std::uint64_t{0});
    CHECK(first.face_sizes == std::vector<int>{91, 8});
    CHECK(first.changed);
    CHECK(sized == std::vector<bool>{true, false});
    // Its first rays: 600 over 100 cells want sqrt(600 / (6 * 100 / 1536)) = 39.2 texels: 45 (0.2 octave)
    // rather than 32 (0.29), at once.
    const GpuBufferLayout at_8 = gpu_buffer_layout<CctTexel>({GpuCubeShape{91, {}}, GpuCubeShape{8, {}}});
    GpuFrameStatistics both = frame_with(2, 0, 6144, 256);
    both.cubes[1].lookups = 600;
    both.coverage[1] = 100.0 / RAYCACHE_COVERAGE_CELLS;
    std::vector<bool> after_first = sized;
    CHECK(next_gpu_face_sizes<CctTexel>(a, at_8, both, after_first, ~std::uint64_t{0}).face_sizes == std::vector<int>{91, 45});
    CHECK(after_first == std::vector<bool>{true, true});
    // Sized now: the same rays keep it; a frame with few rays moves it to the smallest step; a sized cube
    // that gets no ray in a frame keeps its size.
    const GpuBufferLayout at_91 = gpu_buffer_layout<CctTexel>({GpuCubeShape{91, {}}, GpuCubeShape{8, {}}});
    const GpuFaceSizes same = next_gpu_face_sizes<CctTexel>(a, at_91, frame_with(2, 0, 6144, 256), sized, ~std::uint64_t{0});
    CHECK(same.face_sizes == std::vector<int>{91, 8});
    CHECK_FALSE(same.changed);
    const GpuFaceSizes few = next_gpu_face_sizes<CctTexel>(a, at_91, frame_with(2, 0, 24, 256), sized, ~std::uint64_t{0});
    CHECK(few.face_sizes == std::vector<int>{8, 8});
    const GpuFaceSizes none = next_gpu_face_sizes<CctTexel>(a, at_91, frame_with(2, 1, 0, 0), sized, ~std::uint64_t{0});
    CHECK(none.face_sizes == std::vector<int>{91, 8});
    // A buffer too small for 91 and 32: the largest faces are lowered until both fit (fit_gpu_face_sizes):
    // 6 * (40^2 + 32^2) * 4 = 62,976 bytes fit a cap of 40 (41: 6 * (1681 + 1024) * 4 = 64,920).
    std::vector<bool> fresh(2, true);
    const GpuFaceSizes capped = next_gpu_face_sizes<CctTexel>(a, layout, frame_with(2, 0, 6144, 256), fresh, 62976);
    CHECK(capped.face_sizes == std::vector<int>{40, 32});
    // A cube the cap holds below its size (40, wanting 24,576 rays over a sixth of the cells: 156.8 -> 181)
    // does not grow by a few texels when the cap moves up a little (42: 6 * (42^2 + 32^2) * 4 = 66,912
    // bytes; 43 would need 68,952), which would empty it; a cap two half octaves up (80: 178,176 bytes; 81
    // would need 182,040) lets it grow.
    const GpuBufferLayout capped_at_40 = gpu_buffer_layout<CctTexel>({GpuCubeShape{40, {}}, GpuCubeShape{32, {}}});
    std::vector<bool> both_sized(2, true);
    const GpuFaceSizes small_rise = next_gpu_face_sizes<CctTexel>(a, capped_at_40, frame_with(2, 0, 24576, 256), both_sized, 66912);
    CHECK(small_rise.face_sizes == std::vector<int>{40, 32});
    CHECK_FALSE(small_rise.changed);
    const GpuFaceSizes big_rise = next_gpu_face_sizes<CctTexel>(a, capped_at_40, frame_with(2, 0, 24576, 256), both_sized, 178176);
    CHECK(big_rise.face_sizes == std::vector<int>{80, 32});
    // Bad input: flags for another number of cubes, a descriptor whose counters the frame does not have.
    std::vector<bool> wrong(3, false);
    CHECK_THROWS_AS(next_gpu_face_sizes<CctTexel>(a, layout, frame_with(2, 0, 1, 1), wrong, ~std::uint64_t{0}), std::invalid_argument);
    CHECK_THROWS_AS(next_gpu_face_sizes<CctTexel>(a, layout, frame_with(1, 0, 1, 1), sized, ~std::uint64_t{0}), std::invalid_argument);
    // A frame started without marking cells (fixed face sizes) cannot size cubes: an error, not a cube that
    // never adapts. Its statistics say so, read from the start words' flags.
    const GpuFrameLayout frame2 = gpu_frame_layout(2, 10);
    CHECK(read_gpu_statistics(gpu_frame_start_words(frame2).data(), frame2).coverage_marked);
    const GpuFrameStatistics unmarked = read_gpu_statistics(gpu_frame_start_words(frame2, false).data(), frame2);
    CHECK_FALSE(unmarked.coverage_marked);
    CHECK_THROWS_AS(next_gpu_face_sizes<CctTexel>(a, layout, unmarked, sized, ~std::uint64_t{0}), std::invalid_argument);
}

TEST_CASE("moving GPU cubes copies a kept size, resamples a smaller one and tests its edges, and empties a larger one") {
    // Old: 24 (shrinks to 8), 16 (kept, moving from element 3456 to 384), 8 (grows to 16).
    const GpuBufferLayout from = gpu_buffer_layout<CctTexel>({GpuCubeShape{24, {}}, GpuCubeShape{16, {}}, GpuCubeShape{8, {}}});
    const GpuBufferLayout to = gpu_buffer_layout<CctTexel>({GpuCubeShape{8, {}}, GpuCubeShape{16, {}}, GpuCubeShape{16, {}}});
    REQUIRE(from.cubes[1].first_texel == 3456u);
    REQUIRE(to.cubes[1].first_texel == 384u);
    CctCube kept(16), shrinking(24), growing(8);
    for (int face = 0; face < 6; ++face) {
        for (int row = 0; row < 16; row += 2)
            for (int column = 0; column < 16; column += 3) kept.store_at(TexelAddress{face, column, row}, colour_of_texel({face, column, row}));
        for (int row = 0; row < 24; ++row)
            for (int column = 0; column < 24; ++column) // a colour edge between fine columns 11 and 12
                shrinking.store_at(TexelAddress{face, column, row}, column < 12 ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0));
        growing.store_at(TexelAddress{face, 3, 3}, glm::vec3(1));
    }
    for (CctCube* c : {&kept, &shrinking, &growing}) c->begin_frame();
    REQUIRE(kept.set_doubtful(TexelAddress{1, 3, 2}));
    std::vector<std::uint32_t> words = cleared_gpu_words(from), doubtful(from.doubtful_words, 0u);
    write_gpu_words(shrinking, from.cubes[0], words.data(), words.size());
    write_gpu_words(kept, from.cubes[1], words.data(), words.size());
    write_gpu_words(growing, from.cubes[2], words.data(), words.size());
    const std::uint32_t marked = from.cubes[1].first_texel + static_cast<std::uint32_t>(texel_linear_index({1, 3, 2}, 16));
    doubtful[shared::raycache_doubtful_word(marked)] |= shared::raycache_doubtful_bit(marked);

    std::vector<std::uint32_t> new_words = cleared_gpu_words(to), new_doubtful(to.doubtful_words, 0u);
    const std::size_t written =
        move_gpu_cubes<CctTexel>(from, words.data(), doubtful.data(), to, new_words.data(), new_doubtful.data(), 0.1f);
    CHECK(written == kept.valid_texels() + 6u * 8u * 8u);

    // Kept: word for word at its new place, its doubtful bit too.
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < 16; ++row)
            for (int column = 0; column < 16; ++column) {
                const TexelAddress t{face, column, row};
                const std::uint32_t e = to.cubes[1].first_texel + static_cast<std::uint32_t>(texel_linear_index(t, 16));
                CHECK(new_words[e] == kept.load_word(t));
                CHECK(gpu_doubtful(new_doubtful.data(), new_doubtful.size(), e) == (face == 1 && column == 3 && row == 2));
            }
    // Shrunk: coarse (c, r) holds fine (3c + 1, 3r + 1): red for c <= 3 (fine column <= 10), green from c = 4
    // (fine 13); the edge between coarse columns 3 and 4 is marked doubtful on both sides, nothing else.
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < 8; ++row)
            for (int column = 0; column < 8; ++column) {
                CAPTURE(face);
                CAPTURE(column);
                const TexelAddress t{face, column, row};
                const std::uint32_t e = to.cubes[0].first_texel + static_cast<std::uint32_t>(texel_linear_index(t, 8));
                REQUIRE(new_words[e] != gpu_clear_word);
                CHECK(new_words[e] == shrinking.load_word(TexelAddress{face, 3 * column + 1, 3 * row + 1}));
                CHECK(gpu_doubtful(new_doubtful.data(), new_doubtful.size(), e) == (column == 3 || column == 4));
            }
    // Grown: empty, nothing doubtful.
    for (std::uint32_t i = 0; i < shared::raycache_gpu_cube_texel_count(16); ++i) {
        CHECK(new_words[to.cubes[2].first_texel + i] == gpu_clear_word);
        CHECK_FALSE(gpu_doubtful(new_doubtful.data(), new_doubtful.size(), to.cubes[2].first_texel + i));
    }
    // The confidence test off: the shrunk cube has no doubtful texel; the kept one keeps its bit.
    std::vector<std::uint32_t> plain_words = cleared_gpu_words(to), plain_doubtful(to.doubtful_words, 0u);
    move_gpu_cubes<CctTexel>(from, words.data(), doubtful.data(), to, plain_words.data(), plain_doubtful.data(), -1.0f);
    CHECK(plain_words == new_words);
    const std::uint32_t kept_mark = to.cubes[1].first_texel + static_cast<std::uint32_t>(texel_linear_index({1, 3, 2}, 16));
    for (std::uint32_t e = 0; e < to.texels; ++e) CHECK(gpu_doubtful(plain_doubtful.data(), plain_doubtful.size(), e) == (e == kept_mark));
    // Without old doubtful bits, none carried.
    std::vector<std::uint32_t> no_bits(to.doubtful_words, 0u);
    move_gpu_cubes<CctTexel>(from, words.data(), nullptr, to, plain_words.data(), no_bits.data(), -1.0f);
    for (std::uint32_t w : no_bits) CHECK(w == 0u);
    // Layouts of different cubes are refused.
    CHECK_THROWS_AS(move_gpu_cubes<CctTexel>(from, words.data(), nullptr, gpu_buffer_layout<CctTexel>({GpuCubeShape{16, {}}}),
                                             plain_words.data(), nullptr, 0.1f),
                    std::invalid_argument);
}

TEST_CASE("moving CDCT cubes keeps both words of each texel") {
    // b (24 -> 8) first, then a (8, kept, moving from element 3456 to 384): every word pair lands whole.
    const GpuBufferLayout from = gpu_buffer_layout<CdctTexel>({GpuCubeShape{24, {}}, GpuCubeShape{8, {}}});
    const GpuBufferLayout to = gpu_buffer_layout<CdctTexel>({GpuCubeShape{8, {}}, GpuCubeShape{8, {}}});
    CdctCube a(8), b(24);
    a.store_at(TexelAddress{4, 1, 6}, DepthSample{glm::vec3(0.5f, 0.25f, 1.0f), 3.5f});
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < 24; ++row)
            for (int column = 0; column < 24; ++column)
                b.store_at(TexelAddress{face, column, row}, DepthSample{glm::vec3(0.5f), 2.0f + static_cast<float>(column)});
    a.begin_frame();
    b.begin_frame();
    std::vector<std::uint32_t> words = cleared_gpu_words(from);
    write_gpu_words(b, from.cubes[0], words.data(), words.size());
    write_gpu_words(a, from.cubes[1], words.data(), words.size());
    std::vector<std::uint32_t> new_words = cleared_gpu_words(to);
    move_gpu_cubes<CdctTexel>(from, words.data(), nullptr, to, new_words.data(), nullptr, 0.1f);
    CdctCube back_a(8), back_b(8);
    CHECK(read_gpu_words(back_a, to.cubes[1], new_words.data(), new_words.size()) == 1u);
    CHECK(read_gpu_words(back_b, to.cubes[0], new_words.data(), new_words.size()) == 6u * 64u);
    CHECK(back_a.load_word(TexelAddress{4, 1, 6}) == a.load_word(TexelAddress{4, 1, 6}));
    // Coarse column c took fine column 3c + 1: distance 3 + 3c.
    const auto s = back_b.load(TexelAddress{2, 5, 7});
    REQUIRE(s);
    CHECK(s->distance == doctest::Approx(2.0f + 16.0f));
}

// Origin records through a move, by hand: a kept cube's records move word for word; a 40-texel cube (3 tiles
// a face edge) shrinking to 16 (one tile a face) gives its face-0 tile the union of the boxes of the fine
// tiles its texels came from: fine (5, 5) in tile (0, 0), stored from (0, 0, 0) at 4, lands in coarse (2, 2)
// (5.5 x 16 / 40 = 2.2); fine (35, 35) in tile (2, 2), from (1, 1, 1) at 2, lands in (14, 14): box
// [(0, 0, 0), (1, 1, 1)], nearest 2. Keys: ordered(0) = 0x80000000, ~ordered(1) = ~0xBF800000 = 0x407FFFFF,
// ordered(2) = 0xC0000000; the kept box (1, 2, 3) at 5: 0xBF800000, 0xC0000000, 0xC0400000, complements
// 0x407FFFFF, 0x3FFFFFFF, 0x3FBFFFFF, nearest 0xC0A00000. A growing cube starts with no boxes.
TEST_CASE("moving GPU cubes carries their tiles' origin boxes: copied, united when shrinking, none when growing") {
    const GpuBufferLayout from = gpu_buffer_layout<CctTexel>({GpuCubeShape{40, {}}, GpuCubeShape{16, {}}, GpuCubeShape{8, {}}});
    const GpuBufferLayout to = gpu_buffer_layout<CctTexel>({GpuCubeShape{16, {}}, GpuCubeShape{16, {}}, GpuCubeShape{16, {}}});
    REQUIRE(from.cubes[1].first_tile == 54u);
    REQUIRE(to.cubes[1].first_tile == 6u);
    CctCube shrinking(40), kept(16), growing(8);
    REQUIRE(shrinking.store(texel_direction({0, 5, 5}, 40), glm::vec3(1, 0, 0), glm::vec3(0.0f), 4.0f));
    REQUIRE(shrinking.store(texel_direction({0, 35, 35}, 40), glm::vec3(0, 1, 0), glm::vec3(1.0f), 2.0f));
    REQUIRE(kept.store(texel_direction({2, 4, 4}, 16), glm::vec3(0, 0, 1), glm::vec3(1.0f, 2.0f, 3.0f), 5.0f));
    REQUIRE(growing.store(texel_direction({3, 1, 1}, 8), glm::vec3(1), glm::vec3(7.0f), 1.0f));
    for (CctCube* c : {&shrinking, &kept, &growing}) c->begin_frame();
    std::vector<std::uint32_t> words = cleared_gpu_words(from), records(from.origin_words, gpu_clear_word);
    const CctCube* olds[3] = {&shrinking, &kept, &growing};
    for (std::size_t k = 0; k < 3; ++k) {
        write_gpu_words(*olds[k], from.cubes[k], words.data(), words.size());
        write_gpu_origins(*olds[k], from.cubes[k], records.data(), records.size());
    }
    std::vector<std::uint32_t> new_words = cleared_gpu_words(to), new_records(to.origin_words, gpu_clear_word);
    move_gpu_cubes<CctTexel>(from, words.data(), nullptr, to, new_words.data(), nullptr, -1.0f, records.data(), new_records.data());
    auto record = [&](std::uint32_t tile) { return std::vector<std::uint32_t>(new_records.begin() + tile * 16, new_records.begin() + tile * 16 + 16); };
    const std::uint32_t c = gpu_clear_word;
    CHECK(record(0) == std::vector<std::uint32_t>{0x80000000u, 0x80000000u, 0x80000000u, 0x407FFFFFu, 0x407FFFFFu, 0x407FFFFFu,
                                                  0xC0000000u, c, c, c, c, c, c, c, c, c});
    CHECK(record(6 + 2) == std::vector<std::uint32_t>{0xBF800000u, 0xC0000000u, 0xC0400000u, 0x407FFFFFu, 0x3FFFFFFFu, 0x3FBFFFFFu,
                                                      0xC0A00000u, c, c, c, c, c, c, c, c, c});
    for (std::uint32_t tile = 0; tile < 18; ++tile)
        if (tile != 0 && tile != 8) CHECK(record(tile) == std::vector<std::uint32_t>(16, c));
    // Without records on either side, the texels move as before and no record is written.
    std::vector<std::uint32_t> untouched(to.origin_words, 0x12345678u), plain = cleared_gpu_words(to);
    move_gpu_cubes<CctTexel>(from, words.data(), nullptr, to, plain.data(), nullptr, -1.0f, nullptr, untouched.data());
    CHECK(plain == new_words);
    for (std::uint32_t w : untouched) CHECK(w == 0x12345678u);
}

TEST_CASE("a GPU cube whose rays hold still takes finer faces after three settled frames, and goes back when they move on") {
    // One cube at 91 texels, sized, 6144 rays a frame over a sixth of the directions. At 1 ray a texel they
    // want 78.4 texels (91 stays); once three frames in a row answered them all with no miss on an empty
    // texel, at 0.1 rays a texel they want sqrt(6144 / (0.1 x 6 / 6)) = 247.9: the nearest step, 256 (0.05
    // octave away; 181 is 0.45), at once. The frame after the resize is not judged; then 247.9 is within the
    // hysteresis of 256. A frame whose misses are 30% on empty texels (over 20%) ends it: 78.4 is 3.4
    // half-octaves below 256, so the nearest step, 91. A resting frame starts the count again.
    const GpuBufferLayout at_91 = gpu_buffer_layout<CctTexel>({GpuCubeShape{91, {}}});
    const GpuBufferLayout at_256 = gpu_buffer_layout<CctTexel>({GpuCubeShape{256, {}}});
    const AdaptiveResolution a;
    std::vector<bool> sized(1, true);
    std::vector<StillRays> still(1);
    auto frame = [](std::uint64_t hits, std::uint64_t empty) {
        GpuFrameStatistics f = frame_with(1, 0, 6144, 256);
        f.cubes[0].hits = hits;
        f.cubes[0].misses = 6144 - hits;
        f.cubes[0].misses_by[static_cast<std::size_t>(MissReason::empty)] = empty;
        return f;
    };
    auto next = [&](const GpuBufferLayout& layout, const GpuFrameStatistics& f) {
        return next_gpu_face_sizes<CctTexel>(a, layout, f, sized, ~std::uint64_t{0}, &still).face_sizes[0];
    };
    CHECK(next(at_91, frame(6144, 0)) == 91);
    CHECK(next(at_91, frame(6144, 0)) == 91);
    CHECK_FALSE(still[0].resized);
    CHECK(next(at_91, frame(6144, 0)) == 256);
    CHECK(still[0].fine);
    CHECK(still[0].resized);
    CHECK(next(at_256, frame(0, 6144)) == 256); // the cold frame after the resize: not judged
    CHECK(still[0].fine);
    CHECK(next(at_256, frame(6144, 0)) == 256);
    CHECK(next(at_256, frame(4300, 1844)) == 91); // 1844 of 6144: 30% empty
    CHECK_FALSE(still[0].fine);
    // Settled again twice, then a frame resting: the count starts over.
    still[0] = StillRays{};
    CHECK(next(at_91, frame(6144, 0)) == 91);
    CHECK(next(at_91, frame(6144, 0)) == 91);
    GpuFrameStatistics resting = frame(6144, 0);
    resting.resting.assign(1, true);
    CHECK(next(at_91, resting) == 91);
    CHECK(still[0].settled_frames == 0);
    CHECK(next(at_91, frame(6144, 0)) == 91);
    // One state per cube, or an error.
    std::vector<StillRays> two(2);
    CHECK_THROWS_AS(next_gpu_face_sizes<CctTexel>(a, at_91, frame(6144, 0), sized, ~std::uint64_t{0}, &two), std::invalid_argument);
}
