// raycache/cache_file.hpp: saving warm caching cubes to a file and loading them back, so that a walkthrough
// starts warm (as engines bake their light probes) instead of losing its caches at exit.
//
// The file, format version 5 (versions 1 to 4 are read too). Little-endian throughout; every part carries an FNV-1a 64 checksum (fnv1a64
// below, no library needed), so a truncated or corrupted file is refused, never half loaded.
//
//   prelude  "RAYCACHE" (8 bytes), u32 format version, u32 low half of fnv1a64 of those 12 bytes
//   chunk    u32 tag, u64 payload bytes, payload, u64 fnv1a64 of tag + size + payload
//   "HEAD"   u32 technique (1 CCT, 2 CDCT), u32 texel encoding (1: RGB9E5 in a u32; 2: RGB9E5 in the low u32
//            and the float32 distance in the high u32 of a u64), u32 word bytes (4 or 8), u32 tile edge (16),
//            u64 scene hash, u32 name bytes (at most 4096) and the name, u32 cube count (at most 65536)
//   "CUBE"   one per cube: u64 object id and u64 part (the caller's key of what the cube caches, unique in
//            the file), u32 face size N (1..4096), f32 x 3 centre, f32 half-size,
//            f32 how far from the centre the cube's rays were stored from or answered for (>= 0; infinity:
//            not known) and f32 how far out the cube answers rays (> 0; infinity: from anywhere in its box;
//            see CubeToSave; not in formats 1 and 2, whose cubes load with both infinite), u32 tile count, then per tile a u32 tile index, (face * T + tile row) * T + tile column with
//            T = ceil(N / 16), strictly increasing; u32 1 and f32 x 6 (low and high corner) for the box of
//            the origins its texels were stored from (CacheCube::origin_box), or u32 0 and six zeros;
//            f32 the nearest hit distance of its stores (CacheCube::nearest_hit; infinity: none; not in
//            format 1, whose tiles load without one and answer within the drift alone of an
//            OriginTolerance until a store gives them a distance); u64 x 4, one bit a texel (slot = row * 16 + column, bit slot % 64 of word slot / 64): marked
//            doubtful (CacheCube::is_doubtful; only texels holding a value); in formats 4 and 5, u32 0 (no path
//            record: every texel counts as stored without one) or 64, and then the path records of its
//            sixty-four 2 x 2 record blocks (block = (row / 2) * 8 + column / 2); in format 3, always the
//            records of sixteen 4 x 4 blocks (block = (row / 4) * 4 + column / 4), which a loaded cube's
//            2 x 2 blocks take as theirs; a record is 64 bytes: u32 1
//            when every texel of the block holding a value was stored with the record (else 0, and the
//            rest zero: such texels count as having seen everything), u32 flags (1 lit, 2 chained, 4
//            unbounded), u64 the objects' Bloom mask, f32 x 6 the box of the paths' hit points and f32 x 6
//            the box of their escaped directions (low and high corners; empty: +infinity x 3 then
//            -infinity x 3; else finite, low <= high), and in format 5 (a record of 72 bytes) u64 the
//            direction cells their nested cached answers read (PathRecord::cached_reads: bits 0 to 53;
//            records of formats 3 and 4 load with all 54, as having read everywhere); and its 16 x 16 words row by
//            row (texels past the face's edge, and empty texels, hold the technique's empty word; any other
//            word must be valid)
//   "END "   u32 cube count; nothing may follow
//
// Only tiles holding a value are written (sparse, as cubes allocate them). The scene identity is the
// caller's: a 64-bit hash of whatever makes the cached colours right (geometry, materials, lights) and a
// name for messages; a file saved for another scene is refused.
//
// Saving writes a temporary file in the target's folder, fsyncs it, rename()s it over the target and fsyncs
// the folder: a process killed during a save leaves the old file or the new one, and at worst a stray
// ".NAME.tmp-..." file beside them (POSIX only). Loading reads the whole file, checks every size against
// the bytes that remain before reading, every checksum, the scene, the technique and the version, then
// fills fresh cubes; a CacheFileError names the file and what is wrong, and the caller's cubes are left as
// they were. Loaded texels are visible at once, as a frame's stores are after begin_frame(): the next frame
// rendered sees them. Each tile's origin box and doubtful marks travel with it; a CDCT cube's DepthPyramid,
// derived from the texels alone, is not saved and must be rebuilt (SceneCache::load does it).
//
// Threads: saving reads cubes, loading replaces them: both between frames.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"
#include "raycache/cdct.hpp"

namespace raycache {

// A cache file that cannot be written, read, or used for the cache at hand; what() names the file and why.
class CacheFileError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// What the caller says the cached scene is: a hash of what the cached colours depend on, and a name.
struct SceneIdentity {
    std::uint64_t hash = 0;
    std::string name;
};

inline constexpr std::uint32_t cache_file_version = 5;

inline constexpr std::uint64_t fnv1a64_basis = 14695981039346656037ull;

// FNV-1a, 64 bits, of `size` bytes, continuing from `hash`. Any one changed byte changes it.
inline std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t hash = fnv1a64_basis) noexcept {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
    return hash;
}

// How a texel type is written: its technique and encoding numbers and names (CCT and CDCT only).
template <class Texel>
struct CacheFileTexel;
template <>
struct CacheFileTexel<CctTexel> {
    static constexpr std::uint32_t technique = 1, encoding = 1;
    static constexpr const char* name = "CCT";
};
template <>
struct CacheFileTexel<CdctTexel> {
    static constexpr std::uint32_t technique = 2, encoding = 2;
    static constexpr const char* name = "CDCT";
};

// One cube to save: the caller's key of what it caches, (object, part), unique in the file (part: for callers
// whose objects have parts, e.g. primitive ranges of one geometry; 0 otherwise), where it sits, the cube,
// and where its rays leave from: the furthest from the centre any ray was stored from or answered for
// (origins_seen; infinity: not known) and how far out the cube answers rays (origins_limit; infinity:
// from anywhere in its box). A cube whose texels exact invalidation checked for rays from within a
// distance only must keep that limit, or a load would let them answer rays they were never checked for.
template <class Texel>
struct CubeToSave {
    std::uint64_t object = 0;
    CubeBounds bounds;
    const CacheCube<Texel>* cube = nullptr;
    std::uint64_t part = 0;
    float origins_seen = std::numeric_limits<float>::infinity();
    float origins_limit = std::numeric_limits<float>::infinity();
};

// One cube read back, with its tiles' origin boxes and doubtful marks. Its texels are held as the current
// frame's stores: begin_frame() makes them visible.
template <class Texel>
struct LoadedCube {
    std::uint64_t object = 0;
    CubeBounds bounds;
    std::unique_ptr<CacheCube<Texel>> cube;
    std::uint64_t part = 0;
    float origins_seen = std::numeric_limits<float>::infinity();  // as CubeToSave (formats 1, 2: infinity)
    float origins_limit = std::numeric_limits<float>::infinity();
};

// True when two placements are the same, float for float.
inline bool same_placement(const CubeBounds& a, const CubeBounds& b) noexcept {
    return a.centre == b.centre && a.half_size == b.half_size;
}

// "centre (x, y, z), half-size h", every float to the last bit.
inline std::string describe(const CubeBounds& b) {
    char text[160];
    std::snprintf(text, sizeof text, "centre (%.9g, %.9g, %.9g), half-size %.9g", static_cast<double>(b.centre.x),
                  static_cast<double>(b.centre.y), static_cast<double>(b.centre.z), static_cast<double>(b.half_size));
    return text;
}

namespace detail {

inline constexpr char cache_file_magic[8] = {'R', 'A', 'Y', 'C', 'A', 'C', 'H', 'E'};
inline constexpr std::size_t cache_file_prelude_bytes = 16;
inline constexpr std::size_t chunk_frame_bytes = 4 + 8 + 8; // tag, size, checksum
inline constexpr std::uint32_t max_scene_name_bytes = 4096;
inline constexpr std::uint32_t max_cubes_in_file = 65536;
inline constexpr int file_tile_edge = 16;
inline constexpr std::size_t file_tile_texels = file_tile_edge * file_tile_edge;
// Smallest CUBE chunk: frame, object and part, face size, bounds, tile count.
inline constexpr std::size_t min_cube_chunk_bytes = chunk_frame_bytes + 16 + 4 + 16 + 4;

inline constexpr std::uint32_t tag(const char (&t)[5]) noexcept {
    return static_cast<std::uint32_t>(static_cast<unsigned char>(t[0])) |
           static_cast<std::uint32_t>(static_cast<unsigned char>(t[1])) << 8 |
           static_cast<std::uint32_t>(static_cast<unsigned char>(t[2])) << 16 |
           static_cast<std::uint32_t>(static_cast<unsigned char>(t[3])) << 24;
}
inline constexpr std::uint32_t head_tag = tag("HEAD"), cube_tag = tag("CUBE"), end_tag = tag("END ");

inline std::string tag_text(std::uint32_t t) {
    std::string s;
    for (int i = 0; i < 4; ++i) {
        const char c = static_cast<char>(t >> (8 * i) & 0xFFu);
        s += c >= 32 && c < 127 ? std::string(1, c) : "\\x" + std::to_string(static_cast<unsigned char>(c));
    }
    return s;
}

// "object 7", "object 7 part 9".
inline std::string key_text(std::uint64_t object, std::uint64_t part) {
    return "object " + std::to_string(object) + (part ? " part " + std::to_string(part) : std::string());
}

inline std::string hex(std::uint64_t v) {
    char text[24];
    std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(v));
    return text;
}

inline std::string technique_name(std::uint32_t technique) {
    if (technique == CacheFileTexel<CctTexel>::technique) return CacheFileTexel<CctTexel>::name;
    if (technique == CacheFileTexel<CdctTexel>::technique) return CacheFileTexel<CdctTexel>::name;
    return "unknown technique " + std::to_string(technique);
}

// Tiles along a face's edge in the file (and in CacheCube).
inline std::uint32_t file_tiles_per_edge(int face_size) noexcept {
    return static_cast<std::uint32_t>((face_size + file_tile_edge - 1) / file_tile_edge);
}

// The little-endian unsigned integer (a texel word, a size) at p.
template <class Word>
Word read_word(const std::uint8_t* p) noexcept {
    Word v = 0;
    for (std::size_t i = 0; i < sizeof(Word); ++i) v |= static_cast<Word>(p[i]) << (8 * i);
    return v;
}

// Little-endian output.
class ByteWriter {
public:
    std::vector<std::uint8_t> bytes;

    void u32(std::uint32_t v) {
        for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
    void u64(std::uint64_t v) {
        for (int i = 0; i < 8; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
    void f32(float v) { u32(glm::floatBitsToUint(v)); }
    void word(std::uint32_t v) { u32(v); }
    void word(std::uint64_t v) { u64(v); }
    void text(const std::string& s) { bytes.insert(bytes.end(), s.begin(), s.end()); }

    // Starts a chunk; returns where it starts, for end_chunk.
    std::size_t begin_chunk(std::uint32_t chunk_tag) {
        const std::size_t start = bytes.size();
        u32(chunk_tag);
        u64(0); // the payload size, patched by end_chunk
        return start;
    }
    void end_chunk(std::size_t start) {
        const std::uint64_t payload = bytes.size() - start - 12;
        for (int i = 0; i < 8; ++i) bytes[start + 4 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(payload >> (8 * i));
        u64(fnv1a64(bytes.data() + start, bytes.size() - start));
    }
};

// Little-endian input over [data, data + size) that checks every read against what remains; a read past
// the end throws CacheFileError naming `what` (the part being read) as truncated.
class ByteReader {
public:
    ByteReader(const std::uint8_t* data, std::size_t size, std::string source)
        : data_(data), size_(size), source_(std::move(source)) {}

    std::size_t position() const noexcept { return position_; }
    std::size_t remaining() const noexcept { return size_ - position_; }
    const std::uint8_t* here() const noexcept { return data_ + position_; }

    [[noreturn]] void fail(const std::string& what) const {
        throw CacheFileError("RayCache: " + source_ + ": " + what + "; nothing was loaded");
    }
    void need(std::size_t bytes, const std::string& what) const {
        if (bytes > remaining())
            fail("truncated: " + what + " needs " + std::to_string(bytes) + " bytes at byte " + std::to_string(position_) +
                 ", only " + std::to_string(remaining()) + " remain");
    }
    template <class Unsigned>
    Unsigned little_endian(const std::string& what) {
        need(sizeof(Unsigned), what);
        const Unsigned v = read_word<Unsigned>(here());
        position_ += sizeof(Unsigned);
        return v;
    }
    std::uint32_t u32(const std::string& what) { return little_endian<std::uint32_t>(what); }
    std::uint64_t u64(const std::string& what) { return little_endian<std::uint64_t>(what); }
    float f32(const std::string& what) { return glm::uintBitsToFloat(u32(what)); }
    std::string text(std::size_t bytes, const std::string& what) {
        need(bytes, what);
        std::string s(reinterpret_cast<const char*>(here()), bytes);
        position_ += bytes;
        return s;
    }
    void skip(std::size_t bytes, const std::string& what) {
        need(bytes, what);
        position_ += bytes;
    }

    // Reads a chunk's frame and checks its tag and checksum; returns a reader over its payload (which names
    // `what` in its messages) and moves past the chunk.
    ByteReader chunk(std::uint32_t expected_tag, const std::string& what) {
        const std::size_t start = position_;
        const std::uint32_t found = u32(what + " (its tag)");
        if (found != expected_tag)
            fail("expected " + what + " at byte " + std::to_string(start) + ", found a chunk tagged '" + tag_text(found) +
                 "' (a truncated, corrupted or reordered file)");
        const std::uint64_t payload = u64(what + " (its size)");
        if (payload > remaining() || remaining() - payload < 8)
            fail("truncated: " + what + " at byte " + std::to_string(start) + " claims " + std::to_string(payload) +
                 " bytes and its checksum, only " + std::to_string(remaining()) + " remain");
        const std::size_t payload_at = position_;
        position_ += static_cast<std::size_t>(payload);
        const std::uint64_t expected = fnv1a64(data_ + start, position_ - start);
        const std::uint64_t stored = u64(what + " (its checksum)");
        if (stored != expected)
            fail("corrupted: the checksum of " + what + " at byte " + std::to_string(start) + " does not match its contents");
        return ByteReader(data_ + payload_at, static_cast<std::size_t>(payload), source_ + ", " + what);
    }

    // Every byte of a chunk's payload must have been read.
    void expect_end(const std::string& what) const {
        if (remaining() != 0) fail(what + " has " + std::to_string(remaining()) + " bytes more than its fields");
    }

private:
    const std::uint8_t* data_;
    std::size_t size_;
    std::size_t position_ = 0;
    std::string source_;
};

// A cube as the file describes it, checked, its tiles not yet copied.
struct CubeRecord {
    std::uint64_t object = 0, part = 0;
    int face_size = 0;
    CubeBounds bounds;
    float origins_seen = std::numeric_limits<float>::infinity(), origins_limit = std::numeric_limits<float>::infinity();
    std::uint32_t tiles = 0;
    const std::uint8_t* tile_data = nullptr; // `tiles` times a header (read_tile_header) and 256 words
    std::size_t tile_bytes = 0;              // the bytes from tile_data holding them
    std::uint32_t version = cache_file_version;
};

inline constexpr int file_record_blocks = 64;       // 8 x 8 blocks of 2 x 2 texels a tile (format 4)
inline constexpr int format3_record_edge = 4;        // format 3: 4 x 4 blocks of 4 x 4 texels
inline constexpr int format3_record_blocks = 16;
inline constexpr std::size_t file_record_bytes = 64; // one block's path record (formats 3 and 4; format 5: 72)
static_assert(CacheCube<CctTexel>::tile_edge == file_tile_edge && CacheCube<CctTexel>::record_blocks == file_record_blocks &&
                  CacheCube<CctTexel>::path_lit == 1u && CacheCube<CctTexel>::path_chained == 2u &&
                  CacheCube<CctTexel>::path_unbounded == 4u,
              "cache files keep tiles, record blocks and path flags as CacheCube does: change the format with them");

// One record block's path record as the file stores it (format 3 on).
struct BlockRecord {
    bool recorded = false; // every texel of the block holding a value carries `record`
    PathRecord record;
};

// A tile's index, origin box, doubtful marks and path records, as the file stores them before its words.
struct TileHeader {
    std::uint32_t index = 0;
    bool has_box = false;
    glm::vec3 lo{0.0f}, hi{0.0f};
    float nearest = std::numeric_limits<float>::infinity(); // format 2 on; format 1 has none
    std::uint64_t doubtful[4] = {0, 0, 0, 0};
    int record_edge = CacheCube<CctTexel>::record_edge;      // texels along a record block's side in the file
    BlockRecord blocks[file_record_blocks];                  // format 3 on; before, none recorded
    bool is_doubtful(int slot) const noexcept { return (doubtful[slot / 64] >> (slot % 64)) & 1u; }
    // The record of the cube's record block whose first texel is (column0, row0) of its face: the file's
    // block holding it (format 3's 4 x 4 blocks each hold four of the cube's).
    const BlockRecord& record_of(int column0, int row0) const noexcept {
        const int edge = static_cast<int>(file_tile_edge), per_side = edge / record_edge;
        return blocks[(row0 % edge / record_edge) * per_side + column0 % edge / record_edge];
    }
};
// A tile's bytes before its words at least (format 1 has no nearest hit distance, 4 bytes, after the box;
// formats 1 and 2 no path records; format 3 always sixteen; format 4 a count, then 0 or 64 of them).
inline std::size_t least_tile_header_bytes(std::uint32_t version) noexcept {
    const std::size_t records = version == 3 ? format3_record_blocks * file_record_bytes : version >= 4 ? 4 : 0;
    return 4 + 4 + 6 * 4 + (version >= 2 ? 4 : 0) + 4 * 8 + records;
}

// Hit points a file's records may hold: within 1e18 of the origin on every axis, so that the distances and
// cones invalidation derives from them stay finite (a box nearer infinity would overflow them).
inline constexpr float max_file_coordinate = 1e18f;

// A box of the file's path records: empty (+infinity x 3, -infinity x 3), or low <= high within
// max_file_coordinate; for escaped directions (`directions`) also within [-1, 1] and reaching the unit
// sphere (the box of unit vectors holds one).
inline bool is_file_box(const glm::vec3& lo, const glm::vec3& hi, bool directions) noexcept {
    const float inf = std::numeric_limits<float>::infinity();
    if (lo == glm::vec3(inf) && hi == glm::vec3(-inf)) return true;
    const float bound = directions ? 1.0f : max_file_coordinate;
    for (int k = 0; k < 3; ++k)
        if (!(lo[k] >= -bound && lo[k] <= hi[k] && hi[k] <= bound)) return false; // NaN fails too
    if (!directions) return true;
    const glm::vec3 farthest = glm::max(glm::abs(lo), glm::abs(hi));
    return glm::dot(farthest, farthest) >= 0.999f;
}
// Whether a record can be written as it is (a record of hit points far out or not finite cannot: its
// block is written as holding none, which is sound, since its texels then count as having seen anything).
inline bool is_file_record(const PathRecord& r) noexcept {
    return is_file_box(r.vertex_lo, r.vertex_hi, false) && is_file_box(r.escape_lo, r.escape_hi, true);
}

// Reads one block's record (format 3 on; cached reads from format 5 on).
inline BlockRecord read_block_record(ByteReader& r, std::uint32_t tile, int block, std::uint32_t version) {
    BlockRecord b;
    const std::uint32_t recorded = r.u32("a block's record flag");
    const std::uint32_t flags = r.u32("a block's path flags");
    const std::uint64_t objects = r.u64("a block's object mask");
    glm::vec3 box[4] = {glm::vec3(0.0f), glm::vec3(0.0f), glm::vec3(0.0f), glm::vec3(0.0f)};
    for (glm::vec3& corner : box)
        for (int k = 0; k < 3; ++k) corner[k] = r.f32("a block's boxes");
    const std::uint64_t reads = version >= 5 ? r.u64("a block's cached reads") : every_direction_cell;
    const std::string where = "block " + std::to_string(block) + " of tile " + std::to_string(tile);
    if (recorded > 1) r.fail(where + " has record flag " + std::to_string(recorded) + " (0 or 1)");
    if (recorded == 0) {
        bool zero = flags == 0 && objects == 0 && (version < 5 || reads == 0);
        for (const glm::vec3& corner : box) zero = zero && glm::floatBitsToUint(corner) == glm::uvec3(0u);
        if (!zero) r.fail(where + " holds no record but is not all zero");
        return b;
    }
    if (flags & ~CacheCube<CctTexel>::all_path_flags)
        r.fail(where + " has path flags " + std::to_string(flags) + " (1 lit, 2 chained, 4 unbounded)");
    if (reads & ~every_direction_cell) r.fail(where + " has cached reads beyond the 54 direction cells");
    if (!is_file_box(box[0], box[1], false) || !is_file_box(box[2], box[3], true))
        r.fail(where + "'s boxes are neither empty (+inf, -inf) nor low <= high within bounds (hit points within 1e18, "
                       "escape directions within [-1, 1] and reaching the unit sphere)");
    b.recorded = true;
    b.record.objects = objects;
    b.record.vertex_lo = box[0], b.record.vertex_hi = box[1];
    b.record.escape_lo = box[2], b.record.escape_hi = box[3];
    b.record.cached_reads = reads;
    CacheCube<CctTexel>::set_path_flags(b.record, flags);
    return b;
}

inline TileHeader read_tile_header(ByteReader& r, std::uint32_t version) {
    TileHeader h;
    h.index = r.u32("a tile index");
    const std::uint32_t flag = r.u32("a tile's origin flag");
    for (int k = 0; k < 3; ++k) h.lo[k] = r.f32("a tile's origin box");
    for (int k = 0; k < 3; ++k) h.hi[k] = r.f32("a tile's origin box");
    if (flag > 1) r.fail("tile " + std::to_string(h.index) + " has origin flag " + std::to_string(flag) + " (0 or 1)");
    h.has_box = flag == 1;
    const bool zero = glm::floatBitsToUint(h.lo) == glm::uvec3(0u) && glm::floatBitsToUint(h.hi) == glm::uvec3(0u);
    const bool box = glm::all(glm::lessThanEqual(h.lo, h.hi)) && shared::raycache_is_finite3(h.lo) && shared::raycache_is_finite3(h.hi);
    if (h.has_box ? !box : !zero)
        r.fail("tile " + std::to_string(h.index) + "'s origin box is not " + (h.has_box ? "finite, low <= high" : "zero"));
    if (version >= 2) {
        h.nearest = r.f32("a tile's nearest hit distance");
        if (!(h.nearest >= 0.0f))
            r.fail("tile " + std::to_string(h.index) + "'s nearest hit distance is not >= 0 (infinity: none)");
    }
    for (std::uint64_t& bits : h.doubtful) bits = r.u64("a tile's doubtful marks");
    if (version == 3) {
        h.record_edge = format3_record_edge;
        for (int b = 0; b < format3_record_blocks; ++b) h.blocks[b] = read_block_record(r, h.index, b, version);
    } else if (version >= 4) {
        const std::uint32_t count = r.u32("a tile's count of record blocks");
        if (count != 0 && count != file_record_blocks)
            r.fail("tile " + std::to_string(h.index) + " has " + std::to_string(count) + " record blocks (0 or " +
                   std::to_string(file_record_blocks) + ")");
        for (std::uint32_t b = 0; b < count; ++b) h.blocks[b] = read_block_record(r, h.index, static_cast<int>(b), version);
    }
    return h;
}

// The tiles of `cube` holding a value, as file tile indices, increasing.
template <class Texel>
std::vector<std::uint32_t> tiles_holding_values(const CacheCube<Texel>& cube) {
    const std::uint32_t per_edge = file_tiles_per_edge(cube.face_size());
    std::vector<bool> used(std::size_t{RAYCACHE_FACE_COUNT} * per_edge * per_edge, false);
    cube.for_each_valid_texel([&](const TexelAddress& t) {
        used[(static_cast<std::size_t>(t.face) * per_edge + static_cast<std::uint32_t>(t.row / file_tile_edge)) * per_edge +
             static_cast<std::uint32_t>(t.column / file_tile_edge)] = true;
    });
    std::vector<std::uint32_t> tiles;
    for (std::size_t i = 0; i < used.size(); ++i)
        if (used[i]) tiles.push_back(static_cast<std::uint32_t>(i));
    return tiles;
}

// The texel of slot (row, column) of file tile `index` on a face of `face_size`; off the face when the tile
// sticks out past the face's edge.
inline TexelAddress tile_texel(std::uint32_t index, int slot, int face_size) noexcept {
    const std::uint32_t per_edge = file_tiles_per_edge(face_size);
    const int face = static_cast<int>(index / (per_edge * per_edge));
    const int tile_row = static_cast<int>(index / per_edge % per_edge), tile_column = static_cast<int>(index % per_edge);
    return TexelAddress{face, tile_column * file_tile_edge + slot % file_tile_edge, tile_row * file_tile_edge + slot / file_tile_edge};
}

// Reads and checks one CUBE chunk's payload (every word valid or empty, empty past the face's edge).
template <class Texel>
CubeRecord read_cube_record(ByteReader& r, std::uint32_t version) {
    using Word = typename Texel::Word;
    CubeRecord c;
    c.version = version;
    c.object = r.u64("the object id");
    c.part = r.u64("the object part");
    const std::uint32_t face_size = r.u32("the face size");
    if (face_size < std::uint32_t{RAYCACHE_MIN_FACE_SIZE} || face_size > std::uint32_t{RAYCACHE_MAX_FACE_SIZE})
        r.fail("face size " + std::to_string(face_size) + " is outside 1..4096");
    c.face_size = static_cast<int>(face_size);
    c.bounds.centre.x = r.f32("the centre");
    c.bounds.centre.y = r.f32("the centre");
    c.bounds.centre.z = r.f32("the centre");
    c.bounds.half_size = r.f32("the half-size");
    if (!is_usable(c.bounds)) r.fail("the placement (" + describe(c.bounds) + ") is not a finite centre with a half-size > 0");
    if (version >= 3) {
        c.origins_seen = r.f32("how far out the cube's rays left");
        c.origins_limit = r.f32("how far out the cube answers rays");
        if (!(c.origins_seen >= 0.0f)) r.fail("how far out the cube's rays left is not >= 0 (infinity: not known)");
        if (!(c.origins_limit > 0.0f)) r.fail("how far out the cube answers rays is not > 0 (infinity: anywhere in its box)");
    }
    c.tiles = r.u32("the tile count");
    const std::uint32_t per_edge = file_tiles_per_edge(c.face_size);
    const std::uint64_t tile_count = std::uint64_t{RAYCACHE_FACE_COUNT} * per_edge * per_edge;
    if (c.tiles > tile_count)
        r.fail(std::to_string(c.tiles) + " tiles, more than the " + std::to_string(tile_count) + " of a cube of face size " +
               std::to_string(face_size));
    const std::size_t least_tile_bytes = least_tile_header_bytes(c.version) + file_tile_texels * sizeof(Word);
    if (r.remaining() / least_tile_bytes < c.tiles)
        r.fail(std::to_string(c.tiles) + " tiles need at least " + std::to_string(std::uint64_t{c.tiles} * least_tile_bytes) +
               " bytes, the chunk holds " + std::to_string(r.remaining()));
    c.tile_data = r.here();
    c.tile_bytes = r.remaining(); // the tiles must end the chunk (checked below)
    std::int64_t previous = -1;
    for (std::uint32_t i = 0; i < c.tiles; ++i) {
        const TileHeader header = read_tile_header(r, c.version);
        const std::uint32_t index = header.index;
        if (index >= tile_count)
            r.fail("tile index " + std::to_string(index) + " is outside the cube's " + std::to_string(tile_count) + " tiles");
        if (static_cast<std::int64_t>(index) <= previous)
            r.fail("tile index " + std::to_string(index) + " follows " + std::to_string(previous) + " (tiles must be in increasing order, each once)");
        previous = index;
        r.need(file_tile_texels * sizeof(Word), "a tile's texels");
        const std::uint8_t* words = r.here();
        for (int slot = 0; slot < static_cast<int>(file_tile_texels); ++slot) {
            const Word w = read_word<Word>(words + static_cast<std::size_t>(slot) * sizeof(Word));
            if (w == Texel::invalid && header.is_doubtful(slot))
                r.fail("texel " + std::to_string(slot) + " of tile " + std::to_string(index) + " is marked doubtful but holds no value");
            if (w == Texel::invalid) continue;
            if (!Texel::is_valid(w))
                r.fail("texel " + std::to_string(slot) + " of tile " + std::to_string(index) + " is neither a valid " +
                       CacheFileTexel<Texel>::name + " texel nor the empty word");
            if (!is_on_cube(tile_texel(index, slot, c.face_size), c.face_size))
                r.fail("texel " + std::to_string(slot) + " of tile " + std::to_string(index) + " lies past the face's edge but holds a value");
        }
        r.skip(file_tile_texels * sizeof(Word), "a tile's texels");
    }
    r.expect_end("the CUBE chunk");
    return c;
}

// A reader over the record's tiles, each a header and 256 words (checked: read_cube_record() sized them).
template <class Texel>
ByteReader tiles_of(const CubeRecord& c) {
    return ByteReader(c.tile_data, c.tile_bytes, "tiles");
}

// Whether any block of the record's tiles holds a path record.
template <class Texel>
bool holds_path_records(const CubeRecord& c) {
    using Word = typename Texel::Word;
    if (c.version < 3) return false; // formats 1 and 2 keep none
    ByteReader tiles = tiles_of<Texel>(c);
    for (std::uint32_t i = 0; i < c.tiles; ++i) {
        const TileHeader h = read_tile_header(tiles, c.version);
        for (const BlockRecord& b : h.blocks)
            if (b.recorded) return true;
        tiles.skip(file_tile_texels * sizeof(Word), "a tile's texels");
    }
    return false;
}

// A fresh cube holding the record's texels as this frame's stores (with path records or without: CacheCube's
// path_records). Throws CacheFileError when the budget has no room for the cube's fixed part or refuses a tile.
template <class Texel>
std::unique_ptr<CacheCube<Texel>> build_cube(const CubeRecord& c, const std::shared_ptr<MemoryBudget>& budget,
                                             const ByteReader& messages, bool path_records) {
    using Word = typename Texel::Word;
    const auto no_room = [&] {
        messages.fail("the memory budget (" + std::to_string(budget ? budget->limit() : 0) + " bytes, " +
                      std::to_string(budget ? budget->used() : 0) +
                      " in use) cannot hold the file's cubes as well as the cubes they replace");
    };
    const std::size_t fixed = CacheCube<Texel>::fixed_bytes(c.face_size);
    if (budget && fixed > budget->room()) no_room();
    auto cube = std::make_unique<CacheCube<Texel>>(c.face_size, budget, path_records);
    ByteReader tiles = tiles_of<Texel>(c);
    for (std::uint32_t i = 0; i < c.tiles; ++i) {
        const TileHeader h = read_tile_header(tiles, c.version);
        for (int slot = 0; slot < static_cast<int>(file_tile_texels); ++slot) {
            const Word w = read_word<Word>(tiles.here());
            tiles.skip(sizeof(Word), "a texel");
            if (w == Texel::invalid) continue;
            const TexelAddress t = tile_texel(h.index, slot, c.face_size);
            if (!cube->store_word_at(t, w)) no_room();
            if (h.is_doubtful(slot)) cube->set_doubtful(t);
        }
        if (h.has_box) cube->set_origin_box(tile_texel(h.index, 0, c.face_size), h.lo, h.hi, h.nearest); // slot 0 is on the face
        // The paths its blocks' texels saw, so exact invalidation can keep them (the tile index is the cube's).
        cube->for_each_block_state_of_tile(h.index, [&](const typename CacheCube<Texel>::BlockState& b) {
            const BlockRecord& f = h.record_of(b.column0, b.row0);
            if (f.recorded) cube->record_texels_of_block(b, f.record);
        });
    }
    return cube;
}

} // namespace detail

// The bytes of a cache file holding `cubes` (CCT or CDCT) for `scene`: every tile of each cube that holds
// a value (visible or written this frame). Object ids must be unique; every cube non-null.
// Throws std::invalid_argument otherwise, or for a scene name longer than 4096 bytes, more than 65536 cubes, or
// an origins_limit not > 0.
template <class Texel>
std::vector<std::uint8_t> encode_cache(const SceneIdentity& scene, const std::vector<CubeToSave<Texel>>& cubes) {
    using Word = typename Texel::Word;
    using File = CacheFileTexel<Texel>;
    if (scene.name.size() > detail::max_scene_name_bytes)
        throw std::invalid_argument("RayCache: a cache file's scene name must be at most 4096 bytes");
    if (cubes.size() > detail::max_cubes_in_file)
        throw std::invalid_argument("RayCache: a cache file holds at most 65536 cubes, got " + std::to_string(cubes.size()));
    std::set<std::pair<std::uint64_t, std::uint64_t>> keys;
    for (const CubeToSave<Texel>& c : cubes) {
        if (!c.cube) throw std::invalid_argument("RayCache: encode_cache: a null cube");
        if (!keys.insert({c.object, c.part}).second)
            throw std::invalid_argument("RayCache: encode_cache: " + detail::key_text(c.object, c.part) + " appears twice");
        if (!(c.origins_limit > 0.0f)) // lifting a limit would be unsafe, so a bad one is not written as none
            throw std::invalid_argument("RayCache: encode_cache: " + detail::key_text(c.object, c.part) +
                                        "'s origins_limit must be > 0 (infinity: none)");
    }
    detail::ByteWriter w;
    w.text(std::string(detail::cache_file_magic, 8));
    w.u32(cache_file_version);
    w.u32(static_cast<std::uint32_t>(fnv1a64(w.bytes.data(), 12)));

    std::size_t start = w.begin_chunk(detail::head_tag);
    w.u32(File::technique);
    w.u32(File::encoding);
    w.u32(sizeof(Word));
    w.u32(detail::file_tile_edge);
    w.u64(scene.hash);
    w.u32(static_cast<std::uint32_t>(scene.name.size()));
    w.text(scene.name);
    w.u32(static_cast<std::uint32_t>(cubes.size()));
    w.end_chunk(start);

    for (const CubeToSave<Texel>& c : cubes) {
        const int n = c.cube->face_size();
        const std::vector<std::uint32_t> tiles = detail::tiles_holding_values(*c.cube);
        start = w.begin_chunk(detail::cube_tag);
        w.u64(c.object);
        w.u64(c.part);
        w.u32(static_cast<std::uint32_t>(n));
        w.f32(c.bounds.centre.x);
        w.f32(c.bounds.centre.y);
        w.f32(c.bounds.centre.z);
        w.f32(c.bounds.half_size);
        w.f32(c.origins_seen >= 0.0f ? c.origins_seen : std::numeric_limits<float>::infinity()); // NaN, < 0: not known
        w.f32(c.origins_limit);
        w.u32(static_cast<std::uint32_t>(tiles.size()));
        for (std::uint32_t index : tiles) {
            w.u32(index);
            const std::optional<std::pair<glm::vec3, glm::vec3>> box = c.cube->origin_box(detail::tile_texel(index, 0, n));
            w.u32(box ? 1 : 0);
            for (const glm::vec3& corner : {box ? box->first : glm::vec3(0.0f), box ? box->second : glm::vec3(0.0f)})
                for (int k = 0; k < 3; ++k) w.f32(corner[k] + 0.0f);
            w.f32(box ? c.cube->nearest_hit(detail::tile_texel(index, 0, n)) : std::numeric_limits<float>::infinity());
            std::uint64_t doubtful[4] = {0, 0, 0, 0};
            for (int slot = 0; slot < static_cast<int>(detail::file_tile_texels); ++slot) {
                const TexelAddress t = detail::tile_texel(index, slot, n);
                if (c.cube->contains(t) && c.cube->is_doubtful(t)) doubtful[slot / 64] |= std::uint64_t{1} << (slot % 64);
            }
            for (std::uint64_t bits : doubtful) w.u64(bits);
            // Each block's record when every texel of it holding a value carries it (else none: those
            // texels count as having seen everything, as unrecorded texels do); none for a block without
            // values, so a file holds records only where they describe texels (holds_path_records()).
            detail::BlockRecord blocks[detail::file_record_blocks];
            bool any = false;
            c.cube->for_each_block_state_of_tile(index, [&](const typename CacheCube<Texel>::BlockState& b) {
                if (b.unrecorded_texels != 0 || b.valid_texels == 0) return;
                const PathRecord record = b.record();
                if (detail::is_file_record(record)) blocks[b.block] = detail::BlockRecord{true, record}, any = true;
            });
            // A tile with no record (a static scene's) writes none: its texels are unrecorded either way.
            w.u32(any ? static_cast<std::uint32_t>(detail::file_record_blocks) : 0u);
            for (int i = 0; i < (any ? detail::file_record_blocks : 0); ++i) {
                const detail::BlockRecord& b = blocks[i];
                w.u32(b.recorded ? 1 : 0);
                w.u32(b.recorded ? CacheCube<Texel>::path_flags_of(b.record) : 0u);
                w.u64(b.recorded ? b.record.objects : 0);
                for (const glm::vec3& corner : {b.record.vertex_lo, b.record.vertex_hi, b.record.escape_lo, b.record.escape_hi})
                    for (int k = 0; k < 3; ++k) w.f32(b.recorded ? corner[k] + 0.0f : 0.0f);
                w.u64(b.recorded ? b.record.cached_reads : 0);
            }
            for (int slot = 0; slot < static_cast<int>(detail::file_tile_texels); ++slot) {
                const TexelAddress t = detail::tile_texel(index, slot, n);
                w.word(c.cube->contains(t) ? c.cube->load_word(t) : Texel::invalid);
            }
        }
        w.end_chunk(start);
    }

    start = w.begin_chunk(detail::end_tag);
    w.u32(static_cast<std::uint32_t>(cubes.size()));
    w.end_chunk(start);
    return std::move(w.bytes);
}

// The cubes of a cache file's bytes (see LoadedCube), checked whole before any cube is made: the prelude, every chunk's
// size and checksum, the format version (newer: refused), the technique (Texel's), the scene (`expected`,
// hash and name), every face size, placement, tile index and texel word. `source` names the bytes in
// messages (a file name). The cubes draw their tiles from `budget` (may be null); path_records as
// CacheCube's (false: the file's path records are not kept, and its texels count as stored without one;
// std::nullopt: every cube keeps them when any block of the file holds one, none does otherwise).
// Throws CacheFileError saying what is wrong; then nothing was made.
template <class Texel>
std::vector<LoadedCube<Texel>> decode_cache(const std::uint8_t* data, std::size_t size, const SceneIdentity& expected,
                                            const std::shared_ptr<MemoryBudget>& budget = nullptr,
                                            const std::string& source = "cache data", std::optional<bool> path_records = true) {
    using Word = typename Texel::Word;
    using File = CacheFileTexel<Texel>;
    detail::ByteReader r(data, size, source);
    if (size == 0) r.fail("the file is empty");
    r.need(detail::cache_file_prelude_bytes, "the 16-byte prelude");
    if (std::memcmp(data, detail::cache_file_magic, 8) != 0) r.fail("not a RayCache cache file (it does not start with 'RAYCACHE')");
    r.skip(8, "the magic");
    const std::uint32_t version = r.u32("the format version");
    const std::uint32_t check = r.u32("the prelude's checksum");
    if (check != static_cast<std::uint32_t>(fnv1a64(data, 12))) r.fail("corrupted: the prelude's checksum does not match");
    if (version > cache_file_version)
        r.fail("format version " + std::to_string(version) + " is newer than this RayCache reads (" +
               std::to_string(cache_file_version) + "); load it with a newer RayCache or save the cache again");
    if (version < 1) r.fail("unknown format version " + std::to_string(version));

    detail::ByteReader head = r.chunk(detail::head_tag, "the HEAD chunk");
    const std::uint32_t technique = head.u32("the technique");
    const std::uint32_t encoding = head.u32("the texel encoding");
    const std::uint32_t word_bytes = head.u32("the word size");
    const std::uint32_t tile_edge = head.u32("the tile edge");
    const std::uint64_t hash = head.u64("the scene hash");
    const std::uint32_t name_bytes = head.u32("the scene name's length");
    if (name_bytes > detail::max_scene_name_bytes) head.fail("a scene name of " + std::to_string(name_bytes) + " bytes (at most 4096)");
    const std::string name = head.text(name_bytes, "the scene name");
    const std::uint32_t cube_count = head.u32("the cube count");
    head.expect_end("the HEAD chunk");
    if (technique != File::technique)
        r.fail("it holds " + detail::technique_name(technique) + " cubes, this cache is " + File::name);
    if (encoding != File::encoding || word_bytes != sizeof(Word))
        r.fail("texel encoding " + std::to_string(encoding) + " in " + std::to_string(word_bytes) + "-byte words is not " +
               File::name + "'s (encoding " + std::to_string(File::encoding) + ", " + std::to_string(sizeof(Word)) + " bytes)");
    if (tile_edge != detail::file_tile_edge) r.fail("tiles of " + std::to_string(tile_edge) + " texels a side (formats 1 and 2 have 16)");
    if (hash != expected.hash || name != expected.name)
        r.fail("it was saved for scene '" + name + "' (hash " + detail::hex(hash) + "), this is scene '" + expected.name +
               "' (hash " + detail::hex(expected.hash) + ")");
    if (cube_count > detail::max_cubes_in_file) r.fail(std::to_string(cube_count) + " cubes (at most 65536)");
    if (r.remaining() / detail::min_cube_chunk_bytes < cube_count)
        r.fail("truncated: " + std::to_string(cube_count) + " cubes cannot fit in the " + std::to_string(r.remaining()) +
               " bytes after the HEAD chunk");

    std::vector<detail::CubeRecord> records;
    records.reserve(cube_count);
    std::set<std::pair<std::uint64_t, std::uint64_t>> keys;
    for (std::uint32_t i = 0; i < cube_count; ++i) {
        const std::string what = "CUBE chunk " + std::to_string(i + 1) + " of " + std::to_string(cube_count);
        detail::ByteReader cube = r.chunk(detail::cube_tag, what);
        records.push_back(detail::read_cube_record<Texel>(cube, version));
        if (!keys.insert({records.back().object, records.back().part}).second)
            r.fail(detail::key_text(records.back().object, records.back().part) + " has two cubes");
    }
    detail::ByteReader end = r.chunk(detail::end_tag, "the END chunk");
    if (end.u32("the END chunk's cube count") != cube_count) r.fail("the END chunk's cube count is not the HEAD chunk's");
    end.expect_end("the END chunk");
    if (r.remaining() != 0) r.fail(std::to_string(r.remaining()) + " bytes follow the END chunk");

    if (!path_records)
        path_records = std::any_of(records.begin(), records.end(), [](const detail::CubeRecord& c) { return detail::holds_path_records<Texel>(c); });
    std::vector<LoadedCube<Texel>> cubes;
    cubes.reserve(records.size());
    for (const detail::CubeRecord& c : records)
        cubes.push_back(LoadedCube<Texel>{c.object, c.bounds, detail::build_cube<Texel>(c, budget, r, *path_records), c.part, c.origins_seen,
                                          c.origins_limit});
    return cubes;
}

// Writes `bytes` to `path` so that `path` holds either its old contents or all of `bytes`, whenever the
// process dies: a new file beside it (same folder), written, fsync'd, rename()d over `path`, and the
// folder fsync'd. Throws CacheFileError naming the file and the system's reason; the temporary file is
// removed then.
inline void write_file_atomically(const std::string& path, const std::vector<std::uint8_t>& bytes) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
    auto fail = [&](const std::string& what, int error) {
        throw CacheFileError("RayCache: cannot save cache file '" + path + "': " + what + ": " + std::strerror(error));
    };
    if (target.filename().empty()) fail("no file name", EISDIR);
    static std::atomic<unsigned> counter{0};
    std::string temporary;
    int fd = -1;
    for (int attempt = 0; fd < 0; ++attempt) {
        temporary = (folder / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                               std::to_string(counter.fetch_add(1)))).string();
        fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd < 0 && (errno != EEXIST || attempt > 100)) fail("creating a temporary file in '" + folder.string() + "'", errno);
    }
    auto abandon = [&](const std::string& what) {
        const int error = errno;
        if (fd >= 0) ::close(fd);
        ::unlink(temporary.c_str());
        fail(what, error);
    };
    for (std::size_t done = 0; done < bytes.size();) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) abandon("writing " + temporary);
        done += static_cast<std::size_t>(n);
    }
    if (::fsync(fd) != 0) abandon("fsync of " + temporary);
    const int closed = ::close(fd);
    fd = -1;
    if (closed != 0) abandon("closing " + temporary);
    if (::rename(temporary.c_str(), path.c_str()) != 0) abandon("renaming " + temporary + " over it");
    const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir < 0) fail("opening its folder to fsync it", errno);
    const int synced = ::fsync(dir), error = errno;
    ::close(dir);
    if (synced != 0 && error != EINVAL) fail("fsync of its folder", error); // EINVAL: folders cannot be synced there
}

// The whole file. Throws CacheFileError naming the file and the system's reason.
inline std::vector<std::uint8_t> read_whole_file(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw CacheFileError("RayCache: cache file '" + path + "' is a folder");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw CacheFileError("RayCache: cannot open cache file '" + path + "': " + std::strerror(errno));
    std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw CacheFileError("RayCache: cannot read cache file '" + path + "': " + std::strerror(errno));
    return bytes;
}

// encode_cache, written atomically to `path` (write_file_atomically). Between frames.
template <class Texel>
void save_cache_file(const std::string& path, const SceneIdentity& scene, const std::vector<CubeToSave<Texel>>& cubes) {
    write_file_atomically(path, encode_cache(scene, cubes));
}

// decode_cache of the file at `path`. Throws CacheFileError naming the file and what is wrong.
template <class Texel>
std::vector<LoadedCube<Texel>> load_cache_file(const std::string& path, const SceneIdentity& expected,
                                               const std::shared_ptr<MemoryBudget>& budget = nullptr,
                                               std::optional<bool> path_records = true) {
    const std::vector<std::uint8_t> bytes = read_whole_file(path);
    return decode_cache<Texel>(bytes.data(), bytes.size(), expected, budget, "cache file '" + path + "'", path_records);
}

// One cube alone: saves `cube`, placed at `bounds`, as object `object` of `scene`. Between frames.
template <class Texel>
void save_cube(const std::string& path, const CacheCube<Texel>& cube, const CubeBounds& bounds, const SceneIdentity& scene,
               std::uint64_t object = 0) {
    save_cache_file<Texel>(path, scene, {CubeToSave<Texel>{object, bounds, &cube}});
}

// Replaces `target` by the one cube saved in `path`, at the face size it was saved with, drawing on
// target's budget; its texels are visible at once, with their tiles' origin boxes and doubtful marks. The file must hold one cube, of
// object `object` (part 0), placed at `bounds`, for `scene`. Otherwise throws CacheFileError and leaves
// `target` as it was. Between frames.
// A DepthPyramid of the cube must be rebuilt (DepthPyramid(target.face_size()).rebuild(target)).
template <class Texel>
void load_cube(const std::string& path, CacheCube<Texel>& target, const CubeBounds& bounds, const SceneIdentity& scene,
               std::uint64_t object = 0) {
    std::vector<LoadedCube<Texel>> cubes = load_cache_file<Texel>(path, scene, target.budget());
    const std::string source = "RayCache: cache file '" + path + "': ";
    if (cubes.size() != 1)
        throw CacheFileError(source + "it holds " + std::to_string(cubes.size()) + " cubes, not one; nothing was loaded");
    if (cubes[0].object != object || cubes[0].part != 0)
        throw CacheFileError(source + "its cube is " + detail::key_text(cubes[0].object, cubes[0].part) + ", not object " +
                             std::to_string(object) + "; nothing was loaded");
    if (!same_placement(cubes[0].bounds, bounds))
        throw CacheFileError(source + "its cube sits at " + describe(cubes[0].bounds) + ", this one at " + describe(bounds) +
                             "; nothing was loaded");
    cubes[0].cube->begin_frame(); // visible to the next lookup
    target = std::move(*cubes[0].cube);
}

} // namespace raycache
