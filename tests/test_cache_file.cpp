// Cache files (raycache/cache_file.hpp): a saved cube comes back bit for bit; a file for another scene,
// object, placement, technique or a newer format is refused with a message and loads nothing; so is every
// truncation and every corruption tried; a save killed at any moment leaves the old file or the new one.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "raycache/raycache.hpp"
#include "test_cache_files.hpp"
#include "test_random.hpp"

namespace {

using raycache::CacheCube;
using raycache::CacheFileError;
using raycache::CctCube;
using raycache::CctTexel;
using raycache::CdctCube;
using raycache::CdctTexel;
using raycache::CubeBounds;
using raycache::CubeToSave;
using raycache::SceneIdentity;
using raycache::TexelAddress;

const SceneIdentity scene{0x0123456789abcdefull, "test scene"};
const CubeBounds bounds{glm::vec3(1.0f, 2.0f, -3.5f), 0.75f};

template <class Texel>
std::vector<std::uint8_t> encode_one(const CacheCube<Texel>& cube, std::uint64_t object = 7) {
    return raycache::encode_cache<Texel>(scene, {CubeToSave<Texel>{object, bounds, &cube}});
}

template <class Texel>
std::vector<raycache::LoadedCube<Texel>> decode(const std::vector<std::uint8_t>& bytes, const SceneIdentity& expected = scene) {
    return raycache::decode_cache<Texel>(bytes.data(), bytes.size(), expected);
}

// A small CDCT file: a 20-texel cube (partial tiles at the edges) with a few dozen texels.
std::vector<std::uint8_t> small_file() {
    CdctCube cube(20);
    Lcg rng{5};
    fill_randomly(cube, rng, 15);
    return encode_one(cube);
}

template <class Texel>
void check_round_trip(int face_size, unsigned per_mille, std::uint64_t seed) {
    CAPTURE(face_size);
    ScratchFolder folder("round-trip");
    CacheCube<Texel> cube(face_size);
    Lcg rng{seed};
    std::size_t visible = fill_randomly(cube, rng, per_mille);
    // Some stores with the origins they left from (tiles keep their box), some texels marked doubtful.
    for (int k = 0; k < 20; ++k) {
        const glm::vec3 d(rng.signed_uniform(), rng.signed_uniform(), rng.signed_uniform() + 0.01f);
        typename Texel::Value value{};
        if constexpr (std::is_same_v<Texel, CctTexel>) value = glm::vec3(0.5f);
        else value = raycache::DepthSample{glm::vec3(0.5f), 3.0f};
        const glm::vec3 origin(rng.signed_uniform(), 2.0f, rng.signed_uniform());
        // Half of them with the distance to what they hit: their tiles keep the nearest (format 2).
        visible += k % 2 ? cube.store(d, value, origin) : cube.store(d, value, origin, 0.5f + 0.25f * static_cast<float>(k));
    }
    cube.begin_frame();
    cube.for_each_valid_texel([&](const TexelAddress& t) {
        if (rng.next() % 7 == 0) cube.set_doubtful(t);
    });
    const std::size_t this_frame = fill_randomly(cube, rng, per_mille / 2 + 1); // not visible yet: saved too
    REQUIRE(visible + this_frame > 0);
    REQUIRE(cube.doubtful_texels() > 0);
    raycache::save_cube(folder.file("cube.rcc"), cube, bounds, scene, 7);

    CacheCube<Texel> loaded(1);
    raycache::load_cube(folder.file("cube.rcc"), loaded, bounds, scene, 7);
    CHECK(loaded.face_size() == face_size);
    CHECK(same_texels(cube, loaded));
    CHECK(same_marks_and_origins(cube, loaded));
    CHECK(loaded.valid_texels() == cube.valid_texels());
    CHECK(loaded.doubtful_texels() == cube.doubtful_texels());
    CHECK(loaded.allocated_tiles() <= cube.allocated_tiles());
    // Every loaded texel answers lookups at once, and the counters start at zero.
    std::size_t visible_now = 0;
    loaded.for_each_valid_texel([&](const TexelAddress& t) { visible_now += loaded.peek_at(t).has_value(); });
    CHECK(visible_now == cube.valid_texels() - cube.doubtful_texels()); // doubtful texels read as empty
    CHECK(loaded.statistics().lookups == 0u);
    CHECK(loaded.statistics().stores == 0u);
}


// The little-endian u64 at byte `at` of `bytes`.
std::uint64_t u64_at(const std::vector<std::uint8_t>& bytes, std::size_t at) {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= std::uint64_t{bytes[at + i]} << (8 * i);
    return v;
}

// Where a file's first CUBE chunk starts (after the prelude and the HEAD chunk), where its payload starts,
// and the payload's size.
struct CubeChunk {
    std::size_t start, payload, size;
};
CubeChunk first_cube_chunk(const std::vector<std::uint8_t>& bytes) {
    const std::size_t head = 16; // after the prelude
    const std::size_t cube = head + 4 + 8 + u64_at(bytes, head + 4) + 8;
    return {cube, cube + 12, u64_at(bytes, cube + 4)};
}

// `bytes` relabelled as format `version`, the prelude's checksum made right.
std::vector<std::uint8_t> with_version(std::vector<std::uint8_t> bytes, std::uint32_t version) {
    for (int i = 0; i < 4; ++i) bytes[8 + i] = static_cast<std::uint8_t>(version >> (8 * i));
    const auto check = static_cast<std::uint32_t>(raycache::fnv1a64(bytes.data(), 12));
    for (int i = 0; i < 4; ++i) bytes[12 + i] = static_cast<std::uint8_t>(check >> (8 * i));
    return bytes;
}
} // namespace

TEST_CASE("a CCT cube saved and loaded back holds every texel bit for bit, visible at once") {
    for (int n : {1, 2, 15, 16, 17, 37, 64}) check_round_trip<CctTexel>(n, 300, 11 + static_cast<unsigned>(n));
}

TEST_CASE("a CDCT cube saved and loaded back holds every texel bit for bit, visible at once") {
    for (int n : {1, 3, 16, 20, 33, 48}) check_round_trip<CdctTexel>(n, 300, 97 + static_cast<unsigned>(n));
}

TEST_CASE("a full cube and an empty cube round trip") {
    CctCube full(18), empty(18);
    Lcg rng{3};
    CHECK(fill_randomly(full, rng, 1000) == full.texel_count());
    for (const CctCube* cube : {&full, &empty}) {
        std::vector<raycache::LoadedCube<CctTexel>> back = decode<CctTexel>(encode_one(*cube));
        REQUIRE(back.size() == 1u);
        CHECK(same_texels(*cube, *back[0].cube));
        CHECK(back[0].object == 7u);
        CHECK(raycache::same_placement(back[0].bounds, bounds));
    }
}

TEST_CASE("a cache file is sparse: a 4096-texel cube holding one texel takes one tile of bytes") {
    CdctCube cube(4096);
    CHECK(cube.store(glm::vec3(0.3f, -1.0f, 0.2f), raycache::DepthSample{glm::vec3(0.5f), 2.0f}));
    const std::vector<std::uint8_t> bytes = encode_one(cube);
    CHECK(bytes.size() < 16 * 16 * 8 + 300); // its words (stored without a path record: no record block written)
    std::vector<raycache::LoadedCube<CdctTexel>> back = decode<CdctTexel>(bytes);
    REQUIRE(back.size() == 1u);
    CHECK(back[0].cube->face_size() == 4096);
    CHECK(back[0].cube->allocated_tiles() == 1u);
    CHECK(back[0].cube->valid_texels() == 1u);
}

TEST_CASE("several cubes in one file come back with their own object ids, parts and placements") {
    CctCube a(8), b(30), c(3);
    Lcg rng{17};
    fill_randomly(a, rng, 500);
    fill_randomly(b, rng, 100);
    fill_randomly(c, rng, 500);
    const CubeBounds other{glm::vec3(-4.0f, 0.0f, 9.0f), 2.0f};
    // b and c are two parts of one object (as primitive ranges of one geometry are).
    const std::vector<std::uint8_t> bytes = raycache::encode_cache<CctTexel>(
        scene, {CubeToSave<CctTexel>{1, bounds, &a}, CubeToSave<CctTexel>{1ull << 40, other, &b, 3}, CubeToSave<CctTexel>{1ull << 40, bounds, &c, 4}});
    std::vector<raycache::LoadedCube<CctTexel>> back = decode<CctTexel>(bytes);
    REQUIRE(back.size() == 3u);
    CHECK(back[0].object == 1u);
    CHECK(back[0].part == 0u);
    CHECK(back[1].object == 1ull << 40);
    CHECK(back[1].part == 3u);
    CHECK(back[2].part == 4u);
    CHECK(raycache::same_placement(back[1].bounds, other));
    CHECK(same_texels(a, *back[0].cube));
    CHECK(same_texels(b, *back[1].cube));
    CHECK(same_texels(c, *back[2].cube));
    CHECK_THROWS_AS(raycache::encode_cache<CctTexel>(scene, {CubeToSave<CctTexel>{5, bounds, &a, 1}, CubeToSave<CctTexel>{5, other, &b, 1}}),
                    std::invalid_argument);
}

TEST_CASE("a file saved for another scene, object, placement or technique is refused by name and loads nothing") {
    ScratchFolder folder("refused");
    CdctCube saved(12);
    Lcg rng{23};
    fill_randomly(saved, rng, 400);
    const std::string path = folder.file("cube.rcc");
    raycache::save_cube(path, saved, bounds, scene, 7);

    CdctCube target(5);
    fill_randomly(target, rng, 500);
    target.begin_frame();
    CdctCube before(5);
    target.for_each_valid_texel([&](const TexelAddress& t) { before.store_word_at(t, target.load_word(t)); });

    const std::string other_hash = cache_file_error([&] {
        raycache::load_cube(path, target, bounds, SceneIdentity{scene.hash + 1, scene.name}, 7);
    });
    CHECK(contains(other_hash, "saved for scene 'test scene' (hash 0x0123456789abcdef)"));
    CHECK(contains(other_hash, path));
    CHECK(contains(cache_file_error([&] { raycache::load_cube(path, target, bounds, SceneIdentity{scene.hash, "other"}, 7); }),
                   "this is scene 'other'"));
    CHECK(contains(cache_file_error([&] { raycache::load_cube(path, target, bounds, scene, 8); }), "its cube is object 7, not object 8"));
    CubeBounds moved = bounds;
    moved.centre.x = std::nextafter(moved.centre.x, 10.0f); // one ulp away is another placement
    CHECK(contains(cache_file_error([&] { raycache::load_cube(path, target, moved, scene, 7); }), "sits at centre"));
    CctCube cct(5);
    CHECK(contains(cache_file_error([&] { raycache::load_cube(path, cct, bounds, scene, 7); }), "holds CDCT cubes, this cache is CCT"));
    CHECK(cct.valid_texels() == 0u);

    // The target kept its face size and every texel, visible as before.
    CHECK(target.face_size() == 5);
    CHECK(same_texels(before, target));
    std::size_t visible = 0;
    target.for_each_valid_texel([&](const TexelAddress& t) { visible += target.peek_at(t).has_value(); });
    CHECK(visible == before.valid_texels());
}

TEST_CASE("a file of a newer or unknown format version is refused, saying which") {
    const std::vector<std::uint8_t> bytes = small_file();
    CHECK(decode<CdctTexel>(with_version(bytes, 5)).size() == 1u);
    CHECK(decode<CdctTexel>(with_version(bytes, 4)).size() == 1u); // no path record: formats 4 and 5 agree
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_version(bytes, 6)); }), "format version 6 is newer than this RayCache reads (5)"));
    // A format-5 file relabelled as format 3, 2 or 1 does not parse as one (format 3's tiles always carry
    // sixteen records, where this one's say none; formats 1 and 2 lack the cubes' 8 bytes of reach, so they
    // read them as the tile count and a tile).
    CHECK_FALSE(cache_file_error([&] { decode<CdctTexel>(with_version(bytes, 3)); }).empty());
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_version(bytes, 2)); }), "tiles"));
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_version(bytes, 1)); }), "tiles"));
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_version(bytes, 0)); }), "unknown format version 0"));
    std::vector<std::uint8_t> not_ours = bytes;
    not_ours[0] = 'X';
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(not_ours); }), "not a RayCache cache file"));
}

namespace {
// A checked-in fuzz seed (fuzz/corpus/cache_file/NAME): one byte choosing the technique, then a cache file.
std::vector<std::uint8_t> seed_file(const std::string& name) {
    const std::string path = std::string(RAYCACHE_SOURCE_DIR) + "/fuzz/corpus/cache_file/" + name;
    std::FILE* f = std::fopen(path.c_str(), "rb");
    REQUIRE(f);
    std::vector<std::uint8_t> bytes;
    for (int c; (c = std::fgetc(f)) != EOF;) bytes.push_back(static_cast<std::uint8_t>(c));
    std::fclose(f);
    REQUIRE(bytes.size() > 17);
    bytes.erase(bytes.begin());
    return bytes;
}

// `bytes` (one CUBE chunk after the HEAD chunk) with the CUBE payload's 32 bits at `offset` replaced and
// the chunk's checksum made right again, so that only the value is wrong.
std::vector<std::uint8_t> with_cube_bits(std::vector<std::uint8_t> bytes, std::size_t offset, std::uint32_t bits) {
    const auto [cube, payload, size] = first_cube_chunk(bytes);
    for (int i = 0; i < 4; ++i) bytes[payload + offset + i] = static_cast<std::uint8_t>(bits >> (8 * i));
    const std::uint64_t check = raycache::fnv1a64(bytes.data() + cube, 12 + size);
    for (int i = 0; i < 8; ++i) bytes[payload + size + i] = static_cast<std::uint8_t>(check >> (8 * i));
    return bytes;
}
std::vector<std::uint8_t> with_cube_float(const std::vector<std::uint8_t>& bytes, std::size_t offset, float value) {
    std::uint32_t bits;
    std::memcpy(&bits, &value, 4);
    return with_cube_bits(bytes, offset, bits);
}
// Payload offsets of a CUBE chunk (format 5): its first tile's count of record blocks (after object,
// part, face size, placement, reach, tile count; the tile's index, origin flag and box, nearest distance
// and doubtful marks), then its first record block's flag, path flags, boxes and cached reads, and the
// second's flag and path flags (records are 72 bytes).
constexpr std::size_t record_count = 116, first_block_flag = 120, first_block_path_flags = 124, first_block_boxes = 136;
constexpr std::size_t first_block_reads = first_block_boxes + 48;
constexpr std::size_t second_block_flag = first_block_flag + 72, second_block_path_flags = first_block_path_flags + 72;
} // namespace

TEST_CASE("a format-1 file (saved before tiles kept their nearest hit distance) still loads, with no distances") {
    // Written by raycache_fuzz_make_seeds at format 1 and checked in as a fuzz seed: a CDCT file whose
    // tiles, in format 1, have no nearest distance.
    std::vector<std::uint8_t> bytes = seed_file("cdct-edge-tiles-format1");
    CHECK(bytes[8] == 1); // the format version, little-endian
    const std::vector<raycache::LoadedCube<CdctTexel>> cubes = decode<CdctTexel>(bytes, SceneIdentity{0x5eed5eed5eed5eedull, "fuzz"});
    REQUIRE_FALSE(cubes.empty());
    std::size_t texels = 0;
    for (const auto& c : cubes)
        c.cube->for_each_valid_texel([&](const TexelAddress& t) {
            ++texels;
            CHECK(c.cube->nearest_hit(t) == std::numeric_limits<float>::infinity());
        });
    CHECK(texels > 0u);
}


TEST_CASE("a cube's origin reach survives a save: format 3 keeps how far out its rays left and how far out it answers") {
    CdctCube cube(20);
    Lcg rng{11};
    fill_randomly(cube, rng, 15);
    CubeToSave<CdctTexel> limited{7, bounds, &cube, 0, 0.8125f, 0.828125f};
    CubeToSave<CdctTexel> open{8, bounds, &cube, 0, 0.5f, std::numeric_limits<float>::infinity()};
    const std::vector<std::uint8_t> bytes = raycache::encode_cache<CdctTexel>(scene, {limited, open});
    const auto cubes = decode<CdctTexel>(bytes);
    REQUIRE(cubes.size() == 2u);
    CHECK(cubes[0].origins_seen == 0.8125f);
    CHECK(cubes[0].origins_limit == 0.828125f);
    CHECK(cubes[1].origins_seen == 0.5f);
    CHECK(cubes[1].origins_limit == std::numeric_limits<float>::infinity());
    // A limit that is not > 0 is not written as none (that would let the texels answer rays no move was
    // checked for); a reach not known (NaN) is written as infinity.
    CHECK_THROWS_AS(raycache::encode_cache<CdctTexel>(scene, {CubeToSave<CdctTexel>{7, bounds, &cube, 0, 0.5f, 0.0f}}),
                    std::invalid_argument);
    CHECK_THROWS_AS(raycache::encode_cache<CdctTexel>(scene, {CubeToSave<CdctTexel>{7, bounds, &cube, 0, 0.5f, std::nanf("")}}),
                    std::invalid_argument);
    const auto unknown = decode<CdctTexel>(raycache::encode_cache<CdctTexel>(scene, {CubeToSave<CdctTexel>{7, bounds, &cube, 0, std::nanf("")}}));
    CHECK(unknown[0].origins_seen == std::numeric_limits<float>::infinity());
    // Read back: a limit not > 0 or a reach below 0 (or NaN) is refused by name. The two floats follow the
    // object, part, face size and placement: payload bytes 36 and 40.
    const std::vector<std::uint8_t> one = encode_one(cube);
    REQUIRE(decode<CdctTexel>(with_cube_float(one, 36, 0.5f)).size() == 1u); // the patching itself is sound
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_float(one, 40, 0.0f)); }), "how far out the cube answers rays is not > 0"));
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_float(one, 40, std::nanf(""))); }), "answers rays is not > 0"));
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_float(one, 36, -1.0f)); }), "how far out the cube's rays left is not >= 0"));
}

TEST_CASE("a format-2 file (saved before cubes kept their origin reach) still loads, with no limit on its rays") {
    std::vector<std::uint8_t> bytes = seed_file("cdct-three-cubes-format2");
    CHECK(bytes[8] == 2); // the format version, little-endian
    const auto cubes = decode<CdctTexel>(bytes, SceneIdentity{0x5eed5eed5eed5eedull, "fuzz"});
    REQUIRE(cubes.size() == 3u);
    std::size_t texels = 0;
    for (const auto& c : cubes) {
        CHECK(c.origins_seen == std::numeric_limits<float>::infinity());
        CHECK(c.origins_limit == std::numeric_limits<float>::infinity());
        texels += c.cube->valid_texels();
    }
    CHECK(texels > 0u);
    // The format-3 seed of the same cubes says how far out every other one answers.
    const auto three = decode<CdctTexel>(seed_file("cdct-three-cubes-format3"), SceneIdentity{0x5eed5eed5eed5eedull, "fuzz"});
    REQUIRE(three.size() == 3u);
    CHECK(three[0].origins_limit == std::numeric_limits<float>::infinity());
    CHECK(three[1].origins_limit == doctest::Approx(1.02f * 0.26f));
    CHECK(three[1].origins_seen == doctest::Approx(0.26f));
}

TEST_CASE("a loaded cube keeps its blocks' path records: a move that no recorded path met keeps their texels") {
    // Three texels in three blocks of a 16-texel CCT cube: +x, whose path hit object 5 at (3, 0, 0) and
    // cast a shadow ray; +y, whose path hit object 6 at (0, 3, 0), bounced on to (0, 3, 4) and escaped
    // along +z; -z, stored without a record. Object 6 then moves far off every texel's cone (from
    // (40, -40, 40) to (40, -40, 41), radius 0.5, with no light moving): the +y texel's record names it,
    // so it goes; the -z texel's store brought no record, so it goes; the +x texel stays. Before format 3
    // a loaded cube had no records, and lost all three.
    const std::uint64_t five = 5, six = 6;
    REQUIRE((raycache::object_bits(five) & raycache::object_bits(six)) != raycache::object_bits(six)); // no Bloom alias
    CctCube cube(16);
    raycache::PathRecord a, b;
    a.hit(five, glm::vec3(3.0f, 0.0f, 0.0f));
    a.lit = true;
    b.hit(six, glm::vec3(0.0f, 3.0f, 0.0f));
    b.hit(six, glm::vec3(0.0f, 3.0f, 4.0f));
    b.chained = true;
    b.escaped(glm::vec3(0.0f, 0.0f, 1.0f));
    b.track_cached_reads();
    b.read_cached(glm::vec3(0.0f, 0.0f, 1.0f), glm::vec3(0.0f, 0.0f, 1.0f)); // a cube answered its bounce toward +z
    REQUIRE(cube.store(glm::vec3(1, 0, 0), glm::vec3(0.5f), a));
    REQUIRE(cube.store(glm::vec3(0, 1, 0), glm::vec3(0.25f), b));
    REQUIRE(cube.store(glm::vec3(0, 0, -1), glm::vec3(0.75f)));
    cube.begin_frame();
    const CubeBounds unit{glm::vec3(0.0f), 1.0f};
    const auto loaded = decode<CctTexel>(raycache::encode_cache<CctTexel>(scene, {CubeToSave<CctTexel>{7, unit, &cube}}));
    REQUIRE(loaded.size() == 1u);
    CctCube& back = *loaded[0].cube;
    back.begin_frame();
    // The blocks' records come back as they were saved, field by field.
    std::vector<raycache::CacheCube<CctTexel>::BlockState> saved, read;
    cube.for_each_block_state([&](const auto& s) { saved.push_back(s); });
    back.for_each_block_state([&](const auto& s) { read.push_back(s); });
    REQUIRE(saved.size() == read.size());
    int recorded = 0;
    for (std::size_t i = 0; i < saved.size(); ++i) {
        CAPTURE(i);
        CHECK(saved[i].objects == read[i].objects);
        CHECK(saved[i].path_flags == read[i].path_flags);
        CHECK(saved[i].cached_reads == read[i].cached_reads);
        CHECK(saved[i].unrecorded_texels == read[i].unrecorded_texels);
        if (saved[i].objects) {
            ++recorded;
            CHECK(saved[i].vertex_lo == read[i].vertex_lo);
            CHECK(saved[i].vertex_hi == read[i].vertex_hi);
            CHECK(saved[i].escape_lo == read[i].escape_lo);
            CHECK(saved[i].escape_hi == read[i].escape_hi);
        }
    }
    CHECK(recorded == 2);
    // a tracked no cached read; b's read +Z's centre cell
    CHECK(std::count_if(read.begin(), read.end(), [](const auto& s) { return s.cached_reads == raycache::every_direction_cell; }) >= 1);
    CHECK(std::count_if(read.begin(), read.end(), [](const auto& s) { return s.cached_reads == raycache::direction_cell_bit(4, 1, 1); }) == 1);
    raycache::SceneChanges changes;
    changes.moved.push_back({six, {glm::vec3(40.0f, -40.0f, 40.0f), 0.5f}, {glm::vec3(40.0f, -40.0f, 41.0f), 0.5f}});
    changes.lights = {glm::vec3(0.0f, 100.0f, 0.0f)};
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(back, raycache::CubeRays{unit}, changes);
    CHECK(counts.dropped == 2);
    CHECK(counts.dropped_unrecorded == 1);
    CHECK(back.load(*back.texel_of(glm::vec3(1, 0, 0))).has_value());
    CHECK_FALSE(back.load(*back.texel_of(glm::vec3(0, 1, 0))).has_value());
    CHECK_FALSE(back.load(*back.texel_of(glm::vec3(0, 0, -1))).has_value());
}

// `bytes` (format 4, one cube of one tile written with no record block) as format 3 would have written
// it: sixteen 4 x 4 record blocks, the first holding `record`, the others none.
static std::vector<std::uint8_t> as_format3(const std::vector<std::uint8_t>& bytes, const raycache::PathRecord& record) {
    const auto [cube, payload, size] = first_cube_chunk(bytes);
    REQUIRE(u64_at(bytes, payload + record_count) % (std::uint64_t{1} << 32) == 0u); // no record block
    std::vector<std::uint8_t> out(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(payload + record_count));
    auto put = [&](std::uint64_t v, int n) {
        for (int i = 0; i < n; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    };
    put(1, 4);
    put(raycache::CctCube::path_flags_of(record), 4);
    put(record.objects, 8);
    for (const glm::vec3& corner : {record.vertex_lo, record.vertex_hi, record.escape_lo, record.escape_hi})
        for (int k = 0; k < 3; ++k) put(glm::floatBitsToUint(corner[k]), 4);
    out.insert(out.end(), 15 * 64, 0);
    out.insert(out.end(), bytes.begin() + static_cast<std::ptrdiff_t>(payload + record_count + 4),
               bytes.begin() + static_cast<std::ptrdiff_t>(payload + size));
    const std::uint64_t new_size = size - 4 + 16 * 64;
    for (int i = 0; i < 8; ++i) out[cube + 4 + i] = static_cast<std::uint8_t>(new_size >> (8 * i));
    put(raycache::fnv1a64(out.data() + cube, 12 + new_size), 8);
    out.insert(out.end(), bytes.begin() + static_cast<std::ptrdiff_t>(payload + size + 8), bytes.end()); // the END chunk
    return with_version(std::move(out), 3);
}

TEST_CASE("a format-3 file's 4 x 4 record block gives its record to each 2 x 2 block within it") {
    // Three texels of the +x face's first tile, stored without records: (1, 1) and (2, 3) lie in the file's
    // first 4 x 4 block (the cube's 2 x 2 blocks 0 and 9), (5, 1) in its second (the cube's block 2). The
    // format-3 file says the first 4 x 4 block's texels saw object 5 at (3, 0, 0) and cast a shadow ray.
    CctCube cube(16);
    for (const TexelAddress& t : {TexelAddress{0, 1, 1}, TexelAddress{0, 2, 3}, TexelAddress{0, 5, 1}}) REQUIRE(cube.store_at(t, glm::vec3(0.5f)));
    cube.begin_frame();
    raycache::PathRecord path;
    path.hit(5, glm::vec3(3.0f, 0.0f, 0.0f));
    path.lit = true;
    const auto loaded = decode<CctTexel>(as_format3(encode_one(cube), path));
    REQUIRE(loaded.size() == 1u);
    int blocks = 0;
    loaded[0].cube->for_each_block_state([&](const CctCube::BlockState& b) {
        if (b.valid_texels == 0) return;
        ++blocks;
        CAPTURE(b.block);
        if (b.block == 0 || b.block == 9) {
            CHECK(b.unrecorded_texels == 0);
            CHECK(b.objects == raycache::object_bits(5));
            CHECK(b.lit());
            CHECK(b.vertex_lo == glm::vec3(3.0f, 0.0f, 0.0f));
            CHECK(b.vertex_hi == glm::vec3(3.0f, 0.0f, 0.0f));
        } else {
            CHECK(b.block == 2);
            CHECK(b.unrecorded_texels == 1); // the file's second block holds none
        }
    });
    CHECK(blocks == 3);
}

TEST_CASE("a block record that is not one is refused by name") {
    CdctCube cube(20);
    Lcg rng{5};
    fill_randomly(cube, rng, 1000); // every texel stored without a record: each tile is written with no record block
    const std::vector<std::uint8_t> none = encode_one(cube);
    REQUIRE(decode<CdctTexel>(with_cube_bits(none, record_count, 0u)).size() == 1u); // the patching itself is sound
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_bits(none, record_count, 5u)); }), "has 5 record blocks (0 or 64)"));
    // A block with a record (a texel of the +x face's first tile stored with one: its first 2 x 2 block),
    // and its tile's other blocks written as none.
    CdctCube recorded(20);
    raycache::PathRecord path;
    path.hit(3, glm::vec3(2.0f, 0.0f, 0.0f));
    REQUIRE(recorded.store_at(TexelAddress{0, 1, 1}, raycache::DepthSample{glm::vec3(0.5f), 2.0f}, path));
    recorded.begin_frame();
    const std::vector<std::uint8_t> one = encode_one(recorded);
    REQUIRE(decode<CdctTexel>(one).size() == 1u);
    REQUIRE(decode<CdctTexel>(with_cube_bits(one, second_block_flag, 0u)).size() == 1u); // the second block holds none
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_bits(one, second_block_flag, 2u)); }), "record flag 2 (0 or 1)"));
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_bits(one, second_block_path_flags, 1u)); }),
                   "holds no record but is not all zero"));
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_bits(one, first_block_path_flags, 8u)); }), "has path flags 8"));
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_float(one, first_block_boxes, std::nanf(""))); }),
                   "boxes are neither empty"));
    // Cached reads name only the 54 direction cells; a block holding no record reads none.
    REQUIRE(decode<CdctTexel>(with_cube_bits(one, first_block_reads + 4, 0x003FFFFFu)).size() == 1u); // bits 32 to 53
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_bits(one, first_block_reads + 4, 0x00400000u)); }),
                   "cached reads beyond the 54 direction cells"));
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_bits(one, second_block_flag + 64, 1u)); }),
                   "holds no record but is not all zero"));
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_float(one, first_block_boxes, 5.0f)); }), // low > high
                   "boxes are neither empty"));
    // Hit points beyond 1e18 (invalidation's distances would overflow) and an escape box of no unit
    // direction (all zero) are refused too.
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(with_cube_float(one, first_block_boxes, -1e20f)); }),
                   "boxes are neither empty"));
    std::vector<std::uint8_t> zero_escapes = one;
    for (std::size_t k = 0; k < 6; ++k) zero_escapes = with_cube_float(zero_escapes, first_block_boxes + 24 + 4 * k, 0.0f);
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(zero_escapes); }), "reaching the unit sphere"));
}

TEST_CASE("records of a format-4 file load as having read every direction cell, a format-5 file's as saved") {
    // The fuzz seeds of both formats store one texel of each cube with a record (raycache_fuzz_make_seeds);
    // the format-5 ones tracked its cached reads: one, toward +x (+X's centre cell). Blocks where random
    // texels stored without a record sit beside it are written as holding none.
    for (const int format : {4, 5}) {
        CAPTURE(format);
        const std::vector<std::uint8_t> bytes = seed_file("cdct-edge-tiles-format" + std::to_string(format));
        const auto cubes = raycache::decode_cache<CdctTexel>(bytes.data(), bytes.size(), SceneIdentity{0x5eed5eed5eed5eedull, "fuzz"},
                                                             nullptr, "cache data", true); // into cubes that keep records
        REQUIRE_FALSE(cubes.empty());
        int recorded = 0;
        for (const auto& c : cubes)
            c.cube->for_each_block_state([&](const CdctCube::BlockState& b) {
                if (b.valid_texels == 0 || b.unrecorded_texels != 0) return;
                ++recorded;
                CHECK(b.cached_reads == (format == 4 ? raycache::every_direction_cell : raycache::direction_cell_bit(0, 1, 1)));
            });
        CHECK(recorded >= 1);
    }
}

TEST_CASE("a record a file cannot hold (hit points not finite) is saved as none, so its texels count as having seen anything") {
    CctCube cube(16);
    raycache::PathRecord far;
    far.hit(3, glm::vec3(std::numeric_limits<float>::infinity(), 0.0f, 0.0f));
    REQUIRE(cube.store(glm::vec3(1, 0, 0), glm::vec3(0.5f), far));
    cube.begin_frame();
    const auto loaded = decode<CctTexel>(encode_one(cube)); // loads: the record was left out, not the file refused
    REQUIRE(loaded.size() == 1u);
    int unrecorded = 0;
    loaded[0].cube->for_each_block_state([&](const auto& b) { unrecorded += b.unrecorded_texels; });
    CHECK(unrecorded == 1);
}

TEST_CASE("a file's path records are left out when it is loaded into cubes that keep none") {
    CctCube cube(16);
    raycache::PathRecord saw;
    saw.hit(3, glm::vec3(0.0f, 5.0f, 0.0f));
    REQUIRE(cube.store(glm::vec3(1, 0, 0), glm::vec3(0.5f), saw));
    cube.begin_frame();
    const std::vector<std::uint8_t> bytes = encode_one(cube);
    for (const bool records : {true, false}) {
        CAPTURE(records);
        const auto loaded = raycache::decode_cache<CctTexel>(bytes.data(), bytes.size(), scene, nullptr, "cache data", records);
        REQUIRE(loaded.size() == 1u);
        CHECK(loaded[0].cube->keeps_path_records() == records);
        int unrecorded = 0;
        std::uint64_t objects = 0;
        loaded[0].cube->for_each_block_state([&](const auto& b) {
            unrecorded += b.unrecorded_texels;
            objects |= b.objects;
        });
        CHECK(unrecorded == (records ? 0 : 1));
        CHECK(objects == (records ? raycache::object_bits(3) : 0u));
    }
}

TEST_CASE("every truncation of a small cache file is refused") {
    const std::vector<std::uint8_t> bytes = small_file();
    REQUIRE(decode<CdctTexel>(bytes).size() == 1u);
    for (std::size_t length = 0; length < bytes.size(); ++length) {
        CAPTURE(length);
        const std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(length));
        CHECK(!cache_file_error([&] { decode<CdctTexel>(cut); }).empty());
    }
    std::vector<std::uint8_t> longer = bytes;
    longer.push_back(0);
    CHECK(contains(cache_file_error([&] { decode<CdctTexel>(longer); }), "1 bytes follow the END chunk"));
}

TEST_CASE("random byte flips in a cache file are refused by its checksums, never loaded") {
    const std::vector<std::uint8_t> bytes = small_file();
    Lcg rng{2024};
    int refused = 0, checksum_messages = 0;
    const int trials = 3000;
    for (int trial = 0; trial < trials; ++trial) {
        std::vector<std::uint8_t> flipped = bytes;
        const int flips = 1 + static_cast<int>(rng.next() % 4);
        for (int k = 0; k < flips; ++k) flipped[rng.next() % flipped.size()] ^= static_cast<std::uint8_t>(1 + rng.next() % 255);
        if (flipped == bytes) continue; // two flips of one byte cancelled out
        const std::string message = cache_file_error([&] { decode<CdctTexel>(flipped); });
        refused += !message.empty();
        checksum_messages += contains(message, "checksum");
    }
    CHECK(refused >= trials - 10); // the few unchanged files skipped above
    CHECK(checksum_messages > trials / 2);
}

TEST_CASE("a load that the memory budget cannot hold is refused and leaves the cube as it was") {
    CctCube saved(64);
    Lcg rng{8};
    fill_randomly(saved, rng, 200); // every one of its 96 tiles
    ScratchFolder folder("budget");
    raycache::save_cube(folder.file("cube.rcc"), saved, bounds, scene);
    // Room for the target's and the loaded cube's fixed parts, and 10 tiles: not the file's 96.
    auto budget = std::make_shared<raycache::MemoryBudget>(CctCube::tile_bytes() * 10 + CctCube::fixed_bytes(64) * 2);
    CctCube target(64, budget);
    CHECK(target.store(glm::vec3(1, 0, 0), glm::vec3(0.25f)));
    target.begin_frame();
    const std::size_t used = budget->used();
    CHECK(contains(cache_file_error([&] { raycache::load_cube(folder.file("cube.rcc"), target, bounds, scene); }), "memory budget"));
    CHECK(target.valid_texels() == 1u);
    CHECK(target.lookup(glm::vec3(1, 0, 0)).has_value());
    CHECK(budget->used() == used); // the refused load gave every tile back

    // A budget with no room for the loaded cube's fixed part refuses before it makes the cube.
    auto full = std::make_shared<raycache::MemoryBudget>(CctCube::fixed_bytes(64) + CctCube::tile_bytes());
    CctCube held(64, full);
    CHECK(held.store(glm::vec3(1, 0, 0), glm::vec3(0.25f)));
    held.begin_frame();
    CHECK(full->used() == full->limit());
    CHECK(contains(cache_file_error([&] { raycache::load_cube(folder.file("cube.rcc"), held, bounds, scene); }), "memory budget"));
    CHECK(held.lookup(glm::vec3(1, 0, 0)).has_value());
    CHECK(full->used() == full->limit());
}

TEST_CASE("saving into a folder that does not exist, or loading a file that is missing or a folder, throws naming the file") {
    CctCube cube(4);
    ScratchFolder folder("missing");
    const std::string path = folder.file("no/such/folder/cube.rcc");
    CHECK(contains(cache_file_error([&] { raycache::save_cube(path, cube, bounds, scene); }), "cannot save cache file '" + path));
    CHECK(contains(cache_file_error([&] {
                       CctCube target(4);
                       raycache::load_cube(folder.file("absent.rcc"), target, bounds, scene);
                   }),
                   "cannot open cache file"));
    CHECK(contains(cache_file_error([&] {
                       CctCube target(4);
                       raycache::load_cube(folder.path.string(), target, bounds, scene);
                   }),
                   "is a folder"));
}

TEST_CASE("a save killed at random moments leaves the old file or the new one, never one that loads partly") {
    ScratchFolder folder("killed");
    const std::string path = folder.file("cube.rcc");
    // Two cubes big enough that a save takes a while (about 390 KiB each), differing in every texel.
    CdctCube old_cube(64), new_cube(64);
    Lcg rng{99};
    fill_randomly(old_cube, rng, 1000);
    fill_randomly(new_cube, rng, 1000);
    raycache::save_cube(path, old_cube, bounds, scene);
    // The child writes the files save_cube writes, encoded once beforehand, so that its time goes to the
    // writing that must be atomic (encoding alone takes longer than the delays below in a Debug+ASan build).
    const std::vector<std::uint8_t> files[2] = {raycache::encode_cache<CdctTexel>(scene, {CubeToSave<CdctTexel>{0, bounds, &new_cube}}),
                                                raycache::encode_cache<CdctTexel>(scene, {CubeToSave<CdctTexel>{0, bounds, &old_cube}})};

    int old_seen = 0, new_seen = 0, mid_save = 0;
    const int kills = 40;
    for (int k = 0; k < kills; ++k) {
        const pid_t child = ::fork();
        REQUIRE(child >= 0);
        if (child == 0) { // saves new, old, new, ... until killed
            try {
                for (int i = 0;; ++i) raycache::write_file_atomically(path, files[i % 2]);
            } catch (...) {
                ::_exit(3);
            }
        }
        std::this_thread::sleep_for(std::chrono::microseconds(rng.next() % 20000));
        REQUIRE(::kill(child, SIGKILL) == 0);
        int status = 0;
        REQUIRE(::waitpid(child, &status, 0) == child);
        CHECK(WIFSIGNALED(status));

        // A kill between creating the temporary file and renaming it leaves the temporary file behind.
        for (const auto& entry : std::filesystem::directory_iterator(folder.path))
            if (entry.path().filename() != "cube.rcc") {
                ++mid_save;
                std::filesystem::remove(entry.path());
            }
        CdctCube loaded(1);
        const std::string error = cache_file_error([&] { raycache::load_cube(path, loaded, bounds, scene); });
        CHECK(error == "");
        const bool is_old = same_texels(old_cube, loaded), is_new = same_texels(new_cube, loaded);
        CHECK((is_old || is_new));
        old_seen += is_old;
        new_seen += is_new;
    }
    MESSAGE(kills << " kills: " << mid_save << " during a save, then the old file " << old_seen << " times, the new " << new_seen);
    CHECK(mid_save > 0); // the kills did land inside saves
}
