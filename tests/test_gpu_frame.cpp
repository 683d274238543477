// raycache/gpu_frame.hpp: the frame buffer's layout and start words, the end-of-frame pass's group counts,
// the statistics read back and the face sizes fitted to a storage buffer, against values worked out by hand:
// - header 8 words, 55 a cube (5 counters, the resting word, the count of misses on empty texels, 48 words
//   of direction-cell bits): 3 cubes and 100 list entries take 8 + 165 + 100 = 273 words (1092 bytes), of
//   which the first 173 (692 bytes) are rewritten before each frame; entry 0 is word 173.
// - groups of 256: 1 entry -> 1 group, 256 -> 1, 257 -> 2, 65535 * 256 -> 65535, one more -> still 65535.
// - fitting: faces 8, 100, 100 of CCT texels (4 bytes) into 6 * (64 + 2 * 50^2) * 4 = 121,536 bytes gives a
//   cap of 50 (51 would need 6 * (64 + 2 * 2601) * 4 = 126,384): 8, 50, 50.
#include <doctest/doctest.h>

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "raycache/gpu_buffers.hpp"

using namespace raycache;

TEST_CASE("the frame buffer holds a header, five counters, the resting word, the empty count and the cell bits a cube, and the store list") {
    const GpuFrameLayout f = gpu_frame_layout(3, 100);
    CHECK(f.words == 273u);
    CHECK(f.bytes == 1092u);
    CHECK(f.start_bytes == 692u);
    CHECK(shared::raycache_frame_list_word(3, 0) == 173u);
    CHECK(shared::raycache_frame_counter_word(2, RAYCACHE_FRAME_REFUSED) == 8u + 110u + 3u);
    CHECK(shared::raycache_frame_counter_word(2, RAYCACHE_FRAME_RESTED) == 8u + 110u + 4u);
    CHECK(shared::raycache_frame_counter_word(2, RAYCACHE_FRAME_RESTING) == 8u + 110u + 5u);
    CHECK(shared::raycache_frame_counter_word(2, RAYCACHE_FRAME_EMPTY) == 8u + 110u + 6u);
    CHECK(shared::raycache_frame_coverage_word(2, 0) == 8u + 110u + 7u);
    CHECK_THROWS_AS(gpu_frame_layout(3, 100, 1091), std::invalid_argument);
    CHECK_NOTHROW(gpu_frame_layout(3, 100, 1092));
    // The largest list that fits 1092 bytes with 3 cubes is 100 entries; never more than the texels.
    CHECK(gpu_frame_list_capacity(3, 1000, 1092) == 100u);
    CHECK(gpu_frame_list_capacity(3, 40, 1092) == 40u);
    CHECK(gpu_frame_list_capacity(3, 1000, 600) == 0u);
    // One dimension of 65535 groups of 256 covers 16,776,960 entries: no longer list.
    CHECK(gpu_frame_list_capacity(3, 1ull << 30, 1ull << 32) == 16776960u);
    CHECK_NOTHROW(gpu_frame_layout(3, 16776960u));
    CHECK_THROWS_AS(gpu_frame_layout(3, 16776961u), std::invalid_argument);
}

TEST_CASE("the start words empty the list, state capacity and cube count, dispatch {0, 1, 1}, the coverage flag, and zero the counters") {
    const GpuFrameLayout f = gpu_frame_layout(2, 10);
    const std::vector<std::uint32_t> w = gpu_frame_start_words(f);
    REQUIRE(w.size() == 8u + 2u * 55u);
    const std::vector<std::uint32_t> header = {0, 10, 2, 0, 0, 1, 1, 1}; // the last: lookups mark their cells
    CHECK(std::vector<std::uint32_t>(w.begin(), w.begin() + 8) == header);
    for (std::size_t i = 8; i < w.size(); ++i) CHECK(w[i] == 0u); // counters and cell bits
    const std::vector<std::uint32_t> fixed = gpu_frame_start_words(f, false); // fixed face sizes: no marking
    CHECK(std::vector<std::uint32_t>(fixed.begin(), fixed.begin() + 8) == std::vector<std::uint32_t>{0, 10, 2, 0, 0, 1, 1, 0});
    CHECK(std::vector<std::uint32_t>(fixed.begin() + 8, fixed.end()) == std::vector<std::uint32_t>(w.begin() + 8, w.end()));
    CHECK(gpu_end_frame_dispatch_offset == 16u);
    CHECK(gpu_bindings.cct_texels == 0u);
    CHECK(gpu_bindings.cdct_pending == 3u);
    CHECK(gpu_bindings.frame == 4u);
}

TEST_CASE("a frame layout filled in by hand with sizes other than gpu_frame_layout's is refused before anything indexes the buffer") {
    raycache::GpuFrameLayout f; // all sizes 0
    f.cube_count = 3;
    f.list_capacity = 100;
    CHECK_THROWS_AS(raycache::gpu_frame_start_words(f, true, {1, 0, 2}), std::invalid_argument);
    const std::vector<std::uint32_t> words(4096, 0u);
    CHECK_THROWS_AS(raycache::read_gpu_statistics(words.data(), f), std::invalid_argument);
    CHECK_THROWS_AS(raycache::gpu_listed_tiles(words.data(), f), std::invalid_argument);
    // By hand: 3 cubes' counters and cells after the header, then 100 list words.
    raycache::GpuFrameLayout g = raycache::gpu_frame_layout(3, 100);
    CHECK(g.start_bytes == 4u * (RAYCACHE_FRAME_HEADER_WORDS + 3u * RAYCACHE_FRAME_CUBE_WORDS));
    CHECK_NOTHROW(raycache::gpu_frame_start_words(g, true, {1, 0, 2}));
    g.start_bytes += 4; // one word off
    CHECK_THROWS_WITH(raycache::gpu_frame_start_words(g), doctest::Contains("sizes gpu_frame_layout() gives"));
}

TEST_CASE("the end-of-frame pass gets one group per 256 listed texels, at most 65535") {
    CHECK(gpu_end_frame_groups(0) == 0u);
    CHECK(gpu_end_frame_groups(1) == 1u);
    CHECK(gpu_end_frame_groups(256) == 1u);
    CHECK(gpu_end_frame_groups(257) == 2u);
    CHECK(gpu_end_frame_groups(65535u * 256u) == 65535u);
    CHECK(gpu_end_frame_groups(65535u * 256u + 1u) == 65535u);
    CHECK(gpu_end_frame_groups(0xFFFFFFFFull) == 65535u);
    // A store that appends entry k adds a group exactly when entries k + 1 need one more than k.
    std::uint32_t added = 0;
    for (std::uint32_t k = 0; k < 1000; ++k) added += shared::raycache_end_frame_groups(k + 1) > shared::raycache_end_frame_groups(k);
    CHECK(added == 4u); // entries 0, 256, 512, 768
    const GpuGroups g = gpu_sweep_groups(65535u * 64u + 1u);
    CHECK(g.x == 65535u);
    CHECK(g.y == 2u);
    CHECK(gpu_sweep_groups(0).x == 0u);
}

TEST_CASE("GPU statistics read per cube and in all, misses apart from hits, the list clamped to its capacity") {
    const GpuFrameLayout f = gpu_frame_layout(2, 5);
    std::vector<std::uint32_t> w = gpu_frame_start_words(f);
    w[RAYCACHE_FRAME_LIST_COUNT] = 7; // two past the capacity
    w[RAYCACHE_FRAME_OVERFLOW] = 2;
    // hits, misses, stores, refused, rested, the resting word, misses on empty texels
    const std::uint32_t cube0[] = {10, 5, 4, 1, 0, 0, 3}, cube1[] = {0, 3, 2, 6, 0, 0, 2};
    for (std::uint32_t k = 0; k < 7; ++k) w[8 + k] = cube0[k], w[63 + k] = cube1[k];
    // Cube 1's cells: 3 bits in its first word, all 32 of its last: 35 of 1536.
    w[63 + 7] = 0x00010003u;
    w[63 + 54] = 0xFFFFFFFFu;
    const GpuFrameStatistics s = read_gpu_statistics(w.data(), f);
    REQUIRE(s.coverage.size() == 2u);
    CHECK(s.coverage[0] == 0.0);
    CHECK(s.coverage[1] == doctest::Approx(35.0 / 1536.0));
    REQUIRE(s.cubes.size() == 2u);
    CHECK(s.cubes[0].lookups == 15u);
    CHECK(s.cubes[0].hits == 10u);
    CHECK(s.cubes[0].misses == 5u);
    CHECK(s.cubes[0].misses_by[static_cast<std::size_t>(MissReason::empty)] == 3u);
    CHECK(s.cubes[1].misses_by[static_cast<std::size_t>(MissReason::empty)] == 2u);
    CHECK(s.total.misses_by[static_cast<std::size_t>(MissReason::empty)] == 5u);
    CHECK(s.cubes[1].stores == 2u);
    CHECK(s.cubes[1].refused_stores == 6u);
    CHECK(s.total.lookups == 18u);
    CHECK(s.total.stores == 6u);
    CHECK(s.total.refused_stores == 7u);
    CHECK(s.listed == 5u);
    CHECK(s.overflow == 2u);
    // The list starts at word 8 + 2 x 55 = 118: a CCT texel, a tile, a CDCT texel, a tile, a CDCT entry with
    // the tile bit set (a CDCT element), and past the capacity a tile that is not counted: 2 tiles.
    w.resize(static_cast<std::size_t>(f.words), 0u);
    const std::uint32_t entries[] = {17u, RAYCACHE_FRAME_TILE_ENTRY | 3u, RAYCACHE_FRAME_CDCT_ENTRY | 9u, RAYCACHE_FRAME_TILE_ENTRY,
                                     RAYCACHE_FRAME_CDCT_ENTRY | RAYCACHE_FRAME_TILE_ENTRY | 1u};
    for (std::uint32_t k = 0; k < 5; ++k) w[118 + k] = entries[k];
    w.push_back(RAYCACHE_FRAME_TILE_ENTRY | 4u);
    CHECK(gpu_listed_tiles(w.data(), f) == 2u);
}

TEST_CASE("a GPU byte budget caps a texel buffer so that texels, pending twin and doubtful bits fit it, to the texel") {
    // t texels take 2 x 4w t bytes (texels and pending, w words a texel) and 4 ceil(t / 32) bytes of doubtful
    // bits. 1 MiB, CCT (w = 1): 129,055 texels take 2 x 516,220 + 4 x 4,033 = 1,048,572 bytes; one more,
    // 1,048,580. CDCT (w = 2): 65,027 texels take 2 x 520,216 + 4 x 2,033 = 1,048,564; one more, 1,048,580.
    CHECK(raycache::gpu_texel_bytes_within<raycache::CctTexel>(1u << 20) == 516220u);
    CHECK(raycache::gpu_texel_bytes_within<raycache::CdctTexel>(1u << 20) == 520216u);
    CHECK(raycache::gpu_texel_bytes_within<raycache::CctTexel>(3) == 0u);
    // Budgets past 2^61 bytes do not overflow (8 b did): b = 2^61 (a budget of 2^61 + 4), d = 65 (a CCT
    // texel's 64 bits and its doubtful bit): 8 x 2^61 = 18,446,744,073,709,551,616 = 65 x
    // 283,796,062,672,454,640 + 16, so t = 283,796,062,672,454,640 texels of 4 bytes. The largest budget, CDCT
    // (d = 129): 8 (2^64 - 5) = 129 x 1,143,984,128,602,142,735 + 73, texels of 8 bytes.
    CHECK(raycache::gpu_texel_bytes_within<raycache::CctTexel>((std::uint64_t{1} << 61) + 4) == 283796062672454640ull * 4u);
    CHECK(raycache::gpu_texel_bytes_within<raycache::CdctTexel>(~std::uint64_t{0}) == 1143984128602142735ull * 8u);
    // With origin records, one byte a texel more: t (64 + 9) / 8 <= 1,048,572 gives t = 114,912 (73 x 114,912 =
    // 8,388,576 exactly): 459,648 bytes. behind-8's 9 cubes then take N = 46 (9 x 6 x 46^2 = 114,264 texels;
    // 47 would take 119,286), laid out as 2 x 457,056 + 4 x 3,571 + 9 x 54 tiles x 64 = 959,500 bytes.
    CHECK(raycache::gpu_texel_bytes_within<raycache::CctTexel>(1u << 20, true) == 459648u);
    const std::vector<int> nine = fit_gpu_face_sizes(std::vector<int>(9, 256), 4, raycache::gpu_texel_bytes_within<raycache::CctTexel>(1u << 20, true));
    CHECK(nine == std::vector<int>(9, 46));
    std::vector<raycache::GpuCubeShape> nine_shapes;
    for (int n : nine) nine_shapes.push_back({n, raycache::CubeBounds{}});
    CHECK(raycache::gpu_cube_bytes(raycache::gpu_buffer_layout<raycache::CctTexel>(nine_shapes), true) == 959500u);
    CHECK(raycache::gpu_cube_bytes(raycache::gpu_buffer_layout<raycache::CctTexel>(nine_shapes), false) == 928396u);
    // Faces smaller than 8 take ceil(64 / N^2) bytes a texel of records: N = 1 one tile a texel, 64; N = 3, 8
    // (64 / 9 = 7.1); N = 7, 2 (1.3). With N = 1 allowed, t (64 + 1 + 512) / 8 <= 1,048,572: t = 14,538
    // (577 x 14,538 = 8,388,426; one more passes 8,388,576): 58,152 bytes.
    CHECK(raycache::gpu_origin_bytes_per_texel(1) == 64u);
    CHECK(raycache::gpu_origin_bytes_per_texel(3) == 8u);
    CHECK(raycache::gpu_origin_bytes_per_texel(7) == 2u);
    CHECK(raycache::gpu_origin_bytes_per_texel(8) == 1u);
    CHECK(raycache::gpu_origin_bytes_per_texel(17) == 1u);
    CHECK(raycache::gpu_texel_bytes_within<raycache::CctTexel>(1u << 20, true, 1) == 58152u);
    // The bound holds for every face size from the smallest on: a cube of each size N = 1..64 in a budget
    // sized by gpu_texel_bytes_within at the smallest size N fits, with its records.
    for (int n = 1; n <= 64; ++n) {
        CAPTURE(n);
        const std::uint64_t texels = 6ull * n * n;
        const std::uint64_t records = 6ull * ((n + 15) / 16) * ((n + 15) / 16) * 64;
        CHECK(records <= raycache::gpu_origin_bytes_per_texel(n) * texels);
        for (int smaller = 1; smaller <= n; ++smaller) CHECK(records <= raycache::gpu_origin_bytes_per_texel(smaller) * texels);
    }
    // One cube in 1 MiB: 6 N^2 <= 129,055 gives N = 146 (127,896 texels; 147 would take 129,654).
    CHECK(fit_gpu_face_sizes({512}, 4, raycache::gpu_texel_bytes_within<raycache::CctTexel>(1u << 20)) == std::vector<int>{146});
    // behind-32's 33 cubes at 512 texels in 64 MiB, CDCT: the laid-out buffers stay within it.
    const std::uint64_t budget = 64u << 20;
    const std::vector<int> sizes = fit_gpu_face_sizes(std::vector<int>(33, 512), 8, raycache::gpu_texel_bytes_within<raycache::CdctTexel>(budget));
    std::vector<raycache::GpuCubeShape> shapes;
    for (int n : sizes) shapes.push_back({n, raycache::CubeBounds{glm::vec3(0.0f), 1.0f}});
    const raycache::GpuBufferLayout layout = raycache::gpu_buffer_layout<raycache::CdctTexel>(shapes);
    CHECK(2 * layout.bytes + layout.doubtful_bytes <= budget);
    CHECK(2 * layout.bytes + layout.doubtful_bytes > budget * 9 / 10); // and use most of it
}

TEST_CASE("face sizes fitted to a storage buffer lower only the cubes above the largest cap that fits") {
    const std::vector<int> requested = {8, 100, 100};
    CHECK(fit_gpu_face_sizes(requested, 4, 121536) == std::vector<int>{8, 50, 50});
    CHECK(fit_gpu_face_sizes(requested, 4, 126383) == std::vector<int>{8, 50, 50});
    CHECK(fit_gpu_face_sizes(requested, 4, 126384) == std::vector<int>{8, 51, 51});
    CHECK(fit_gpu_face_sizes(requested, 4, 1u << 30) == requested);
    // Uniform sizes: the largest uniform size that fits (what the Vulkan example did by lowering one at a time).
    CHECK(fit_gpu_face_sizes({512, 512}, 4, 128u << 20) == std::vector<int>{512, 512});
    CHECK(fit_gpu_face_sizes(std::vector<int>(33, 512), 4, 128u << 20) == std::vector<int>(33, 411));
    CHECK_THROWS_AS(fit_gpu_face_sizes({8, 8}, 4, 47), std::invalid_argument); // 2 * 6 * 4 = 48 bytes at N = 1
    CHECK_THROWS_AS(fit_gpu_face_sizes({0}, 4, 100), std::invalid_argument);
}
