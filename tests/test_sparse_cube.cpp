// Sparse texel storage and memory budgets: a cube allocates 16 x 16 tiles on their first store, charges
// them to its MemoryBudget, and refuses stores (never writes) into tiles the budget cannot hold.
//
// Directions and their texels by hand from the face table: +X: column = floor((-z/|x| + 1)/2 * N),
// row = floor((-y/|x| + 1)/2 * N); -Z: column = floor((-x/|z| + 1)/2 * N), row = floor((-y/|z| + 1)/2 * N).
#include <doctest/doctest.h>

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <tuple>
#include <thread>
#include <vector>

#include "raycache/raycache.hpp"

#include "test_random.hpp"

namespace {

using raycache::CctCube;
using raycache::CdctCube;
using raycache::MemoryBudget;
using raycache::TexelAddress;

const glm::vec3 grey(0.5f);

// On cache lines of 64 bytes, grouped by who writes them during a frame: 16 x 16 words; the four 64-bit
// written masks and the four unrecorded masks (stores) on a line of their own; the four 64-bit doubtful masks, the visible origin box (6
// four-byte values), nearest hit distance (4 bytes) and has-box flag (1 byte), which lookups read, on the
// next (61 bytes, padded to 64); then what stores write: the pending origin box (6 four-byte values), the
// pending nearest distance, the stale mark and the valid-texel count (4 bytes each), padded to 8; four 64-bit
// recorded masks (raycache/invalidation.hpp), four 64-bit masks of the texels holding a value from earlier
// frames, and the path records: for each of the sixty-four 2 x 2 record
// blocks a 64-bit Bloom mask of objects, the hit-point box and the escape-direction box (6 + 6 four-byte
// values) and the path flags (4 bytes), padded to 64, and the 64-bit mask of the direction cells its
// nested cached answers read: 72 bytes; then sixteen more such records for the unions of its 4 x 4 groups
// of texels and one for the tile's union; the whole padded to a multiple of 64.
constexpr std::size_t round_up(std::size_t n, std::size_t to) { return (n + to - 1) / to * to; }
constexpr std::size_t written_line = round_up(4 * 8 + 4 * 8, 64);
constexpr std::size_t lookup_line = round_up(4 * 8 + 6 * 4 + 4 + 1, 64);
// The records live after the tile, in its allocation; the tile itself ends with the pointer to them.
constexpr std::size_t records = (64 + 16 + 1) * (round_up(8 + 6 * 4 + 6 * 4 + 4, 8) + 8); // 2 x 2 blocks, 4 x 4 groups, the tile
constexpr std::size_t store_part_alone = round_up(6 * 4 + 4 + 4 + 4, 8) + 4 * 8 + 4 * 8 + sizeof(void*);
constexpr std::size_t cct_tile_alone = round_up(16 * 16 * 4 + written_line + lookup_line + store_part_alone, 64);
constexpr std::size_t cdct_tile_alone = round_up(16 * 16 * 8 + written_line + lookup_line + store_part_alone, 64);
constexpr std::size_t cct_tile = cct_tile_alone + records;
constexpr std::size_t cdct_tile = cdct_tile_alone + records;
static_assert(cct_tile == 7112 && cdct_tile == 8136, "the sizes the test's name gives");
static_assert(cct_tile_alone == 1280 && cdct_tile_alone == 2304, "the sizes without records the test's name gives");

} // namespace

TEST_CASE("a tile is 16 x 16 texels, their written and doubtful bits, an origin box, a nearest distance and a path record per 2 x 2 block, per 4 x 4 group and for the tile, on cache lines by writer: 7112 bytes for the CCT, 8136 for the CDCT") {
    CHECK(CctCube::tile_bytes() == cct_tile);
    CHECK(CdctCube::tile_bytes() == cdct_tile);
}

TEST_CASE("without path records a tile is 1280 bytes (CCT) or 2304 (CDCT), and the budget is charged that") {
    CHECK(CctCube::tile_bytes(false) == cct_tile_alone);
    CHECK(CdctCube::tile_bytes(false) == cdct_tile_alone);
    auto budget = std::make_shared<MemoryBudget>(1u << 20);
    CctCube cct(32, budget, false);
    CdctCube cdct(32, budget, false);
    CHECK_FALSE(cct.keeps_path_records());
    CHECK(cct.bytes_per_tile() == cct_tile_alone);
    const std::size_t tables = budget->used();
    for (int face = 0; face < 6; ++face) {
        CHECK(cct.store_at(TexelAddress{face, 0, 0}, grey));
        CHECK(cdct.store_at(TexelAddress{face, 20, 20}, raycache::DepthSample{grey, 2.0f}));
    }
    CHECK(cct.allocated_bytes() == 6 * cct_tile_alone);
    CHECK(cdct.allocated_bytes() == 6 * cdct_tile_alone);
    CHECK(budget->used() == tables + 6 * (cct_tile_alone + cdct_tile_alone));
    cct.clear();
    cdct.clear();
    CHECK(budget->used() == tables);
}

TEST_CASE("a new cube holds no tile, and a store allocates exactly the tile of its texel") {
    CctCube cube(64); // 4 x 4 tiles a face
    CHECK(cube.allocated_tiles() == 0u);
    // +X centre: tu = tv = 0.5 -> texel (32, 32), tile (2, 2).
    CHECK(cube.store(glm::vec3(1, 0, 0), grey));
    CHECK(cube.allocated_tiles() == 1u);
    CHECK(cube.allocated_bytes() == cct_tile);
    // Every other texel of that tile (columns and rows 32..47) stays in it.
    for (int row = 32; row < 48; ++row)
        for (int column = 32; column < 48; ++column) cube.store_at(TexelAddress{0, column, row}, grey);
    CHECK(cube.allocated_tiles() == 1u);
    CHECK(cube.valid_texels() == 256u);
    // Column 48 is the next tile; -Z is another face.
    CHECK(cube.store_at(TexelAddress{0, 48, 32}, grey));
    CHECK(cube.store(glm::vec3(0, 0, -1), grey));
    CHECK(cube.allocated_tiles() == 3u);
    // Tiles are numbered face by face, row by row: (face 0, row 2, column 2) = 10, column 3 = 11, and the
    // -Z face's (5) centre tile 5 * 16 + 10 = 90; the per-tile block walk starts each at its corner texel.
    CHECK(cube.allocated_tile_indices() == std::vector<std::size_t>{10, 11, 90});
    std::vector<int> corners;
    for (std::size_t i : cube.allocated_tile_indices())
        cube.for_each_block_state_of_tile(i, [&](const CctCube::BlockState& b) {
            if (b.block == 0) corners.insert(corners.end(), {b.face, b.column0, b.row0});
        });
    CHECK(corners == std::vector<int>{0, 32, 32, 0, 48, 32, 5, 32, 32});
}

// Every record block holding a value, and none other, with its texels counted and its union of paths as
// built by hand from the stores, on faces that a tile fits (16), that clip the last tiles to an odd number of
// columns and rows (21, 37), or that are smaller than a tile (5).
TEST_CASE("record blocks report their texels holding values and the union of their stores' paths, also where the face clips a tile") {
    for (const int n : {5, 16, 21, 37}) {
        CAPTURE(n);
        CctCube cube(n);
        Lcg random{static_cast<std::uint64_t>(n)};
        // What the stores put in each 2 x 2 block, keyed (face, block row, block column).
        struct Expected {
            int valid = 0, unrecorded = 0;
            raycache::PathRecord paths = raycache::PathRecord::empty();
        };
        std::map<std::tuple<int, int, int>, Expected> expected;
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column) {
                    const std::uint32_t pick = random.next() % 10;
                    if (pick >= 4) continue; // 60% stay empty
                    const TexelAddress a{face, column, row};
                    Expected& e = expected[{face, row / 2, column / 2}];
                    ++e.valid;
                    if (pick == 0) { // stored without a record
                        REQUIRE(cube.store_at(a, grey));
                        ++e.unrecorded;
                        continue;
                    }
                    raycache::PathRecord saw;
                    saw.track_cached_reads();
                    saw.hit(static_cast<std::uint64_t>(face * 1000 + row * 40 + column),
                            glm::vec3(static_cast<float>(column), -static_cast<float>(row), 0.25f * static_cast<float>(face)));
                    saw.lit = (column % 3) == 0;
                    if (row % 4 == 1) saw.escaped(glm::vec3(static_cast<float>(column) - 10.0f, 1.0f, static_cast<float>(row)));
                    REQUIRE(cube.store_at(a, grey, saw));
                    e.paths.merge(saw);
                }
        cube.begin_frame();
        std::size_t blocks = 0;
        cube.for_each_block_state([&](const CctCube::BlockState& b) {
            ++blocks;
            CAPTURE(b.face);
            CAPTURE(b.column0);
            CAPTURE(b.row0);
            // The block's texels: 2 x 2, clipped to the face, starting at even texels.
            CHECK(b.column0 % 2 == 0);
            CHECK(b.row0 % 2 == 0);
            CHECK(b.column1 == std::min(n, b.column0 + 2));
            CHECK(b.row1 == std::min(n, b.row0 + 2));
            const auto found = expected.find({b.face, b.row0 / 2, b.column0 / 2});
            REQUIRE(found != expected.end());
            const Expected& e = found->second;
            CHECK(b.valid_texels == e.valid);
            CHECK(b.unrecorded_texels == e.unrecorded);
            const raycache::PathRecord r = b.record();
            CHECK(r.objects == e.paths.objects);
            CHECK(r.lit == e.paths.lit);
            CHECK(r.unbounded == e.paths.unbounded);
            CHECK(r.has_vertices() == e.paths.has_vertices());
            if (e.paths.has_vertices()) {
                CHECK(r.vertex_lo == e.paths.vertex_lo);
                CHECK(r.vertex_hi == e.paths.vertex_hi);
            }
            CHECK(r.has_escapes() == e.paths.has_escapes());
            if (e.paths.has_escapes()) {
                CHECK(r.escape_lo == e.paths.escape_lo);
                CHECK(r.escape_hi == e.paths.escape_hi);
            }
        });
        CHECK(blocks == expected.size());
    }
}

// Each 4 x 4 group of a tile keeps the union of every path stored into its texels, as built by hand from
// the stores, on the faces of the test above (a face smaller than a tile, tiles clipped at odd sizes);
// groups and tiles holding no recorded store keep the empty union.
TEST_CASE("each 4 x 4 group of a tile keeps the union of the paths stored into its texels, and a tile names its groups holding them") {
    for (const int n : {5, 16, 21, 37}) {
        CAPTURE(n);
        CctCube cube(n);
        Lcg random{static_cast<std::uint64_t>(100 + n)};
        const int tiles_per_edge = (n + 15) / 16;
        // Keyed (tile index: face, tile row, tile column in the cube's order; group: 4 x 4 squares in rows).
        std::map<std::pair<std::size_t, int>, raycache::PathRecord> expected;
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column) {
                    const std::uint32_t pick = random.next() % 10;
                    if (pick >= 3) continue;
                    const TexelAddress a{face, column, row};
                    if (pick == 0) { // without a record: adds nothing to any union
                        REQUIRE(cube.store_at(a, grey));
                        continue;
                    }
                    raycache::PathRecord saw;
                    saw.hit(static_cast<std::uint64_t>(7 + face * 3 + row % 5),
                            glm::vec3(static_cast<float>(column) * 0.5f, static_cast<float>(row) - 3.0f, -static_cast<float>(face)));
                    if (column % 3 == 1) saw.escaped(glm::vec3(1.0f, static_cast<float>(row % 4) - 1.5f, -static_cast<float>(column % 5)));
                    saw.lit = row % 2 == 0;
                    REQUIRE(cube.store_at(a, grey, saw));
                    const std::size_t tile = static_cast<std::size_t>((face * tiles_per_edge + row / 16) * tiles_per_edge + column / 16);
                    const int group = (row % 16) / 4 * 4 + (column % 16) / 4;
                    auto [it, fresh] = expected.try_emplace({tile, group}, raycache::PathRecord::empty());
                    it->second.merge(saw);
                }
        cube.begin_frame();
        std::size_t groups_with_paths = 0;
        for (std::size_t tile = 0; tile < static_cast<std::size_t>(6 * tiles_per_edge * tiles_per_edge); ++tile) {
            // Which groups hold a recorded store, as the stores put them; and the blocks of a choice of groups
            // are those of all the tile's blocks that lie in them.
            std::uint32_t recorded_groups = 0;
            for (int group = 0; group < CctCube::record_groups; ++group)
                if (expected.count({tile, group})) recorded_groups |= 1u << group;
            CAPTURE(tile);
            CHECK(cube.groups_with_records(tile) == recorded_groups);
            for (const std::uint32_t chosen : {0u, 0x8421u, 0x00F0u, recorded_groups, CctCube::all_record_groups}) {
                std::vector<int> all, some;
                cube.for_each_block_of_tile(tile, [&](const CctCube::BlockPlace& b) {
                    if ((chosen >> CctCube::group_of_block(b.block)) & 1u) all.push_back(b.block);
                });
                cube.for_each_block_of_tile(tile, [&](const CctCube::BlockPlace& b) { some.push_back(b.block); }, chosen);
                CHECK(some == all);
            }
            for (int group = 0; group < CctCube::record_groups; ++group) {
                CAPTURE(group);
                const raycache::PathRecord r = cube.group_keys(tile, group).record();
                const auto found = expected.find({tile, group});
                if (found == expected.end()) {
                    CHECK(r.objects == 0u);
                    CHECK_FALSE(r.has_vertices());
                    CHECK_FALSE(r.has_escapes());
                    continue;
                }
                ++groups_with_paths;
                const raycache::PathRecord& e = found->second;
                CHECK(r.objects == e.objects);
                CHECK(r.lit == e.lit);
                CHECK(r.has_vertices());
                CHECK(r.vertex_lo == e.vertex_lo);
                CHECK(r.vertex_hi == e.vertex_hi);
                CHECK(r.has_escapes() == e.has_escapes());
                if (e.has_escapes()) {
                    CHECK(r.escape_lo == e.escape_lo);
                    CHECK(r.escape_hi == e.escape_hi);
                }
            }
        }
        CHECK(groups_with_paths == expected.size());
    }
}

// The blocks a tile's walk visits, for a choice of its groups, are the blocks holding a value in those
// groups, in block order, with their texels and counts as the stores put them: computed here from the
// stores alone, with every store recorded (the walk then reads the recorded bits alone) and with some not,
// on faces smaller than a tile and clipped at odd sizes, 5% to 60% of the texels stored.
TEST_CASE("a tile's walk over its blocks visits exactly the blocks holding a value in the groups chosen, in block order") {
    for (const bool some_unrecorded : {false, true})
        for (const int n : {5, 16, 21, 37})
            for (const std::uint32_t percent : {5u, 60u}) {
                CAPTURE(some_unrecorded);
                CAPTURE(n);
                CAPTURE(percent);
                CctCube cube(n);
                Lcg random{static_cast<std::uint64_t>(300 + n + percent)};
                const int tiles_per_edge = (n + 15) / 16;
                struct Block {
                    int column0, row0, column1, row1, valid = 0, unrecorded = 0;
                };
                std::map<std::pair<std::size_t, int>, Block> expected; // (tile, block)
                for (int face = 0; face < 6; ++face)
                    for (int row = 0; row < n; ++row)
                        for (int column = 0; column < n; ++column) {
                            if (random.next() % 100 >= percent) continue;
                            const TexelAddress a{face, column, row};
                            const bool recorded = !some_unrecorded || random.next() % 4 != 0;
                            if (recorded) {
                                raycache::PathRecord saw;
                                saw.hit(7, glm::vec3(static_cast<float>(column), static_cast<float>(row), 1.0f));
                                REQUIRE(cube.store_at(a, grey, saw));
                            } else {
                                REQUIRE(cube.store_at(a, grey));
                            }
                            const std::size_t tile = static_cast<std::size_t>((face * tiles_per_edge + row / 16) * tiles_per_edge + column / 16);
                            const int block = (row % 16) / 2 * 8 + (column % 16) / 2;
                            const int c0 = column / 2 * 2, r0 = row / 2 * 2;
                            auto [it, fresh] = expected.try_emplace({tile, block}, Block{c0, r0, std::min(n, c0 + 2), std::min(n, r0 + 2)});
                            ++it->second.valid;
                            it->second.unrecorded += recorded ? 0 : 1;
                        }
                cube.begin_frame();
                for (std::size_t tile = 0; tile < static_cast<std::size_t>(6 * tiles_per_edge * tiles_per_edge); ++tile)
                    for (const std::uint32_t chosen : {0u, 1u, 0x8421u, 0x00F0u, 0x5A5Au, 0xF000u, CctCube::all_record_groups}) {
                        CAPTURE(tile);
                        CAPTURE(chosen);
                        std::vector<std::tuple<int, int, int, int, int, int, int>> seen, wanted;
                        cube.for_each_block_of_tile(tile, [&](const CctCube::BlockPlace& b) {
                            CHECK(b.tile == tile);
                            CHECK(b.face == static_cast<int>(tile) / (tiles_per_edge * tiles_per_edge));
                            seen.emplace_back(b.block, b.column0, b.row0, b.column1, b.row1, b.valid_texels, b.unrecorded_texels);
                        }, chosen);
                        for (const auto& [key, e] : expected) {
                            if (key.first != tile) continue;
                            const int group = key.second / 16 * 4 + key.second % 8 / 2;
                            if ((chosen >> group) & 1u) wanted.emplace_back(key.second, e.column0, e.row0, e.column1, e.row1, e.valid, e.unrecorded);
                        }
                        CHECK(seen == wanted);
                    }
            }
}

// A union of unions in the tiles' key form is the union of the records (PathRecord::merge), including its
// rule that escapes from nowhere make a union unbounded, and the empty union changes nothing.
TEST_CASE("path unions merged in key form decode to the merged records") {
    raycache::PathRecord a = raycache::PathRecord::empty(), b = raycache::PathRecord::empty();
    a.hit(3, glm::vec3(-1.0f, 2.0f, 0.5f));
    a.hit(4, glm::vec3(1.0f, -2.0f, 0.0f));
    a.lit = true;
    a.escaped(glm::vec3(0.0f, 0.0f, -3.0f));
    b.hit(9, glm::vec3(5.0f, 0.0f, -3.0f));
    b.escaped(glm::vec3(0.0f, 2.0f, 0.0f));
    b.chained = true;
    // Stored in two blocks of one tile (texels (0, 0) and (2, 0) of +X), read back per block.
    CctCube cube(16);
    REQUIRE(cube.store_at(TexelAddress{0, 0, 0}, grey, a));
    REQUIRE(cube.store_at(TexelAddress{0, 2, 0}, grey, b));
    cube.begin_frame();
    std::vector<CctCube::PathKeys> keys;
    cube.for_each_block_keys_of_tile(0, [&](const CctCube::BlockPlace&, const CctCube::PathKeys& k) { keys.push_back(k); });
    REQUIRE(keys.size() == 2u);
    CctCube::PathKeys u = CctCube::PathKeys::empty();
    u.merge(keys[0]);
    u.merge(keys[1]);
    const raycache::PathRecord r = u.record();
    CHECK(r.objects == (raycache::object_bits(3) | raycache::object_bits(4) | raycache::object_bits(9)));
    CHECK(r.vertex_lo == glm::vec3(-1.0f, -2.0f, -3.0f));
    CHECK(r.vertex_hi == glm::vec3(5.0f, 2.0f, 0.5f));
    CHECK(r.escape_lo == glm::vec3(0.0f, 0.0f, -1.0f));
    CHECK(r.escape_hi == glm::vec3(0.0f, 1.0f, 0.0f));
    CHECK(r.lit);
    CHECK(r.chained);
    CHECK_FALSE(r.unbounded);
    // Escapes with no hit point (from nowhere) make the union unbounded, as PathRecord::merge does.
    raycache::PathRecord nowhere = raycache::PathRecord::empty();
    nowhere.escaped(glm::vec3(1.0f, 0.0f, 0.0f));
    CctCube other(16);
    REQUIRE(other.store_at(TexelAddress{0, 0, 0}, grey, nowhere));
    other.begin_frame();
    other.for_each_block_keys_of_tile(0, [&](const CctCube::BlockPlace&, const CctCube::PathKeys& k) { u.merge(k); });
    CHECK(u.record().unbounded);
    CHECK(u.record().vertex_lo == glm::vec3(-1.0f, -2.0f, -3.0f)); // the boxes still hold
    // The empty union is the identity.
    CctCube::PathKeys e = CctCube::PathKeys::empty();
    CHECK_FALSE(e.record().has_vertices());
    CHECK_FALSE(e.record().has_escapes());
    e.merge(keys[0]);
    CHECK(e.record().vertex_lo == glm::vec3(-1.0f, -2.0f, 0.0f));
    CHECK(e.record().vertex_hi == glm::vec3(1.0f, 2.0f, 0.5f));
}

TEST_CASE("lookups and loads of texels in tiles never stored miss without allocating") {
    CctCube cube(256);
    for (int i = 0; i < 100; ++i) CHECK_FALSE(cube.lookup(glm::vec3(1.0f, 0.01f * static_cast<float>(i), -0.3f)));
    CHECK_FALSE(cube.load(TexelAddress{3, 200, 17}));
    CHECK_FALSE(cube.peek_at(TexelAddress{5, 0, 255}));
    CHECK(cube.allocated_tiles() == 0u);
    CHECK(cube.statistics().misses == 100u);
}

TEST_CASE("a face smaller than a tile has one tile, and its texels map into it") {
    CctCube cube(5);
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < 5; ++row)
            for (int column = 0; column < 5; ++column) CHECK(cube.store_at(TexelAddress{face, column, row}, grey));
    CHECK(cube.allocated_tiles() == 6u);
    CHECK(cube.valid_texels() == 150u);
    cube.begin_frame();
    for (int face = 0; face < 6; ++face) CHECK(cube.peek_at(TexelAddress{face, 4, 4}));
}

TEST_CASE("clear gives every tile back to the cube and to its budget") {
    auto budget = std::make_shared<MemoryBudget>(1u << 20);
    CctCube cube(32, budget);
    const std::size_t table = budget->used(); // the cube's fixed part: 6 faces x 2 x 2 tile pointers, bitmaps, counters
    CHECK(table == CctCube::fixed_bytes(32));
    for (int face = 0; face < 6; ++face) cube.store_at(TexelAddress{face, 0, 0}, grey);
    CHECK(budget->used() == table + 6 * cct_tile);
    cube.clear();
    CHECK(cube.allocated_tiles() == 0u);
    CHECK(budget->used() == table);
    CHECK_FALSE(cube.load(TexelAddress{0, 0, 0}));
}

TEST_CASE("a cube's fixed part grows by a table entry a tile and a bitmap word per 64 tiles, within the planners' bounds, and is what its budget is charged before any tile") {
    // By hand: 6 ceil(N / 16)^2 tiles; each takes an 8-byte table pointer, and two bitmaps take a 64-bit word
    // for every 64 tiles or part of 64. 16 -> 6 tiles (1 word each), 32 -> 24 (1), 64 -> 96 (2), 91 -> 216 (4).
    CHECK(CctCube::fixed_bytes(32) - CctCube::fixed_bytes(16) == (24u - 6u) * 8u);
    CHECK(CctCube::fixed_bytes(64) - CctCube::fixed_bytes(32) == (96u - 24u) * 8u + 2u * 8u);
    CHECK(CdctCube::fixed_bytes(91) - CdctCube::fixed_bytes(64) == (216u - 96u) * 8u + 2u * 2u * 8u);
    CHECK(CctCube::fixed_bytes(1) == CctCube::fixed_bytes(16)); // one tile a face below 16 texels
    // The bounds SceneCache plans budgets with hold for every face size.
    for (int n = 1; n <= 4096; ++n) {
        const std::size_t tiles = 6u * static_cast<std::size_t>((n + 15) / 16) * static_cast<std::size_t>((n + 15) / 16);
        CHECK(CctCube::fixed_bytes(n) <= CctCube::fixed_bytes_per_cube() + tiles * CctCube::fixed_bytes_per_tile);
        CHECK(CdctCube::fixed_bytes(n) <= CdctCube::fixed_bytes_per_cube() + tiles * CdctCube::fixed_bytes_per_tile);
    }
    auto budget = std::make_shared<MemoryBudget>(1u << 20);
    {
        CdctCube cube(45, budget);
        CHECK(budget->used() == CdctCube::fixed_bytes(45));
        CHECK(cube.bytes() == CdctCube::fixed_bytes(45));
        CHECK(cube.store_at(TexelAddress{2, 40, 40}, raycache::DepthSample{grey, 1.0f}));
        CHECK(budget->used() == cube.bytes());
        CHECK(cube.bytes() == CdctCube::fixed_bytes(45) + cdct_tile);
    }
    CHECK(budget->used() == 0u);
}

TEST_CASE("a budget that holds one tile refuses the second tile's stores, the frame's first tile comes back empty, and fills") {
    auto budget = std::make_shared<MemoryBudget>(CctCube::fixed_bytes(32) + cct_tile);
    {
        CctCube cube(32, budget);
        CHECK(cube.store_at(TexelAddress{0, 0, 0}, grey));
        CHECK(cube.store_at(TexelAddress{0, 15, 15}, grey)); // same tile
        CHECK_FALSE(cube.store_at(TexelAddress{0, 16, 0}, grey)); // next tile: over the budget
        CHECK_FALSE(cube.store_at(TexelAddress{4, 3, 3}, grey));
        CHECK(cube.statistics().refused_stores == 2u);
        CHECK(cube.statistics().stores == 2u);
        CHECK(cube.allocated_tiles() == 1u);
        CHECK(budget->used() == budget->limit());
        cube.begin_frame(); // a refused frame: its tile is given back, and tile 0 (the first wanted) allocated empty
        CHECK(cube.allocated_tiles() == 1u);
        CHECK(budget->used() == budget->limit());
        CHECK_FALSE(cube.lookup(texel_direction(TexelAddress{0, 16, 0}, 32)));
        CHECK_FALSE(cube.lookup(texel_direction(TexelAddress{0, 15, 15}, 32)));
        CHECK(cube.store_at(TexelAddress{0, 15, 15}, grey)); // the next frame's stores fill it
        cube.begin_frame();
        CHECK(cube.lookup(texel_direction(TexelAddress{0, 15, 15}, 32)));
    }
    CHECK(budget->used() == 0u); // the destroyed cube gave everything back
}

TEST_CASE("cubes sharing a budget draw on it together") {
    const std::size_t fixed = CdctCube::fixed_bytes(16); // one tile a face: a table of 6 x 8 bytes, bitmaps, counters
    auto budget = std::make_shared<MemoryBudget>(2 * fixed + 33000);
    CdctCube a(16, budget), b(16, budget);
    CHECK(budget->used() == 2u * fixed);
    // 33000 bytes left: four CDCT tiles (32544), not five (40680).
    int stored = 0;
    for (int face = 0; face < 6; ++face) {
        stored += a.store_at(TexelAddress{face, 1, 1}, raycache::DepthSample{grey, 1.0f});
        stored += b.store_at(TexelAddress{face, 1, 1}, raycache::DepthSample{grey, 1.0f});
    }
    CHECK(stored == 4);
    CHECK(a.allocated_tiles() + b.allocated_tiles() == 4u);
    CHECK(budget->used() == 2u * fixed + 4u * cdct_tile);
}

TEST_CASE("try_reserve takes bytes only when they fit, and release gives them back") {
    MemoryBudget budget(100);
    CHECK(budget.try_reserve(60));
    CHECK_FALSE(budget.try_reserve(41));
    CHECK(budget.try_reserve(40));
    CHECK_FALSE(budget.try_reserve(1));
    CHECK_FALSE(budget.try_reserve(static_cast<std::size_t>(-1)));
    budget.release(100);
    CHECK(budget.used() == 0u);
    budget.reserve_always(150); // the fixed part of a cube: granted past the limit
    CHECK(budget.used() == 150u);
    CHECK_FALSE(budget.try_reserve(1));
}

// The texel walks skip tiles never stored into and read whole rows of a tile's written bits at once; what
// they visit, and in which order, must stay what a walk over every texel of every face finds.
TEST_CASE("for_each_written_texel (whole, and band by band) and for_each_valid_texel visit, in linear-index order, exactly the texels a walk over every texel finds") {
    for (int n : {5, 16, 37, 64}) {
        CAPTURE(n);
        CctCube cube(n);
        std::uint32_t seed = 12345u;
        auto next = [&seed] { return seed = seed * 1664525u + 1013904223u; };
        // Texels stored in earlier frames (valid, not written), some of them emptied between frames, and this
        // frame (valid and written), scattered.
        for (int frame = 0; frame < 2; ++frame) {
            for (int i = 0; i < 3 * n; ++i) {
                const TexelAddress t{static_cast<int>(next() % 6u), static_cast<int>(next() % n), static_cast<int>(next() % n)};
                cube.store_at(t, grey);
            }
            cube.begin_frame();
            for (int i = 0; i < n; ++i)
                cube.invalidate(TexelAddress{static_cast<int>(next() % 6u), static_cast<int>(next() % n), static_cast<int>(next() % n)});
        }
        for (int i = 0; i < 2 * n; ++i) {
            const TexelAddress t{static_cast<int>(next() % 6u), static_cast<int>(next() % n), static_cast<int>(next() % n)};
            cube.store_at(t, grey);
        }
        std::vector<std::uint64_t> expected_written, expected_valid, written, valid;
        auto index = [n](const TexelAddress& t) {
            return (static_cast<std::uint64_t>(t.face) * n + t.row) * n + t.column;
        };
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column) {
                    const TexelAddress t{face, column, row};
                    if (!cube.load(t)) continue;
                    expected_valid.push_back(index(t));
                    if (!cube.peek_at(t)) expected_written.push_back(index(t)); // holds a value no lookup sees yet
                }
        cube.for_each_written_texel([&](const TexelAddress& t) { written.push_back(index(t)); });
        cube.for_each_valid_texel([&](const TexelAddress& t) { valid.push_back(index(t)); });
        CHECK(written.size() > 0u);
        CHECK(valid.size() > written.size());
        CHECK(written == expected_written); // same texels, same (linear) order
        CHECK(valid == expected_valid);
        // Band b is tile row b % T of face b / T (T tiles to an edge): band by band, in order, the same walk.
        const int per_edge = (n + 15) / 16;
        REQUIRE(cube.tile_bands() == 6 * per_edge);
        std::vector<std::uint64_t> by_bands;
        int outside = 0;
        for (int b = 0; b < cube.tile_bands(); ++b)
            cube.for_each_written_texel_in_bands(b, b + 1, [&](const TexelAddress& t) {
                outside += t.face != b / per_edge || t.row / 16 != b % per_edge;
                by_bands.push_back(index(t));
            });
        CHECK(outside == 0);
        CHECK(by_bands == expected_written);
    }
}

// Under a full budget, which tiles a frame's stores allocate first depends on thread timing. So a frame in
// which the budget refused a tile keeps none of the tiles it allocated: they are given back between frames,
// and the tiles the frame wanted are allocated again, empty, in tile order, as far as the budget goes.
TEST_CASE("a frame the budget refused gives back its new tiles and allocates the tiles it wanted, empty, in tile order") {
    const TexelAddress a{0, 16, 0}, b{0, 0, 0}, c{4, 3, 3}; // tiles 1, 0 and 16 of a 32-texel cube
    for (const bool reversed : {false, true}) {
        CAPTURE(reversed);
        auto budget = std::make_shared<MemoryBudget>(CctCube::fixed_bytes(32) + 2u * cct_tile); // the fixed part and two tiles
        CctCube cube(32, budget);
        const TexelAddress order[3] = {reversed ? c : a, b, reversed ? a : c};
        int stored = 0;
        for (const TexelAddress& t : order) stored += cube.store_at(t, grey);
        CHECK(stored == 2); // the third tile does not fit, whichever it is
        cube.begin_frame();
        // Tiles 0 and 1 (the first two of the three wanted, in tile order) are held, empty.
        CHECK(cube.allocated_tiles() == 2u);
        CHECK(cube.valid_texels() == 0u);
        CHECK(budget->used() == budget->limit());
        for (const TexelAddress& t : {a, b, c}) CHECK_FALSE(cube.lookup(texel_direction(t, 32)));
        // The next frame's stores land in them; tile 16 is still refused.
        CHECK(cube.store_at(a, grey));
        CHECK(cube.store_at(b, grey));
        CHECK_FALSE(cube.store_at(c, grey));
        cube.begin_frame();
        CHECK(cube.lookup(texel_direction(a, 32)));
        CHECK(cube.lookup(texel_direction(b, 32)));
        CHECK_FALSE(cube.lookup(texel_direction(c, 32)));
        CHECK(cube.valid_texels() == 2u);
    }
}

TEST_CASE("under a full budget the texels a cube keeps are the same with one thread or four, in any order") {
    constexpr int n = 64; // 96 tiles; the budget holds 20
    std::vector<TexelAddress> texels;
    for (int face = 0; face < 6; ++face)
        for (int row = 1; row < n; row += 7)
            for (int column = 2; column < n; column += 9) texels.push_back(TexelAddress{face, column, row});
    // Two frames of the same stores; returns the valid texels' linear indices after them.
    auto run = [&](int threads, std::uint32_t seed) {
        auto budget = std::make_shared<MemoryBudget>(CctCube::fixed_bytes(n) + 20 * cct_tile);
        CctCube cube(n, budget);
        std::vector<TexelAddress> mine = texels;
        for (std::size_t i = mine.size(); i > 1; --i) { // a shuffle of its own per run
            seed = seed * 1664525u + 1013904223u;
            std::swap(mine[i - 1], mine[seed % i]);
        }
        for (int frame = 0; frame < 2; ++frame) {
            std::vector<std::thread> pool;
            for (int k = 0; k < threads; ++k)
                pool.emplace_back([&, k] {
                    for (std::size_t i = static_cast<std::size_t>(k); i < mine.size(); i += static_cast<std::size_t>(threads))
                        cube.store_at(mine[i], grey);
                });
            for (std::thread& t : pool) t.join();
            cube.begin_frame();
        }
        std::vector<std::uint64_t> kept;
        cube.for_each_valid_texel([&](const TexelAddress& t) { kept.push_back((std::uint64_t(t.face) * n + t.row) * n + t.column); });
        return kept;
    };
    const std::vector<std::uint64_t> reference = run(1, 1u);
    CHECK(reference.size() > 0u);
    CHECK(reference.size() < texels.size());
    for (std::uint32_t seed = 2; seed < 10; ++seed) {
        CAPTURE(seed);
        CHECK(run(4, seed) == reference);
        CHECK(run(1, seed) == reference);
    }
}

TEST_CASE("a texel's answer record is the union of its record block's paths, or unbounded when its store brought none") {
    // Texels (0, 0) and (1, 1) of face +X share a 2 x 2 block; (0, 0) was stored with a path that hit object
    // 3 at (2, 0, 0), (1, 1) with one that hit object 4 at (0, 5, 0) and cast a shadow ray; (4, 4) without a
    // record. Both recorded texels answer with the block's union; (4, 4) with an unbounded record.
    CctCube cube(16);
    raycache::PathRecord three, four;
    three.hit(3, glm::vec3(2, 0, 0));
    four.hit(4, glm::vec3(0, 5, 0));
    four.lit = true;
    REQUIRE(cube.store_at(TexelAddress{0, 0, 0}, grey, three));
    REQUIRE(cube.store_at(TexelAddress{0, 1, 1}, grey, four));
    REQUIRE(cube.store_at(TexelAddress{0, 4, 4}, grey));
    cube.begin_frame();
    for (const TexelAddress t : {TexelAddress{0, 0, 0}, TexelAddress{0, 1, 1}}) {
        const raycache::PathRecord r = cube.answer_record(t);
        CHECK(r.objects == (raycache::object_bits(3) | raycache::object_bits(4)));
        CHECK(r.vertex_lo == glm::vec3(0, 0, 0));
        CHECK(r.vertex_hi == glm::vec3(2, 5, 0));
        CHECK(r.lit);
        CHECK_FALSE(r.unbounded);
        CHECK(r.cached_reads == raycache::every_direction_cell); // neither path tracked its cached reads
    }
    CHECK(cube.answer_record(TexelAddress{0, 4, 4}).unbounded);
    CHECK(cube.answer_record(TexelAddress{1, 4, 4}).unbounded); // no tile there
    CctCube none(16, nullptr, false);
    REQUIRE(none.store_at(TexelAddress{0, 0, 0}, grey, three));
    none.begin_frame();
    CHECK(none.answer_record(TexelAddress{0, 0, 0}).unbounded); // a cube without records knows nothing
}

TEST_CASE("a tile's paths are the union of its blocks' records, none for a tile never allocated, empty without records") {
    // Face +X of a 32-texel cube has 2 x 2 tiles of 16 x 16 texels, tile 1 to the right of tile 0. Tile 0
    // holds (0, 0), whose path hit object 3 at (2, 0, 0), and (9, 9), another block's, whose path hit object
    // 4 at (0, 5, 0) and escaped along +y; tile 1 holds (20, 3) alone, stored without a record.
    CctCube cube(32);
    raycache::PathRecord three, four;
    three.hit(3, glm::vec3(2, 0, 0));
    four.hit(4, glm::vec3(0, 5, 0));
    four.escaped(glm::vec3(0, 2, 0));
    REQUIRE(cube.store_at(TexelAddress{0, 0, 0}, grey, three));
    REQUIRE(cube.store_at(TexelAddress{0, 9, 9}, grey, four));
    REQUIRE(cube.store_at(TexelAddress{0, 20, 3}, grey));
    cube.begin_frame();
    const std::optional<raycache::PathRecord> first = cube.tile_paths(0);
    REQUIRE(first);
    CHECK(first->objects == (raycache::object_bits(3) | raycache::object_bits(4)));
    CHECK(first->vertex_lo == glm::vec3(0, 0, 0));
    CHECK(first->vertex_hi == glm::vec3(2, 5, 0));
    CHECK(first->escape_lo == glm::vec3(0, 1, 0));
    CHECK(first->escape_hi == glm::vec3(0, 1, 0));
    CHECK_FALSE(first->lit);
    CHECK_FALSE(first->unbounded);
    const std::optional<raycache::PathRecord> second = cube.tile_paths(1);
    REQUIRE(second); // allocated, but no store brought a record: nothing in its union
    CHECK(second->objects == 0);
    CHECK_FALSE(second->has_vertices());
    CHECK(second->cached_reads == 0);
    CHECK_FALSE(cube.tile_paths(2)); // never stored into
    // The same union in the form the tile keeps it: its boxes, flags, objects and cells as above.
    const std::optional<CctCube::PathKeys> keys = cube.tile_keys(0);
    REQUIRE(keys);
    CHECK(keys->objects == first->objects);
    CHECK(keys->has_vertices());
    CHECK(keys->has_escapes());
    CHECK_FALSE(keys->unbounded());
    CHECK(keys->record().vertex_hi == glm::vec3(2, 5, 0));
    CHECK(keys->record().escape_lo == glm::vec3(0, 1, 0));
    REQUIRE(cube.tile_keys(1));
    CHECK_FALSE(cube.tile_keys(1)->has_vertices());
    CHECK_FALSE(cube.tile_keys(1)->has_escapes());
    CHECK_FALSE(cube.tile_keys(2));
    CctCube none(32, nullptr, false);
    REQUIRE(none.store_at(TexelAddress{0, 0, 0}, grey, three));
    none.begin_frame();
    const std::optional<raycache::PathRecord> bare = none.tile_paths(0);
    REQUIRE(bare);
    CHECK(bare->objects == 0); // a cube without records keeps no union
    REQUIRE(none.tile_keys(0));
    CHECK(none.tile_keys(0)->objects == 0);
    CHECK_FALSE(none.tile_keys(0)->has_vertices());
}
