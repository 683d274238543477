// raycache/cache_cube.hpp: CacheCube<Texel>, the six N x N texel faces around one cached object.
//
// Frames and determinism. A store becomes visible to lookups from the next begin_frame() on; during the
// frame it was made in, its texel reads as empty. So every lookup of a frame sees the same cube whatever
// the thread timing, and a frame rendered with a cold cube traces every cached ray, exactly as without
// the cache. When several stores reach one texel in the same frame, the smallest packed word wins.
// A texel that is already visible keeps its value until clear() or invalidate(), or until its tile is
// dropped as stale (below). A texel marked
// doubtful (set_doubtful(), between frames; see raycache/edge_confidence.hpp) keeps its value but reads
// as empty to lookups, so the rays that reach it are traced.
//
// Memory. Texels live in tiles of 16 x 16 (smaller faces: one tile per face), allocated on a tile's
// first store, so a cube costs what its rays have touched, not 6 N^2 texels: most of a large cube is
// never reached. With a MemoryBudget, a tile that does not fit is not allocated and its stores are
// refused (the ray is traced as without a cache). Which tiles of a frame fit would then depend on thread
// timing, so after a frame in which the budget refused anything, begin_frame() (or settle_budget()) gives
// back every tile that frame allocated and allocates the tiles the frame wanted (those and the refused
// ones) again, empty, in tile order while they fit: their rays fill them from the next frame on, and what
// the cube holds depends on the rays alone. clear() gives every tile back.
//
// Origins. The CCT keys texels by direction alone and so assumes the surroundings are far away; when the
// camera circles a mirror, the point a direction leaves from drifts and the cached colour goes stale.
// store(direction, value, origin) widens its tile's box of origins (pending until the next begin_frame()),
// and lookup(direction, origin, drift) misses, marking the tile stale, when the origin lies more than
// `drift` outside the tile's visible box. begin_frame() drops stale tiles, which refill from the current
// rays. A fixed drift suits far surroundings only: a surface at distance d seen from an origin moved by s
// shifts by about s / d radians, so near surfaces (a floor under a mirror ball) go wrong long before far
// ones. Stores given the hit distance keep, per tile, the nearest surface its rays met, and a lookup with
// an OriginTolerance allows at most `parallax` x that distance of drift. Boxes, distances and marks are
// order-independent (min, max, or), read only from frame-constant state.
//
// Threads. lookup(), peek() and store() may run on any number of threads at once, on one cube, without
// locks (lookups are wait-free; a tile's first store claims its table entry with one CAS, allocates the
// tile and publishes it; other stores to that tile wait for it meanwhile).
// begin_frame(), clear() and invalidate() must run between frames, when no other thread uses the cube.
// Debug builds check that rule (RAYCACHE_CHECK_FRAME_RULE, on unless NDEBUG): lookups, stores and the
// helpers that wrap them (cached_trace, the CDCT searches, SceneCache::leaving_ray: across the caller's
// trace too) count themselves in_frame(), and the between-frames calls assert that nobody is counted.
#pragma once

#include "raycache/requires_cpp17.hpp"

#if !defined(RAYCACHE_CHECK_FRAME_RULE) && !defined(NDEBUG)
#define RAYCACHE_CHECK_FRAME_RULE 1
#endif

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "raycache/assert.hpp"
#include "raycache/cube_face.hpp"
#include "raycache/memory_budget.hpp"
#include "raycache/path_record.hpp"
#include "raycache/shared/origin_rule.h"
#include "raycache/shared/ray_box.h"
#include "raycache/statistics.hpp"
#include "raycache/texel.hpp"

namespace raycache {

// How far a ray's origin may lie outside the origins its tile was stored from and still be answered:
// `drift` world units, and no more than `parallax` times the distance to the nearest surface the tile's
// stored rays hit (the angle, in radians, by which that surface may appear to move; infinity: no bound).
struct OriginTolerance {
    float drift = 0.0f;
    float parallax = std::numeric_limits<float>::infinity();
};

template <class Texel>
class CacheCube {
    using Traits = TexelTraits<Texel>; // checks the Texel type's requirements

public:
    using Word = typename Traits::Word;
    using Value = typename Traits::Value;

    // Texels along a tile's edge (faces smaller than this have one tile each).
    static constexpr int tile_edge = static_cast<int>(RAYCACHE_ORIGIN_TILE_EDGE);
    // Path records (raycache/invalidation.hpp) are kept per block of record_edge x record_edge texels of a
    // tile: a path that hit a moved object then costs the texels of its block, not the whole tile's. The
    // unions of fewer, more alike paths are narrower: one object of 32 moving on behind-32, blocks of 4 x 4
    // kept about ten points more of a CDCT's texels per move than 8 x 8 blocks, and 2 x 2 blocks four more
    // again (88% -> 92%), for 3 KiB more a tile than 4 x 4 (kept only once objects move: PathRecords).
    static constexpr int record_edge = 2;
    static constexpr int record_blocks = (tile_edge / record_edge) * (tile_edge / record_edge);
    static_assert(tile_edge % record_edge == 0, "record blocks tile a tile");
    // The blocks fall in groups of record_group_edge x record_group_edge blocks (4 x 4 texels), each with
    // the union of its blocks' paths, after the blocks' records: invalidation tests a tile's groups by these
    // and reads the blocks of only the groups that met a change (most groups of a tile that met one).
    static constexpr int record_group_edge = tile_edge / record_edge >= 2 ? 2 : 1;
    static constexpr int record_groups_per_side = tile_edge / record_edge / record_group_edge;
    static constexpr int record_groups = record_groups_per_side * record_groups_per_side;
    static_assert((tile_edge / record_edge) % record_group_edge == 0, "groups tile a tile");
    static constexpr int first_group_slot = record_blocks;
    // Then the union of the whole tile's paths, so that invalidation can pass over a tile that no change
    // can reach without reading its groups.
    static constexpr int tile_union_slot = record_blocks + record_groups;
    // Bit k of the index spread to nibble k (0xF << 4 k), for the four bits of a row of groups.
    static constexpr std::uint64_t nibbles_of_bits[16] = {
        0x0000, 0x000F, 0x00F0, 0x00FF, 0x0F00, 0x0F0F, 0x0FF0, 0x0FFF,
        0xF000, 0xF00F, 0xF0F0, 0xF0FF, 0xFF00, 0xFF0F, 0xFFF0, 0xFFFF};
    // The group of record block `block` of a tile (unsigned: the divisions by powers of two are shifts).
    static constexpr int group_of_block(int block) noexcept {
        constexpr unsigned per_side = tile_edge / record_edge;
        const auto b = static_cast<unsigned>(block);
        return static_cast<int>(b / per_side / record_group_edge * record_groups_per_side + b % per_side / record_group_edge);
    }

    // A cube of six face_size x face_size faces, every texel invalid and no tile allocated yet.
    // budget: optional, shared with other cubes; its limit bounds the tiles this cube allocates (the cube's
    // fixed part, fixed_bytes(): tile table, tile bitmaps and counters, is charged whatever the limit; a
    // SceneCache makes no cube whose fixed part the budget has no room for). May be null: no limit.
    // path_records: whether its tiles keep what their stores' paths saw (raycache/invalidation.hpp), a
    // record per 2 x 2 block, per 4 x 4 group and per tile (tile_bytes()); without, stores with a record
    // count as stores without one, so exact invalidation empties their texels at any change: for static
    // scenes, in 82% (CCT) or 72% (CDCT) less memory.
    // Throws std::invalid_argument unless 1 <= face_size <= 4096.
    explicit CacheCube(int face_size, std::shared_ptr<MemoryBudget> budget = nullptr, bool path_records = true)
        : face_size_(checked_face_size(face_size)),
          tiles_per_edge_((face_size + tile_edge - 1) / tile_edge),
          tile_count_(std::size_t{RAYCACHE_FACE_COUNT} * static_cast<std::size_t>(tiles_per_edge_) * static_cast<std::size_t>(tiles_per_edge_)),
          path_records_(path_records),
          state_(new State(tile_count())),
          budget_(std::move(budget)) {
        if (budget_) {
            budget_->reserve_always(fixed_bytes(face_size_));
            state_->refusals_seen = budget_->refusals();
        }
    }
    ~CacheCube() { give_back(); }
    CacheCube(const CacheCube&) = delete;
    CacheCube& operator=(const CacheCube&) = delete;
    // A moved-from cube may only be destroyed or assigned to.
    CacheCube(CacheCube&&) noexcept = default;
    CacheCube& operator=(CacheCube&& other) noexcept {
        if (this != &other) {
            give_back();
            face_size_ = other.face_size_;
            tiles_per_edge_ = other.tiles_per_edge_;
            tile_count_ = other.tile_count_;
            path_records_ = other.path_records_;
            state_ = std::move(other.state_);
            budget_ = std::move(other.budget_);
        }
        return *this;
    }

    int face_size() const noexcept { return face_size_; }
    // 6 * N * N.
    std::size_t texel_count() const noexcept { return std::size_t{RAYCACHE_FACE_COUNT} * face_size_ * face_size_; }
    // Bytes that 6 * N * N texels take, 6 * N * N * sizeof(Word): the thesis's memory per cube, and what this
    // cube would hold with every tile allocated (see allocated_bytes() for what it holds).
    std::size_t texel_bytes() const noexcept { return texel_count() * sizeof(Word); }
    // Every byte the cube holds now, all charged to its budget: its fixed part and its allocated tiles.
    std::size_t bytes() const noexcept { return fixed_bytes(face_size_) + allocated_bytes(); }
    // The bytes a cube of `face_size` holds whatever it stores: its tile table (an 8-byte pointer a tile), two
    // bitmaps of a bit a tile (settle_budget()), its counters and the cube object itself.
    static std::size_t fixed_bytes(int face_size) noexcept {
        const std::size_t tiles = tile_count(face_size);
        return sizeof(CacheCube) + sizeof(State) + tiles * sizeof(std::atomic<Tile*>) + 2 * TileBitmap::bytes_for(tiles);
    }
    // Bounds of fixed_bytes() for budget planning (raycache/adaptive_resolution.hpp): a cube of face size N
    // holds at most fixed_bytes_per_cube() + fixed_bytes_per_tile x 6 ceil(N / 16)^2 bytes whatever it
    // stores (a table entry and its two bitmap bits, rounded up to a byte, a tile; the bitmaps' last words).
    static constexpr std::size_t fixed_bytes_per_tile = sizeof(void*) + 1;
    static constexpr std::size_t fixed_bytes_per_cube() noexcept { return sizeof(CacheCube) + sizeof(State) + 2 * sizeof(std::uint64_t); }
    // Bytes of the tiles allocated so far (each bytes_per_tile()).
    std::size_t allocated_bytes() const noexcept { return allocated_tiles() * bytes_per_tile(); }
    std::size_t allocated_tiles() const noexcept { return state_->allocated_tiles.load(std::memory_order_relaxed); }
    // Bytes of one tile: 16 x 16 words, their bits, its origin boxes and, with path_records, a path record
    // per 2 x 2 block, the unions of its 4 x 4 groups and the tile's union (in the same allocation).
    static constexpr std::size_t tile_bytes(bool path_records = true) noexcept {
        return sizeof(Tile) + (path_records ? sizeof(PathUnion) * (tile_union_slot + 1) : 0);
    }
    std::size_t bytes_per_tile() const noexcept { return tile_bytes(path_records_); }
    // Whether the tiles keep path records (the constructor's path_records).
    bool keeps_path_records() const noexcept { return path_records_; }
    const std::shared_ptr<MemoryBudget>& budget() const noexcept { return budget_; }

    // Counts the calling thread as using the cube within a frame for as long as the returned object lives
    // (debug builds; nothing in release builds). Between-frames calls assert that no such object lives.
    class InFrame {
    public:
        explicit InFrame(const CacheCube* cube) noexcept : cube_(cube) { enter(1); }
        ~InFrame() { enter(-1); }
        InFrame(const InFrame&) = delete;
        InFrame& operator=(const InFrame&) = delete;

    private:
        void enter(int delta) noexcept {
#if RAYCACHE_CHECK_FRAME_RULE
            cube_->state_->users.fetch_add(delta, std::memory_order_relaxed);
#else
            (void)delta;
#endif
        }
        const CacheCube* cube_;
    };
    InFrame in_frame() const noexcept { return InFrame(this); }

    // Asserts (debug builds) that no thread is inside a lookup, store or in_frame() scope of this cube:
    // the rule for begin_frame(), clear(), invalidate() and structures updated from the cube between frames.
    void assert_between_frames() const noexcept {
#if RAYCACHE_CHECK_FRAME_RULE
        RAYCACHE_ASSERT(state_->users.load(std::memory_order_relaxed) == 0 &&
                        "RayCache: begin_frame(), clear(), invalidate() and pyramid updates run between frames, "
                        "while no thread looks up, stores or searches");
#endif
    }

    // The value cached for `direction`, counted as a hit or a miss (with its MissReason). std::nullopt (a
    // miss) when the texel is empty, was written this frame, is doubtful, or `direction` is not a direction.
    // Thread-safe, wait-free.
    std::optional<Value> lookup(const glm::vec3& direction) noexcept {
        const std::optional<TexelAddress> t = texel_of(direction);
        if (!t) {
            record_miss(MissReason::outside);
            return std::nullopt;
        }
        return lookup_at(*t);
    }

    // lookup() for a ray leaving from `origin`: a miss also when `origin` lies more than `drift` outside the
    // box of the origins its tile's visible texels were stored from; the tile is then marked stale and
    // dropped at the next begin_frame(). Thread-safe, wait-free (a marking is one relaxed store).
    std::optional<Value> lookup(const glm::vec3& direction, const glm::vec3& origin, float drift) noexcept {
        return lookup(direction, origin, OriginTolerance{drift});
    }

    // lookup(direction, origin, drift) with the drift also bounded by parallax (OriginTolerance): a tile whose
    // rays met a surface at distance d answers origins within min(drift, parallax * d) of its box (drift
    // alone while none of its stores gave a finite distance).
    std::optional<Value> lookup(const glm::vec3& direction, const glm::vec3& origin, const OriginTolerance& tolerance) noexcept {
        const std::optional<TexelAddress> t = texel_of(direction);
        if (!t) {
            record_miss(MissReason::outside);
            return std::nullopt;
        }
        return lookup_at(*t, origin, tolerance);
    }

    // The texel `direction` falls in (the face table of cube_face.hpp); std::nullopt when it is not a
    // direction. With lookup_at() and store_at(), a ray that looks up and then stores computes it once.
    RAYCACHE_HOT_FN std::optional<TexelAddress> texel_of(const glm::vec3& direction) const noexcept {
        const shared::raycache_texel_address a = shared::raycache_texel_of(direction, face_size_);
        if (a.face == RAYCACHE_NO_FACE) return std::nullopt;
        return TexelAddress{a.face, a.column, a.row};
    }

    // lookup(direction) of texel `t` (from texel_of(); must lie on the cube, asserted): counted, no origin test.
    std::optional<Value> lookup_at(const TexelAddress& t) noexcept {
        const InFrame use = in_frame();
        RAYCACHE_ASSERT(contains(t));
        if (!contains(t)) {
            record_miss(MissReason::outside);
            return std::nullopt;
        }
        MissReason why = MissReason::empty;
        std::optional<Value> value = visible_value(tile_of(t), t, &why);
        if (value) record_hit();
        else record_miss(why);
        return value;
    }

    // lookup(direction, origin, tolerance) of texel `t` (from texel_of(); must lie on the cube, asserted).
    std::optional<Value> lookup_at(const TexelAddress& t, const glm::vec3& origin, const OriginTolerance& tolerance) noexcept {
        const InFrame use = in_frame();
        RAYCACHE_ASSERT(contains(t));
        if (!contains(t)) {
            record_miss(MissReason::outside);
            return std::nullopt;
        }
        Tile* tile = tile_of(t);
        MissReason why = MissReason::empty;
        std::optional<Value> value = visible_value(tile, t, &why);
        if (!value) {
            record_miss(why);
        } else if (!tile->origins_cover(origin, tile->allowed_drift(tolerance, tile->nearest))) {
            if (!tile->stale.load(std::memory_order_relaxed)) tile->stale.store(1u, std::memory_order_relaxed);
            value.reset();
            record_miss(MissReason::origin);
        } else {
            record_hit();
        }
        return value;
    }

    // lookup() without counting, for searches that read many texels per ray (count them with record_hit() and
    // record_miss()).
    // With `why`, a miss also says its cause there (why_missed()'s answer, without finding the texel again).
    RAYCACHE_HOT_FN std::optional<Value> peek(const glm::vec3& direction, MissReason* why = nullptr) const noexcept {
        const std::optional<TexelAddress> t = texel_of(direction);
        if (!t) {
            if (why) *why = MissReason::outside;
            return std::nullopt;
        }
        return visible_value(tile_of(*t), *t, why);
    }

    // The value of `texel` as a lookup would see it (empty, or written this frame: std::nullopt), without
    // counting: for filters and searches that read texels by address. `texel` must lie on the cube (asserted).
    RAYCACHE_HOT_FN std::optional<Value> peek_at(const TexelAddress& texel) const noexcept {
        RAYCACHE_ASSERT(contains(texel));
        if (!contains(texel)) return std::nullopt;
        return visible_value(texel);
    }

    // Count one lookup made of peek() calls: a hit, or a miss and why (why_missed() names the state of a
    // texel whose read found nothing). Thread-safe, wait-free.
    void record_hit() noexcept { state_->counters.add(hits); }
    // (Always inlined: it is all a resting cube's ray costs the cube besides the probe test.)
    RAYCACHE_HOT_FN void record_miss(MissReason why) noexcept { state_->counters.add(first_miss + static_cast<std::size_t>(why)); }
    // Count what a ray that filled a texel reported it cost (TracedRay::work; 0: not reported, not counted):
    // cached_trace's helpers call it after a store that wrote. Thread-safe, wait-free.
    void record_filled_work(std::uint32_t work) noexcept {
        if (!work) return;
        state_->counters.add(filled_work, work);
        state_->counters.add(work_reports);
    }
    // record_hit(), or record_miss(MissReason::search): a miss with no cause given counts as a search's.
    void record_lookup(bool hit) noexcept {
        if (hit) record_hit();
        else record_miss(MissReason::search);
    }

    // Why peek_at(texel) finds nothing: empty (no value, or no tile), fresh (stored this frame) or doubtful;
    // outside for a texel off the cube. For a texel whose peek finds a value, empty. Between frames or
    // during one, as peek_at(). Out of line: misses only.
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((noinline, cold))
#endif
    MissReason why_missed_at(const TexelAddress& texel) const noexcept {
        if (!contains(texel)) return MissReason::outside;
        MissReason why = MissReason::empty;
        (void)visible_value(tile_of(texel), texel, &why);
        return why;
    }
    // why_missed_at() for the texel of `direction`; outside when it is not a direction. Out of line: misses only.
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((noinline, cold))
#endif
    MissReason why_missed(const glm::vec3& direction) const noexcept {
        const std::optional<TexelAddress> t = texel_of(direction);
        return t ? why_missed_at(*t) : MissReason::outside;
    }

    // Caches `value` in the texel of `direction`; returns whether it was written. Refused (false) when
    // `direction` is not a direction, the value cannot be encoded, the texel already holds a visible
    // value, a smaller word was stored into it this frame, or its tile does not fit the budget.
    // Visible from the next begin_frame(). Thread-safe, lock-free.
    bool store(const glm::vec3& direction, const Value& value) noexcept {
        const InFrame use = in_frame();
        const std::optional<TexelAddress> t = texel_of(direction);
        return t ? store_word(*t, Texel::encode(value)) : refuse();
    }

    // store() for a ray that left from `origin`: also widens its tile's pending box of origins (unless the
    // texel already holds a visible value), which lookup(direction, origin, drift) reads from the next frame on.
    bool store(const glm::vec3& direction, const Value& value, const glm::vec3& origin) noexcept {
        return store(direction, value, origin, std::numeric_limits<float>::infinity());
    }

    // store(direction, value, origin) for a ray whose hit lay `hit_distance` along the unit direction
    // (infinity: it escaped): the tile also keeps the nearest such distance, which bounds the drift of
    // lookups given a parallax (OriginTolerance). A NaN or negative distance is refused.
    bool store(const glm::vec3& direction, const Value& value, const glm::vec3& origin, float hit_distance) noexcept {
        return store(direction, value, origin, hit_distance, OriginTolerance{std::numeric_limits<float>::infinity()});
    }

    // store(direction, value, origin, hit_distance) that keeps the tile's origins tight: refused when the tile
    // already has a visible origin box and adding `origin` would make it wider, on any axis, than the
    // drift `tolerance` allows for the tile (its nearest hit distance, or this one when nearer). Otherwise a
    // tile filled a little more each frame along a moving camera would stretch its box along the path, and
    // its first values would answer rays from ever further away. Only frame-constant state decides.
    bool store(const glm::vec3& direction, const Value& value, const glm::vec3& origin, float hit_distance,
               const OriginTolerance& tolerance) noexcept {
        const std::optional<TexelAddress> t = texel_of(direction);
        return t ? store_at(*t, value, origin, hit_distance, tolerance) : refuse();
    }

    // store() of a traced ray with what its path saw (raycache/path_record.hpp): when the word is written, its
    // tile adds `path` to the union of its stores' records and marks the texel as recorded, for
    // raycache/invalidation.hpp. Texels stored without a record count as having seen anything.
    bool store(const glm::vec3& direction, const Value& value, const glm::vec3& origin, float hit_distance,
               const OriginTolerance& tolerance, const PathRecord& path) noexcept {
        const std::optional<TexelAddress> t = texel_of(direction);
        return t ? store_at(*t, value, origin, hit_distance, tolerance, &path) : refuse();
    }
    bool store(const glm::vec3& direction, const Value& value, const PathRecord& path) noexcept {
        const std::optional<TexelAddress> t = texel_of(direction);
        return t ? store_at(*t, value, path) : refuse();
    }

    // store(direction, value, origin, hit_distance, tolerance[, path]) into texel `t` (from texel_of(); must
    // lie on the cube, asserted); path null: stored without a record.
    bool store_at(const TexelAddress& t, const Value& value, const glm::vec3& origin, float hit_distance,
                  const OriginTolerance& tolerance, const PathRecord* path = nullptr) noexcept {
        const InFrame use = in_frame();
        RAYCACHE_ASSERT(contains(t));
        if (!contains(t) || !shared::raycache_is_finite3(origin) || !(hit_distance >= 0.0f)) return refuse();
        const StoreOrigin from{origin, hit_distance, tolerance};
        return store_word(t, Texel::encode(value), &from, path);
    }

    // Bits of BlockState::path_flags: what a block's recorded paths did (raycache/path_record.hpp).
    static constexpr std::uint32_t path_lit = 1u, path_chained = 2u, path_unbounded = 4u;
    static constexpr std::uint32_t all_path_flags = path_lit | path_chained | path_unbounded;
    // A record's lit, chained and unbounded as path flags, and back.
    static std::uint32_t path_flags_of(const PathRecord& r) noexcept {
        return (r.lit ? path_lit : 0u) | (r.chained ? path_chained : 0u) | (r.unbounded ? path_unbounded : 0u);
    }
    static void set_path_flags(PathRecord& r, std::uint32_t flags) noexcept {
        r.lit = (flags & path_lit) != 0;
        r.chained = (flags & path_chained) != 0;
        r.unbounded = (flags & path_unbounded) != 0;
    }

    // Where one record block (record_edge x record_edge texels) of an allocated tile lies, and how many of
    // its texels hold values: what the passes over a block's texels need (invalidate_in_block() and others).
    struct BlockPlace {
        std::size_t tile;                // the tile's index
        int block;                       // the block within the tile
        int face, column0, row0, column1, row1; // texels [column0, column1) x [row0, row1) of the face
        int unrecorded_texels;           // texels of the block holding a value whose store brought no path record
        int valid_texels;                // texels of the block holding a value (recorded or not)
    };

    // A union of path records as a tile keeps it: the boxes' floats as ordered keys, so that a union of
    // unions is integer minima and maxima, with no float converted (invalidation merges a tile's blocks so
    // and decodes, with record(), only the unions it tests).
    struct PathKeys {
        std::uint64_t objects;                      // Bloom mask of the objects hit
        std::uint32_t vertex_min[3], vertex_max[3]; // ordered floats; empty while min > max
        std::uint32_t escape_min[3], escape_max[3]; // escaped bounces' directions, the same way
        std::uint32_t flags;                        // path_lit | path_chained | path_unbounded
        std::uint64_t cached_reads;                 // direction cells of nested cached answers

        // The union of no paths.
        static PathKeys empty() noexcept {
            return PathKeys{0, {~0u, ~0u, ~0u}, {0u, 0u, 0u}, {~0u, ~0u, ~0u}, {0u, 0u, 0u}, 0u, 0};
        }
        // PathRecord::merge() in key form. Its rule for escapes from nowhere needs no test here: a tile's
        // union holding such a path is unbounded already (merge_path()), and so is every union of it.
        void merge(const PathKeys& o) noexcept {
            objects |= o.objects;
            for (int k = 0; k < 3; ++k) {
                vertex_min[k] = std::min(vertex_min[k], o.vertex_min[k]);
                vertex_max[k] = std::max(vertex_max[k], o.vertex_max[k]);
                escape_min[k] = std::min(escape_min[k], o.escape_min[k]);
                escape_max[k] = std::max(escape_max[k], o.escape_max[k]);
            }
            flags |= o.flags;
            cached_reads |= o.cached_reads;
        }
        // Whether record() holds hit points, or escapes: its box's x extent as record() decodes it (keys in
        // order, then the floats, which a NaN key fails), so that a test of emptiness needs no decoding.
        bool has_vertices() const noexcept { return holds_box(vertex_min, vertex_max); }
        bool has_escapes() const noexcept { return holds_box(escape_min, escape_max); }
        bool unbounded() const noexcept { return (flags & path_unbounded) != 0; } // record().unbounded
        // The union as one PathRecord (empty boxes as PathRecord keeps them).
        PathRecord record() const noexcept {
            PathRecord r = PathRecord::empty();
            r.objects = objects;
            r.cached_reads = cached_reads;
            set_path_flags(r, flags);
            glm::vec3 lo, hi;
            read_box(vertex_min, vertex_max, lo, hi);
            if (lo.x <= hi.x) r.vertex_lo = lo, r.vertex_hi = hi;
            read_box(escape_min, escape_max, lo, hi);
            if (lo.x <= hi.x) r.escape_lo = lo, r.escape_hi = hi;
            return r;
        }

    private:
        static bool holds_box(const std::uint32_t (&min)[3], const std::uint32_t (&max)[3]) noexcept {
            return !(min[0] > max[0]) && unordered(min[0]) <= unordered(max[0]);
        }
    };

    // One record block of an allocated tile with the union of the path records stored into its texels, for
    // invalidation (raycache/invalidation.hpp) and cache files.
    struct BlockState : BlockPlace {
        std::uint64_t objects;           // Bloom mask of the objects the recorded paths hit
        glm::vec3 vertex_lo, vertex_hi;  // box of their hit points; empty while lo.x > hi.x
        glm::vec3 escape_lo, escape_hi;  // box of their escaped bounces' unit directions; empty while lo.x > hi.x
        std::uint32_t path_flags;        // path_lit | path_chained | path_unbounded
        std::uint64_t cached_reads;      // direction cells their nested cached answers read (PathRecord::cached_reads)

        bool lit() const noexcept { return (path_flags & path_lit) != 0; }             // a path cast shadow rays
        bool chained() const noexcept { return (path_flags & path_chained) != 0; }     // bounced between hit points
        bool unbounded() const noexcept { return (path_flags & path_unbounded) != 0; } // escaped with no bound
        // The block's union as one PathRecord (empty boxes as PathRecord keeps them), for merging.
        PathRecord record() const noexcept {
            PathRecord r = PathRecord::empty();
            r.objects = objects;
            r.cached_reads = cached_reads;
            if (vertex_lo.x <= vertex_hi.x) r.vertex_lo = vertex_lo, r.vertex_hi = vertex_hi;
            if (escape_lo.x <= escape_hi.x) r.escape_lo = escape_lo, r.escape_hi = escape_hi;
            set_path_flags(r, path_flags);
            return r;
        }
    };

    // f(const BlockState&) for every record block holding a value, of every allocated tile, in tile then
    // block order. Between frames only.
    template <class F>
    void for_each_block_state(F&& f) const {
        for (std::size_t i = 0, count = tile_count(); i < count; ++i) for_each_block_state_of_tile(i, f);
    }

    // The indices of the allocated tiles, ascending (for spreading for_each_block_state_of_tile() over
    // threads). Between frames only.
    std::vector<std::size_t> allocated_tile_indices() const {
        std::vector<std::size_t> indices;
        indices.reserve(allocated_tiles());
        for (std::size_t i = 0, count = tile_count(); i < count; ++i)
            if (state_->tiles[i].load(std::memory_order_acquire)) indices.push_back(i);
        return indices;
    }

    // for_each_block_state() for tile `i` alone (nothing when it is not allocated). Between frames only;
    // threads may read different tiles at once.
    template <class F>
    void for_each_block_state_of_tile(std::size_t i, F&& f) const {
        for_each_block_keys_of_tile(i, [&](const BlockPlace& place, const PathKeys& keys) {
            BlockState t{};
            static_cast<BlockPlace&>(t) = place;
            t.objects = keys.objects;
            t.path_flags = keys.flags;
            t.cached_reads = keys.cached_reads;
            read_box(keys.vertex_min, keys.vertex_max, t.vertex_lo, t.vertex_hi);
            read_box(keys.escape_min, keys.escape_max, t.escape_lo, t.escape_hi);
            f(static_cast<const BlockState&>(t));
        });
    }

    // f(const BlockPlace&, const PathKeys&) for every record block of tile `i` holding a value, in block
    // order, with its union of paths as the tile keeps it (for_each_block_state_of_tile() without decoding
    // the boxes: invalidation merges blocks before it tests them). Between frames only; threads may read
    // different tiles at once.
    template <class F>
    void for_each_block_keys_of_tile(std::size_t i, F&& f) const {
        const Tile* tile = allocated_tile(i);
        if (!tile) return;
        for_each_block_of_tile(i, [&](const BlockPlace& place) {
            f(place, tile->records ? tile->records[place.block].keys() : PathKeys::empty());
        });
    }

    // Bit g for each group g (group_of_block()) of tile `i` with a texel holding a value stored with a path
    // record; 0 when the tile is not allocated. Between frames only.
    static constexpr std::uint32_t all_record_groups = record_groups >= 32 ? ~0u : (1u << record_groups) - 1u;
    std::uint32_t groups_with_records(std::size_t i) const noexcept {
        const Tile* tile = allocated_tile(i);
        if (!tile) return 0;
        constexpr int group_texels = record_group_edge * record_edge; // texels along a group's side
        constexpr std::uint64_t group_columns = (std::uint64_t{1} << group_texels) - 1u;
        std::uint32_t groups = 0;
        for (int gr = 0; gr < record_groups_per_side; ++gr) {
            std::uint64_t rows = 0; // the group row's recorded bits, its rows' masks or'ed
            for (int r = gr * group_texels; r < (gr + 1) * group_texels; ++r)
                rows |= recorded_word(*tile, r * tile_edge / 64) >> (r * tile_edge % 64);
            for (int gc = 0; gc < record_groups_per_side; ++gc)
                if ((rows >> (gc * group_texels)) & group_columns) groups |= 1u << (gr * record_groups_per_side + gc);
        }
        return groups;
    }

    // for_each_block_keys_of_tile() without the unions: f(const BlockPlace&) for every record block of tile
    // `i` holding a value, in block order, in the groups that `groups` names (bit g: group g; invalidation
    // reads the blocks of only the groups it tests, and their unions only when it tests them: block_keys()).
    // Between frames only; threads may read different tiles at once.
    template <class F>
    void for_each_block_of_tile(std::size_t i, F&& f, std::uint32_t groups = all_record_groups) const {
        static_assert(record_groups <= 32, "a group mask holds every group of a tile");
        const Tile* tile = allocated_tile(i);
        if (!tile) return;
        const TexelAddress first = first_texel_of_tile(i);
        const bool any_unrecorded = has_unrecorded(*tile);
        // The recorded texels of each row of the tile (bit c: column c), read once for its blocks; rows and
        // columns off the face (a face smaller than a tile) hold none, and their blocks are left out.
        static_assert(tile_edge < 64 && 64 % tile_edge == 0, "a tile row lies within one bit word");
        const int rows_on_face = std::min(tile_edge, face_size_ - first.row);
        const int columns_on_face = std::min(tile_edge, face_size_ - first.column);
        const std::uint64_t on_face = (std::uint64_t{1} << columns_on_face) - 1u;
        std::uint64_t row_bits[tile_edge];
        for (int r = 0; r < tile_edge; ++r)
            row_bits[r] = r < rows_on_face ? (recorded_word(*tile, r * tile_edge / 64) >> (r * tile_edge % 64)) & on_face : 0u;
        constexpr int per_side = tile_edge / record_edge;
        BlockPlace t{};
        t.tile = i;
        t.face = first.face;
        for (int br = 0; br < per_side && br * record_edge < rows_on_face; ++br) {
            // 2 x 2 blocks: the recorded texels of the row's eight blocks counted at once, in 4-bit fields
            // (a pair of bits counts as v - (v >> 1)): even blocks' in `even`, odd blocks' in `odd`.
            std::uint64_t even = 0, odd = 0;
            if constexpr (record_edge == 2) {
                const std::uint64_t a = row_bits[2 * br], b = row_bits[2 * br + 1];
                constexpr std::uint64_t pairs = 0x5555555555555555ull, fields = 0x3333333333333333ull; // any tile edge below 64
                const std::uint64_t pa = a - ((a >> 1) & pairs), pb = b - ((b >> 1) & pairs);
                even = (pa & fields) + (pb & fields);
                odd = ((pa >> 2) & fields) + ((pb >> 2) & fields);
            }
            // With every value recorded, only the row's blocks holding one in the groups named are visited,
            // bit by bit (bit 2 bc of `visit`: block bc; most blocks of a sparse tile hold none).
            if constexpr (record_edge == 2 && record_group_edge == 2) {
                if (!any_unrecorded) {
                    const std::uint64_t any = row_bits[2 * br] | row_bits[2 * br + 1];
                    std::uint64_t visit = (any | (any >> 1)) & 0x5555555555555555ull;
                    // Nibble gc: the row's blocks of group (br / 2, gc), when `groups` names it.
                    static_assert(record_groups_per_side == 4, "a group row's bits index the table");
                    visit &= nibbles_of_bits[(groups >> ((br / 2) * record_groups_per_side)) & 0xFu];
                    for (; visit != 0; visit &= visit - 1u) {
                        const int bc = count_trailing_zeros(visit) / 2;
                        t.block = br * per_side + bc;
                        t.column0 = first.column + bc * record_edge;
                        t.row0 = first.row + br * record_edge;
                        t.column1 = std::min(face_size_, t.column0 + record_edge);
                        t.row1 = std::min(face_size_, t.row0 + record_edge);
                        t.unrecorded_texels = 0;
                        t.valid_texels = static_cast<int>((((bc & 1) ? odd : even) >> (4 * (bc >> 1))) & 0xFu);
                        f(static_cast<const BlockPlace&>(t));
                    }
                    continue;
                }
            }
            for (int bc = 0; bc < per_side && bc * record_edge < columns_on_face; ++bc) {
                const int b = br * per_side + bc;
                if (!((groups >> group_of_block(b)) & 1u)) continue;
                t.block = b;
                t.column0 = first.column + bc * record_edge;
                t.row0 = first.row + br * record_edge;
                t.column1 = std::min(face_size_, t.column0 + record_edge);
                t.row1 = std::min(face_size_, t.row0 + record_edge);
                t.unrecorded_texels = 0;
                if (any_unrecorded)
                    for_each_texel_of_block(t, [&](const TexelAddress&, int slot) {
                        if (Texel::is_valid(tile->texels[slot].load(std::memory_order_relaxed)) && !recorded(*tile, slot))
                            ++t.unrecorded_texels;
                    });
                // The recorded texels hold values.
                t.valid_texels = t.unrecorded_texels;
                if constexpr (record_edge == 2) {
                    t.valid_texels += static_cast<int>((((bc & 1) ? odd : even) >> (4 * (bc >> 1))) & 0xFu);
                } else {
                    for (int row = t.row0 - first.row; row < t.row1 - first.row; ++row)
                        t.valid_texels += bit_count((row_bits[row] >> (bc * record_edge)) & ((std::uint64_t{1} << record_edge) - 1u));
                }
                // A block holding no value answers for no path and has nothing to empty: it is passed over
                // (most blocks of a sparse tile after a cold frame are such).
                if (t.valid_texels == 0) continue;
                f(static_cast<const BlockPlace&>(t));
            }
        }
    }

    // What invalidation needs of a whole tile before its blocks: where it lies, its origins (as BlockState's),
    // whether a texel holds a value stored without a record, and the union of its blocks' path records (a
    // superset of what its texels saw: stores add to it; retighten_tile_union() drops what emptied blocks held).
    struct TileSummary {
        int face, column0, row0; // the tile's first texel
        bool has_origins;
        glm::vec3 origin_lo, origin_hi;
        bool any_unrecorded;
        PathRecord paths; // empty in a cube without records
    };
    // tile_summary() of tile `i`; std::nullopt when it is not allocated. Between frames only.
    std::optional<TileSummary> tile_summary(std::size_t i) const {
        const Tile* tile = allocated_tile(i);
        if (!tile) return std::nullopt;
        const TexelAddress first = first_texel_of_tile(i);
        TileSummary s{first.face, first.column, first.row, false, glm::vec3(0.0f), glm::vec3(0.0f), has_unrecorded(*tile), paths_of(*tile)};
        s.has_origins = origins_of(*tile, s.origin_lo, s.origin_hi);
        return s;
    }
    // Asks the processor to start loading what tile_summary(i) reads (the tile's bits, origin box, counts
    // and union of paths), so that a pass over many tiles waits on several at once rather than on each in
    // turn. A hint: it changes nothing the cube holds. Between frames.
    void prefetch_tile_summary(std::size_t i) const noexcept {
        const Tile* tile = allocated_tile(i);
        if (!tile) return;
        prefetch_line(&tile->written_bits[0]);
        prefetch_line(&tile->doubtful_bits[0]);
        prefetch_line(&tile->pending_min[0]);
        prefetch_line(&tile->recorded_bits[0]);
        prefetch_line(&tile->records); // the line of the pointer to the records (prefetch_tile_records())
    }
    // Starts loading tile i's union of paths and its groups' unions (tile_summary()'s and group_keys()'), once
    // prefetch_tile_summary(i) brought the tile's own lines. A hint, as that.
    void prefetch_tile_records(std::size_t i) const noexcept {
        const Tile* tile = allocated_tile(i);
        if (!tile || !tile->records) return;
        const char* first = reinterpret_cast<const char*>(&tile->records[first_group_slot]);
        const char* last = reinterpret_cast<const char*>(&tile->records[tile_union_slot + 1]);
        for (const char* p = first; p < last; p += 64) prefetch_line(p);
    }
    // Starts loading tile i's union of paths alone (tile_keys()'), once prefetch_tile_summary(i) brought the
    // line of the pointer to its records: all that a pass testing the union first reads of most tiles (a
    // transitive pass's). A hint, as that.
    void prefetch_tile_union(std::size_t i) const noexcept {
        const Tile* tile = allocated_tile(i);
        if (!tile || !tile->records) return;
        const char* first = reinterpret_cast<const char*>(&tile->records[tile_union_slot]);
        prefetch_line(first);
        prefetch_line(first + sizeof(PathUnion) - 1); // a union can straddle two lines
    }
    // tile_paths() in the form the tile keeps it (PathKeys::record() gives tile_paths()): std::nullopt when
    // the tile is not allocated, the empty union in a cube without records. Between frames only.
    std::optional<PathKeys> tile_keys(std::size_t i) const noexcept {
        const Tile* tile = allocated_tile(i);
        if (!tile) return std::nullopt;
        return tile->records ? tile->records[tile_union_slot].keys() : PathKeys::empty();
    }
    // The union of the paths of tile `i` alone (tile_summary()'s `paths`, without the rest of the summary):
    // empty in a cube without records; std::nullopt when the tile is not allocated. Between frames only.
    std::optional<PathRecord> tile_paths(std::size_t i) const {
        const std::optional<PathKeys> keys = tile_keys(i);
        if (!keys) return std::nullopt;
        return keys->record();
    }
    // What the value texel `t` answers with saw, as far as the cube knows, for a cached answer nested in
    // another traced path (SceneCache::leaving_ray's `enclosing`): the union of the paths stored into its
    // record block so far (a superset of its own store's: a union only grows until a move empties the
    // block), so the enclosing path depends on it even after the texel itself is replaced; unbounded (any
    // move may change it) when its store brought no record. During a frame, on any thread: it reads the
    // block's atomics as they stand. `t` must lie on the cube (asserted).
    PathRecord answer_record(const TexelAddress& t) const noexcept {
        RAYCACHE_ASSERT(contains(t));
        PathRecord unknown = PathRecord::empty();
        unknown.unbounded = true;
        if (!contains(t)) return unknown;
        const Tile* tile = tile_of(t);
        if (!tile || !tile->records || !recorded(*tile, slot_of(t))) return unknown;
        return record_of(tile->records[block_of(t)]);
    }

    // Makes tile `i`'s union `kept` after invalidation emptied some of its texels: the caller, which has
    // just read the tile's blocks, passes the union of those still holding a recorded texel (a union
    // missing any of their paths would let invalidation keep texels a move changed). Between frames only.
    void retighten_tile_union(std::size_t i, const PathKeys& kept) noexcept {
        assert_between_frames();
        Tile* tile = allocated_tile(i);
        if (!tile || !tile->records) return;
        tile->records[tile_union_slot].store(kept);
    }
    // The same for group `group` of tile `i` (group_of_block()): `kept`, the union of its blocks still
    // holding a recorded texel. Between frames only.
    void retighten_group_union(std::size_t i, int group, const PathKeys& kept) noexcept {
        assert_between_frames();
        RAYCACHE_ASSERT(group >= 0 && group < record_groups);
        Tile* tile = allocated_tile(i);
        if (!tile || !tile->records || group < 0 || group >= record_groups) return;
        tile->records[first_group_slot + group].store(kept);
    }

    // The union of the paths stored into record block `b` (from for_each_block_of_tile()), as its tile keeps
    // it; the empty union in a cube without records. Between frames only. Always inlined (keys() is): GCC
    // made it a call once the tile pass's block walk had shrunk (0.4% of a CDCT move).
    RAYCACHE_HOT_FN PathKeys block_keys(const BlockPlace& b) const noexcept {
        RAYCACHE_ASSERT(b.block >= 0 && b.block < record_blocks);
        const Tile* tile = allocated_tile(b.tile);
        if (!tile || !tile->records || b.block < 0 || b.block >= record_blocks) return PathKeys::empty();
        return tile->records[b.block].keys();
    }
    // The union of the paths stored into group `group` of tile `i` (group_of_block()): a superset of its
    // blocks' unions (stores add to both; retighten_group_union() drops what emptied blocks held); the empty
    // union when the tile is not allocated or the cube keeps no records. Between frames only.
    PathKeys group_keys(std::size_t i, int group) const noexcept {
        RAYCACHE_ASSERT(group >= 0 && group < record_groups);
        const Tile* tile = allocated_tile(i);
        if (!tile || !tile->records || group < 0 || group >= record_groups) return PathKeys::empty();
        return tile->records[first_group_slot + group].keys();
    }

    // f(TexelAddress, bool recorded) for each texel of block `b` (from for_each_block_state()) holding a
    // value; `recorded`: its store brought a path record. Between frames only.
    template <class F>
    void for_each_value_of_block(const BlockPlace& b, F&& f) const {
        const Tile* tile = allocated_tile(b.tile);
        if (!tile) return;
        for_each_texel_of_block(b, [&](const TexelAddress& t, int slot) {
            if (Texel::is_valid(tile->texels[slot].load(std::memory_order_relaxed))) f(t, recorded(*tile, slot));
        });
    }

    // Empties the texels of block `b` (from for_each_block_state()) holding a value for which
    // drop(TexelAddress, bool recorded) returns true; `recorded`: the texel's store brought a path record.
    // A block left with no value forgets its path record too (no texel answers for those paths any more),
    // so its next stores start a fresh union. Returns how many were emptied. Between frames only.
    template <class Drop>
    std::size_t invalidate_in_block(const BlockPlace& b, Drop&& drop) {
        assert_between_frames();
        Tile* tile = allocated_tile(b.tile);
        if (!tile) return 0;
        // invalidate() texel by texel, with the bits and counts updated once for the block (between frames
        // no other thread touches the cube, so the words need no read-modify-write of their own).
        std::size_t dropped = 0, kept = 0;
        std::uint64_t gone[bit_words] = {};
        for_each_texel_of_block(b, [&](const TexelAddress& t, int slot) {
            if (!Texel::is_valid(tile->texels[slot].load(std::memory_order_relaxed))) return;
            if (!drop(t, recorded(*tile, slot))) return void(++kept);
            tile->texels[slot].store(Texel::invalid, std::memory_order_relaxed);
            gone[slot / 64] |= std::uint64_t{1} << (slot % 64);
            ++dropped;
        });
        if (dropped > 0) forget_emptied(*tile, gone, dropped);
        if (dropped > 0 && kept == 0 && tile->records) tile->records[b.block].clear();
        return dropped;
    }

    // Marks every valid texel of block `b` (from for_each_block_state()) as recorded and adds `path` to the
    // block's record: for texels copied from another cube whose records are known (carry_path_records, a
    // cache file's records), also when they were copied in this frame by stores without a record.
    // Nothing in a cube without path records. Between frames.
    void record_texels_of_block(const BlockPlace& b, const PathRecord& path) noexcept {
        assert_between_frames();
        Tile* tile = allocated_tile(b.tile);
        if (!tile || !tile->records) return; // a cube without records: its texels stay unrecorded
        for_each_texel_of_block(b, [&](const TexelAddress&, int slot) {
            if (!Texel::is_valid(tile->texels[slot].load(std::memory_order_relaxed))) return;
            const std::uint64_t bit = std::uint64_t{1} << (slot % 64);
            tile->recorded_bits[slot / 64].fetch_or(bit, std::memory_order_relaxed);
            tile->unrecorded_bits[slot / 64].fetch_and(~bit, std::memory_order_relaxed); // copied in without one: known now
        });
        merge_path(tile->records[b.block], path);
        merge_path(tile->records[first_group_slot + group_of_block(b.block)], path);
        merge_path(tile->records[tile_union_slot], path);
    }

    // store() by address (named apart so that a braced {face, column, row} never reads as a direction);
    // `texel` must lie on the cube (asserted).
    bool store_at(const TexelAddress& texel, const Value& value) noexcept {
        RAYCACHE_ASSERT(contains(texel));
        if (!contains(texel)) return refuse();
        return store_word(texel, Texel::encode(value));
    }
    // store_at(texel, value) with what the stored ray's path saw (as store(direction, value, path)).
    bool store_at(const TexelAddress& texel, const Value& value, const PathRecord& path) noexcept {
        const InFrame use = in_frame();
        RAYCACHE_ASSERT(contains(texel));
        if (!contains(texel)) return refuse();
        return store_word(texel, Texel::encode(value), nullptr, &path);
    }

    // The value in `texel` whether or not it is visible yet; std::nullopt when empty. No counting.
    // `texel` must lie on the cube (asserted).
    std::optional<Value> load(const TexelAddress& texel) const noexcept {
        RAYCACHE_ASSERT(contains(texel));
        if (!contains(texel)) return std::nullopt;
        const Tile* tile = tile_of(texel);
        if (!tile) return std::nullopt;
        const Word word = tile->texels[slot_of(texel)].load(std::memory_order_acquire);
        if (!Texel::is_valid(word)) return std::nullopt;
        return Texel::decode(word);
    }

    // The packed word in `texel`, visible or written this frame; Texel::invalid when empty. No counting.
    // For saving a cube (raycache/cache_file.hpp). `texel` must lie on the cube (asserted).
    Word load_word(const TexelAddress& texel) const noexcept {
        RAYCACHE_ASSERT(contains(texel));
        if (!contains(texel)) return Texel::invalid;
        const Tile* tile = tile_of(texel);
        return tile ? tile->texels[slot_of(texel)].load(std::memory_order_acquire) : Texel::invalid;
    }

    // store_at() of an already packed word, bit for bit (for loading a saved cube); refused as store_at()
    // refuses, and for a word that is not valid. `texel` must lie on the cube (asserted).
    bool store_word_at(const TexelAddress& texel, Word word) noexcept {
        RAYCACHE_ASSERT(contains(texel));
        if (!contains(texel)) return refuse();
        return store_word(texel, word);
    }

    // The visible box {lo, hi} of the origins that `texel`'s tile was stored from (what lookup(direction,
    // origin, drift) compares with); std::nullopt when its tile has none. For saving a cube. Between frames.
    std::optional<std::pair<glm::vec3, glm::vec3>> origin_box(const TexelAddress& texel) const noexcept {
        RAYCACHE_ASSERT(contains(texel));
        const Tile* tile = contains(texel) ? tile_of(texel) : nullptr;
        if (!tile || !tile->has_box) return std::nullopt;
        return std::make_pair(glm::vec3(tile->box_min[0], tile->box_min[1], tile->box_min[2]),
                              glm::vec3(tile->box_max[0], tile->box_max[1], tile->box_max[2]));
    }

    // Makes [lo, hi] the visible origin box of `texel`'s tile, for loading a saved cube; false (nothing set)
    // when the tile holds no texel yet. Between frames.
    bool set_origin_box(const TexelAddress& texel, const glm::vec3& lo, const glm::vec3& hi,
                        float nearest = std::numeric_limits<float>::infinity()) noexcept {
        RAYCACHE_ASSERT(contains(texel));
        Tile* tile = contains(texel) ? tile_of(texel) : nullptr;
        if (!tile) return false;
        for (int k = 0; k < 3; ++k) tile->box_min[k] = lo[k], tile->box_max[k] = hi[k];
        tile->has_box = true;
        tile->nearest = nearest >= 0.0f ? nearest : std::numeric_limits<float>::infinity();
        return true;
    }

    // The nearest hit distance of the stores (given distances) into `texel`'s tile up to the last
    // begin_frame(); infinity when none. For saving a cube. Between frames.
    float nearest_hit(const TexelAddress& texel) const noexcept {
        RAYCACHE_ASSERT(contains(texel));
        const Tile* tile = contains(texel) ? tile_of(texel) : nullptr;
        return tile ? tile->nearest : std::numeric_limits<float>::infinity();
    }

    // Marks a texel holding a value as doubtful: from then on lookups and peeks miss on it (load() still
    // reads it) until clear() or invalidate(). False when the texel holds no value. Between frames only.
    bool set_doubtful(const TexelAddress& texel) noexcept {
        assert_between_frames();
        RAYCACHE_ASSERT(contains(texel));
        if (!contains(texel)) return false;
        Tile* tile = tile_of(texel);
        const int slot = slot_of(texel);
        if (!tile || !Texel::is_valid(tile->texels[slot].load(std::memory_order_relaxed))) return false;
        const std::uint64_t bit = std::uint64_t{1} << (slot % 64);
        if (!(tile->doubtful_bits[slot / 64].fetch_or(bit, std::memory_order_relaxed) & bit))
            state_->doubtful_texels.fetch_add(1, std::memory_order_relaxed);
        return true;
    }
    bool is_doubtful(const TexelAddress& texel) const noexcept {
        RAYCACHE_ASSERT(contains(texel));
        const Tile* tile = contains(texel) ? tile_of(texel) : nullptr;
        return tile && doubtful(*tile, slot_of(texel));
    }
    // Texels marked doubtful.
    std::size_t doubtful_texels() const noexcept { return state_->doubtful_texels.load(std::memory_order_relaxed); }

    // Empties one texel (and drops its doubtful mark). Between frames only.
    void invalidate(const TexelAddress& texel) noexcept {
        assert_between_frames();
        RAYCACHE_ASSERT(contains(texel));
        if (!contains(texel)) return;
        Tile* tile = tile_of(texel);
        if (!tile) return;
        const int slot = slot_of(texel);
        const bool held = Texel::is_valid(tile->texels[slot].exchange(Texel::invalid, std::memory_order_relaxed));
        std::uint64_t gone[bit_words] = {};
        gone[slot / 64] = std::uint64_t{1} << (slot % 64);
        forget_emptied(*tile, gone, held ? 1 : 0);
    }

    // Empties every texel, gives every tile back (to the budget too) and resets the counters. Between frames only.
    void clear() noexcept {
        assert_between_frames();
        free_tiles();
        state_->written_this_frame.store(false, std::memory_order_relaxed);
        state_->valid_texels.store(0, std::memory_order_relaxed);
        state_->doubtful_texels.store(0, std::memory_order_relaxed);
        state_->counters.reset();
    }

    // Ends a frame: this frame's stores become visible, tiles marked stale are dropped (their texels empty,
    // their memory given back), pending origin boxes become visible; returns the frame's counters and
    // resets them. Between frames only.
    CubeStatistics begin_frame() noexcept {
        assert_between_frames();
        const CubeStatistics finished = statistics();
        give_back_if_refused();
        allocate_wanted();
        end_frame_tiles(state_->written_this_frame.exchange(false, std::memory_order_relaxed));
        reset_counters();
        return finished;
    }
    // If the budget refused a tile to anyone since the last call (so which tiles this frame got depended on
    // thread timing), gives back every tile allocated since the last begin_frame() and allocates the tiles
    // wanted since (those and the refused ones) again, empty, in tile order while the budget allows. Runs in
    // begin_frame(); call it first where this frame's stores are read before begin_frame() (the confidence
    // test, the depth pyramid and invalidation do). Cubes sharing a budget: call give_back_refused_frame()
    // on all of them, then allocate_wanted_tiles() on all (as SceneCache does), so that what one cube gets
    // does not depend on the other cubes' tiles still held. Between frames only.
    void settle_budget() noexcept {
        assert_between_frames();
        give_back_if_refused();
        allocate_wanted();
    }
    // The first half of settle_budget(): the frame's new tiles given back, if the budget refused any tile.
    void give_back_refused_frame() noexcept {
        assert_between_frames();
        give_back_if_refused();
    }
    // The second half: the tiles wanted in a refused frame allocated, empty, in tile order while they fit
    // (not counted as refusals when they do not).
    void allocate_wanted_tiles() noexcept {
        assert_between_frames();
        allocate_wanted();
    }

    // Tiles dropped as stale since the cube was made.
    std::size_t dropped_tiles() const noexcept { return state_->dropped_tiles.load(std::memory_order_relaxed); }

    // The counters since the last reset (approximate while other threads are counting).
    CubeStatistics statistics() const noexcept {
        CubeStatistics s;
        s.hits = state_->counters.sum(hits);
        for (std::size_t k = 0; k < miss_reason_count; ++k) {
            s.misses_by[k] = state_->counters.sum(first_miss + k);
            s.misses += s.misses_by[k];
        }
        s.lookups = s.hits + s.misses;
        s.stores = state_->counters.sum(stores);
        s.refused_stores = state_->counters.sum(refused_stores);
        s.filled_work = state_->counters.sum(filled_work);
        s.work_reports = state_->counters.sum(work_reports);
        s.valid_texels = valid_texels();
        s.texel_count = texel_count();
        return s;
    }

    // Zeroes the counters. Between frames only (the count of texels holding a value is kept through it).
    void reset_statistics() noexcept {
        assert_between_frames();
        reset_counters();
    }

    // Calls f(address) for every texel stored during the current frame, in linear-index order
    // (for structures derived from the cube, updated before begin_frame()). Between frames only.
    template <class F>
    void for_each_written_texel(F&& f) const {
        for_each_written_texel_in_bands(0, tile_bands(), f);
    }

    // Bands of texels that passes between frames can spread over threads: band b is tile row b % T of
    // face b / T (T tiles to a face's edge), in linear-index order.
    int tile_bands() const noexcept { return RAYCACHE_FACE_COUNT * tiles_per_edge_; }

    // for_each_written_texel() for the texels of bands [first, last) alone, in the same order. Between
    // frames only; calls on disjoint bands may run on different threads at once.
    template <class F>
    void for_each_written_texel_in_bands(int first, int last, F&& f) const {
        RAYCACHE_ASSERT(0 <= first && first <= last && last <= tile_bands());
        if (!(0 <= first && first <= last && last <= tile_bands())) return;
        if (!state_->written_this_frame.load(std::memory_order_relaxed)) return;
        // A tile row's 16 written bits at once: bits (row % 4) * 16 .. + 15 of word row / 4.
        for_each_texel_where(
            [](const Tile& tile, int row) {
                return static_cast<std::uint32_t>(tile.written_bits[row / 4].load(std::memory_order_relaxed) >> (row % 4 * 16)) & 0xFFFFu;
            },
            [](const Tile&, int) { return true; }, f, first, last);
    }

    // Calls f(address) for every texel holding a value (visible or written this frame), in linear-index
    // order. Between frames only.
    template <class F>
    void for_each_valid_texel(F&& f) const {
        // A tile row's 16 held or written bits at once, as for_each_written_texel_in_bands().
        for_each_texel_where(
            [](const Tile& tile, int row) {
                const std::uint64_t bits = tile.held_bits[row / 4].load(std::memory_order_relaxed) | tile.written_bits[row / 4].load(std::memory_order_relaxed);
                return static_cast<std::uint32_t>(bits >> (row % 4 * 16)) & 0xFFFFu;
            },
            [](const Tile& tile, int slot) { return Texel::is_valid(tile.texels[slot].load(std::memory_order_relaxed)); }, f);
    }

    // Texels holding a value, visible or written this frame.
    std::size_t valid_texels() const noexcept {
        return static_cast<std::size_t>(state_->valid_texels.load(std::memory_order_relaxed) +
                                        static_cast<std::int64_t>(state_->counters.sum(new_values)));
    }
    double valid_fraction() const noexcept {
        return static_cast<double>(valid_texels()) / static_cast<double>(texel_count());
    }

    bool contains(const TexelAddress& t) const noexcept { return is_on_cube(t, face_size_); }

private:
    // A miss is counted under its reason: counter first_miss + MissReason.
    enum Counter : std::size_t { hits, stores, refused_stores, new_values, filled_work, work_reports, first_miss,
                                 counter_count = first_miss + miss_reason_count };

    // Zeroes the counters, the texels stores gave a value kept in valid_texels. Not concurrent with stores.
    void reset_counters() noexcept {
        state_->valid_texels.fetch_add(static_cast<std::int64_t>(state_->counters.sum(new_values)), std::memory_order_relaxed);
        state_->counters.reset();
    }

    static constexpr int tile_texels = tile_edge * tile_edge;
    static constexpr int bit_words = tile_texels / 64;

    // A float's bits mapped so that unsigned order is the float's order (for atomic min and max).
    static std::uint32_t ordered(float f) noexcept { return shared::raycache_ordered_key(f); }
    static float unordered(std::uint32_t key) noexcept { return shared::raycache_key_float(key); }

    // The union of the path records stored into one record block of a tile.
    struct PathUnion {
        PathUnion() noexcept { clear(); }
        // Empty: no object, empty boxes, no flag (a new tile's, or a block left with no value).
        void clear() noexcept {
            objects.store(0, std::memory_order_relaxed);
            flags.store(0, std::memory_order_relaxed);
            cached_reads.store(0, std::memory_order_relaxed);
            for (int k = 0; k < 3; ++k) {
                vertex_min[k].store(0xFFFFFFFFu, std::memory_order_relaxed);
                vertex_max[k].store(0u, std::memory_order_relaxed);
                escape_min[k].store(0xFFFFFFFFu, std::memory_order_relaxed);
                escape_max[k].store(0u, std::memory_order_relaxed);
            }
        }
        std::atomic<std::uint64_t> objects{0};                   // Bloom mask of the objects hit
        std::atomic<std::uint32_t> vertex_min[3], vertex_max[3]; // ordered floats; empty while min > max
        std::atomic<std::uint32_t> escape_min[3], escape_max[3]; // escaped bounces' directions, the same way
        std::atomic<std::uint32_t> flags{0};                     // path_lit | path_chained | path_unbounded
        std::atomic<std::uint64_t> cached_reads{0};              // direction cells of nested cached answers
        // Replaces the union by `k` (between frames: no store is merging into it).
        void store(const PathKeys& k) noexcept {
            objects.store(k.objects, std::memory_order_relaxed);
            for (int a = 0; a < 3; ++a) {
                vertex_min[a].store(k.vertex_min[a], std::memory_order_relaxed);
                vertex_max[a].store(k.vertex_max[a], std::memory_order_relaxed);
                escape_min[a].store(k.escape_min[a], std::memory_order_relaxed);
                escape_max[a].store(k.escape_max[a], std::memory_order_relaxed);
            }
            flags.store(k.flags, std::memory_order_relaxed);
            cached_reads.store(k.cached_reads, std::memory_order_relaxed);
        }
        // The union as it stands, in key form. Always inlined: as a call it had invalidation's tile pass spill
        // its registers around each of a move's ~14,000 reads (1.4% of the move's instructions).
        RAYCACHE_HOT_FN PathKeys keys() const noexcept {
            PathKeys k;
            k.objects = objects.load(std::memory_order_relaxed);
            // Spelt out: GCC keeps a loop over atomics rolled (its counter and branch were 1.4% of a move).
            load_axis(k, 0);
            load_axis(k, 1);
            load_axis(k, 2);
            k.flags = flags.load(std::memory_order_relaxed);
            k.cached_reads = cached_reads.load(std::memory_order_relaxed);
            return k;
        }

    private:
        RAYCACHE_HOT_FN void load_axis(PathKeys& k, int a) const noexcept {
            k.vertex_min[a] = vertex_min[a].load(std::memory_order_relaxed);
            k.vertex_max[a] = vertex_max[a].load(std::memory_order_relaxed);
            k.escape_min[a] = escape_min[a].load(std::memory_order_relaxed);
            k.escape_max[a] = escape_max[a].load(std::memory_order_relaxed);
        }
    };

    struct Tile {
        Tile() noexcept {
            for (auto& t : texels) t.store(Texel::invalid, std::memory_order_relaxed);
            for (auto& w : written_bits) w.store(0, std::memory_order_relaxed);
            for (auto& w : doubtful_bits) w.store(0, std::memory_order_relaxed);
            for (int k = 0; k < 3; ++k) {
                pending_min[k].store(0xFFFFFFFFu, std::memory_order_relaxed);
                pending_max[k].store(0u, std::memory_order_relaxed);
            }
            for (auto& w : recorded_bits) w.store(0, std::memory_order_relaxed);
            for (auto& w : unrecorded_bits) w.store(0, std::memory_order_relaxed);
            for (auto& w : held_bits) w.store(0, std::memory_order_relaxed);
            pending_nearest.store(ordered(std::numeric_limits<float>::infinity()), std::memory_order_relaxed);
        }
        // Lowers the pending nearest hit distance to `d` (d >= 0; infinity changes nothing).
        void near_pending(float d) noexcept {
            const std::uint32_t key = ordered(d);
            std::uint32_t now = pending_nearest.load(std::memory_order_relaxed);
            while (key < now && !pending_nearest.compare_exchange_weak(now, key, std::memory_order_relaxed)) {}
        }
        // Widens the pending origin box by `o` (atomic min and max on ordered float bits).
        void widen_pending(const glm::vec3& o) noexcept {
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t key = ordered(o[k] + 0.0f); // -0 as +0
                std::uint32_t lo = pending_min[k].load(std::memory_order_relaxed);
                while (key < lo && !pending_min[k].compare_exchange_weak(lo, key, std::memory_order_relaxed)) {}
                std::uint32_t hi = pending_max[k].load(std::memory_order_relaxed);
                while (key > hi && !pending_max[k].compare_exchange_weak(hi, key, std::memory_order_relaxed)) {}
            }
        }
        // Whether `o` lies within `drift` of the visible origin box (true when no box is known: stores made
        // without an origin give none).
        // (The rules: raycache/shared/origin_rule.h, which the GPU's tiles follow too.)
        bool origins_cover(const glm::vec3& o, float drift) const noexcept {
            return !has_box || shared::raycache_origin_covered(o, glm::vec3(box_min[0], box_min[1], box_min[2]),
                                                               glm::vec3(box_max[0], box_max[1], box_max[2]), drift);
        }
        // Whether the visible box grown by `o` stays within `drift` wide on every axis (true without a box).
        bool box_stays_within(const glm::vec3& o, float drift) const noexcept {
            return !has_box || shared::raycache_origin_box_stays_within(glm::vec3(box_min[0], box_min[1], box_min[2]),
                                                                        glm::vec3(box_max[0], box_max[1], box_max[2]), o, drift);
        }
        // The drift a tolerance allows a tile whose nearest hit lies at `nearest`: min(drift, parallax x
        // nearest); drift alone when either factor of the product is infinite.
        static float allowed_drift(const OriginTolerance& t, float nearest) noexcept {
            return shared::raycache_allowed_drift(t.drift, t.parallax, nearest);
        }
        // The members are grouped by cache line according to who writes them during a frame, so that a
        // store does not evict the line of doubtful bits and visible origin box that every lookup of the
        // tile reads (lookups of a texel holding a value still read the written bits, which stores set).
        std::atomic<Word> texels[tile_texels];
        // One bit per texel: written during the current frame (so not visible yet). Written by stores, read
        // by lookups of a texel holding a value.
        alignas(64) std::atomic<std::uint64_t> written_bits[bit_words];
        // On the same line, also written by stores: texels a store without a record reached this frame
        // (winning or not); begin_frame() takes their recorded bits away, whichever store's value they kept,
        // since the threads' order decided that.
        std::atomic<std::uint64_t> unrecorded_bits[bit_words];
        // Read by lookups, written between frames only:
        // one bit per texel: its value is kept but not answered (set_doubtful());
        alignas(64) std::atomic<std::uint64_t> doubtful_bits[bit_words];
        // the box of the origins earlier frames' stores left from (lookups read it without synchronisation of
        // its own) and the nearest hit distance of those stores.
        float box_min[3] = {0, 0, 0}, box_max[3] = {0, 0, 0};
        float nearest = std::numeric_limits<float>::infinity();
        bool has_box = false;
        // Written by this frame's stores (and stale by lookups), read between frames: the pending origin box
        // and nearest distance, which begin_frame() makes visible, and the texels holding a value (so passes
        // over tiles need not read them).
        alignas(64) std::atomic<std::uint32_t> pending_min[3]; // (alignas on a declaration aligns each declarator)
        std::atomic<std::uint32_t> pending_max[3];
        std::atomic<std::uint32_t> pending_nearest;
        std::atomic<std::uint32_t> stale{0}; // a lookup met an origin outside the box: drop at begin_frame()
        std::atomic<std::uint32_t> valid{0};
        // What the paths stored into this tile saw (store() with a PathRecord): per record block, their
        // union, kept until the tile is dropped; read between frames only (raycache/invalidation.hpp).
        std::atomic<std::uint64_t> recorded_bits[bit_words]; // texels whose store brought a record
        // Texels holding a value stored before this frame (with written_bits: every texel holding one), so
        // passes over a sparse tile visit its few values, not its 256 words. Written between frames only.
        std::atomic<std::uint64_t> held_bits[bit_words];
        // The path records, one per record block, then one per group of blocks and the tile's union of them
        // (first_group_slot, tile_union_slot: supersets, tightened by retighten_group_union() and
        // retighten_tile_union()), right after the tile in its allocation (new_tile()); null in a cube
        // without records.
        PathUnion* records = nullptr;
    };

    // One bit per tile of the cube: set from any thread, taken (read and cleared) between frames.
    class TileBitmap {
    public:
        explicit TileBitmap(std::size_t tiles) : size_((tiles + 63) / 64), words_(new std::atomic<std::uint64_t>[size_]) { clear(); }
        void set(std::size_t tile) noexcept {
            words_[tile / 64].fetch_or(std::uint64_t{1} << (tile % 64), std::memory_order_relaxed);
        }
        void clear() noexcept {
            for (std::size_t w = 0; w < size_; ++w) words_[w].store(0, std::memory_order_relaxed);
        }
        // Clears the bitmap, calling f(tile) for each bit that was set, in tile order.
        template <class F>
        void take_each(F&& f) noexcept {
            for (std::size_t w = 0; w < size_; ++w)
                for (std::uint64_t bits = words_[w].exchange(0, std::memory_order_relaxed); bits; bits &= bits - 1)
                    f(w * 64 + static_cast<std::size_t>(count_trailing_zeros(bits)));
        }
        std::size_t bytes() const noexcept { return size_ * sizeof(std::uint64_t); }
        static std::size_t bytes_for(std::size_t tiles) noexcept { return (tiles + 63) / 64 * sizeof(std::uint64_t); }

    private:
        std::size_t size_;
        std::unique_ptr<std::atomic<std::uint64_t>[]> words_;
    };

    struct State {
        explicit State(std::size_t count) : tiles(new std::atomic<Tile*>[count]), fresh(count), wanted(count) {
            for (std::size_t i = 0; i < count; ++i) tiles[i].store(nullptr, std::memory_order_relaxed);
        }
        std::unique_ptr<std::atomic<Tile*>[]> tiles; // face by face, tile row by tile row; null until stored into
        // One bit per tile each (settle_budget()): allocated by a store since the last begin_frame(); a store
        // wanted it and the budget refused.
        TileBitmap fresh, wanted;
        std::uint64_t refusals_seen = 0; // the budget's refusals() at the last settle_budget()
        std::atomic<bool> written_this_frame{false}; // set by the frame's first store; read by lookups
        // Above: what lookups read. Below, on lines of their own: what threads write during a frame.
        alignas(64) std::atomic<std::size_t> allocated_tiles{0};
        std::atomic<std::int64_t> valid_texels{0}; // up to the last begin_frame() and changes between frames
        std::atomic<std::size_t> doubtful_texels{0};
        std::atomic<int> users{0}; // threads inside in_frame() scopes (debug builds)
        std::atomic<std::size_t> dropped_tiles{0};
        // Per thread, each slot on lines of its own; new_values counts the texels stores gave a value since the
        // counters were last reset (added to valid_texels then), so that no store writes a cube-wide atomic.
        detail::StripedCounters<counter_count> counters;
    };

    static int checked_face_size(int face_size) {
        if (!is_valid_face_size(face_size))
            throw std::invalid_argument("RayCache: a caching cube's face size must be 1 to 4096 texels, got " +
                                        std::to_string(face_size) +
                                        " (the thesis studies 128, 256 and 512; memory is 6 * N * N texels)");
        return face_size;
    }

    // Kept from construction: loops over the tiles and allocated_tile()'s bound ask it often.
    std::size_t tile_count() const noexcept { return tile_count_; }
    static std::size_t tile_count(int face_size) noexcept { return shared::raycache_origin_tile_count(face_size); }
    std::size_t table_bytes() const noexcept { return tile_count() * sizeof(std::atomic<Tile*>); }

    std::size_t tile_index(const TexelAddress& t) const noexcept {
        const std::size_t per_edge = static_cast<std::size_t>(tiles_per_edge_);
        return (static_cast<std::size_t>(t.face) * per_edge + static_cast<std::size_t>(t.row / tile_edge)) * per_edge +
               static_cast<std::size_t>(t.column / tile_edge);
    }
    // (Addresses on the cube are never negative: unsigned remainders by the power of two are masks.)
    static int slot_of(const TexelAddress& t) noexcept {
        return static_cast<int>(static_cast<unsigned>(t.row) % tile_edge * tile_edge + static_cast<unsigned>(t.column) % tile_edge);
    }

    // Always inlined: a CDCT move's shell walk calls it for each texel it reads.
    RAYCACHE_HOT_FN Tile* tile_of(const TexelAddress& t) const noexcept {
        Tile* tile = state_->tiles[tile_index(t)].load(std::memory_order_acquire);
        return tile == claimed() ? nullptr : tile;
    }

    // A table entry's value while one thread reserves and allocates its tile (never dereferenced).
    static Tile* claimed() noexcept { return reinterpret_cast<Tile*>(std::uintptr_t{1}); }

    // The tile of `t`, allocated (within the budget) if it has none yet; null when it does not fit. One
    // thread claims an empty entry and alone asks the budget, so a tile is refused only when the budget
    // has no room for it (two threads racing for one tile cannot make the loser's request fail), and the
    // frame's refusals depend on the tiles its rays want, not on timing (settle_budget()). Stores to a
    // claimed tile wait the allocation out; lookups read a claimed tile as empty.
    Tile* tile_for_store(const TexelAddress& t) noexcept {
        std::atomic<Tile*>& entry = state_->tiles[tile_index(t)];
        for (;;) {
            Tile* tile = entry.load(std::memory_order_acquire);
            if (tile == claimed()) {
                std::this_thread::yield();
                continue;
            }
            if (tile) return tile;
            if (entry.compare_exchange_weak(tile, claimed(), std::memory_order_acq_rel, std::memory_order_acquire)) break;
        }
        const std::size_t i = tile_index(t);
        bool refused = false;
        Tile* fresh = new_tile(true, &refused);
        if (fresh) state_->fresh.set(i); // settle_budget()
        else if (refused) state_->wanted.set(i);
        entry.store(fresh, std::memory_order_release);
        return fresh;
    }

    // A new, empty tile, its bytes taken from the budget (a refusal counted when count_refusal) and counted
    // in allocated_tiles; null when the budget (*refused set) or the heap has no room for it. The caller
    // puts it in the table.
    Tile* new_tile(bool count_refusal, bool* refused = nullptr) noexcept {
        const std::size_t bytes = bytes_per_tile();
        if (budget_ && !budget_->try_reserve(bytes, count_refusal)) {
            if (refused) *refused = true;
            return nullptr;
        }
        // One allocation: the tile, then its records (sizeof(Tile) is a multiple of 64, so they are aligned).
        void* memory = ::operator new(bytes, std::align_val_t{alignof(Tile)}, std::nothrow);
        if (!memory) {
            if (budget_) budget_->release(bytes);
            return nullptr;
        }
        Tile* tile = new (memory) Tile();
        if (path_records_) {
            tile->records = reinterpret_cast<PathUnion*>(static_cast<unsigned char*>(memory) + sizeof(Tile));
            for (int b = 0; b <= tile_union_slot; ++b) new (&tile->records[b]) PathUnion();
        }
        state_->allocated_tiles.fetch_add(1, std::memory_order_relaxed);
        return tile;
    }
    // Frees a tile of new_tile() and gives its bytes back to the budget.
    void delete_tile(Tile* tile) noexcept {
        static_assert(std::is_trivially_destructible_v<PathUnion>, "records are freed with their tile's memory");
        tile->~Tile();
        ::operator delete(tile, std::align_val_t{alignof(Tile)});
        if (budget_) budget_->release(bytes_per_tile());
    }

    // Frees every tile and returns the fixed part's bytes to the budget (destruction, move-assignment).
    void give_back() noexcept {
        if (!state_) return;
        free_tiles();
        if (budget_) budget_->release(fixed_bytes(face_size_));
        state_.reset();
    }

    void free_tiles() noexcept {
        for (std::size_t i = 0, count = tile_count(); i < count; ++i) {
            Tile* tile = state_->tiles[i].exchange(nullptr, std::memory_order_relaxed);
            if (!tile) continue;
            delete_tile(tile);
        }
        state_->allocated_tiles.store(0, std::memory_order_relaxed);
        state_->fresh.clear();
        state_->wanted.clear();
    }

    using TileBits = std::atomic<std::uint64_t>[bit_words]; // one bit per texel of a tile, by slot

    static bool bit_set(const TileBits& bits, int slot) noexcept {
        return (bits[slot / 64].load(std::memory_order_relaxed) >> (slot % 64)) & 1u;
    }
    static int count_trailing_zeros(std::uint64_t bits) noexcept { // bits != 0
#if defined(__GNUC__) || defined(__clang__)
        return __builtin_ctzll(bits);
#else
        int n = 0;
        for (; !(bits & 1u); bits >>= 1) ++n;
        return n;
#endif
    }
    // Where the target has no popcount instruction (x86-64 without -mpopcnt, the distributions' default),
    // __builtin_popcountll is a call into libgcc: a tenth of an invalidation pass's instructions went there.
    // The SWAR count below is a dozen inlined operations.
    static int bit_count(std::uint64_t bits) noexcept {
#if defined(__POPCNT__) || defined(__ARM_NEON) || defined(__aarch64__)
        return __builtin_popcountll(bits);
#else
        bits -= (bits >> 1) & 0x5555555555555555ull;
        bits = (bits & 0x3333333333333333ull) + ((bits >> 2) & 0x3333333333333333ull);
        bits = (bits + (bits >> 4)) & 0x0F0F0F0F0F0F0F0Full;
        return static_cast<int>((bits * 0x0101010101010101ull) >> 56);
#endif
    }
    // How many of a tile's bits are set.
    static int count_bits(const TileBits& bits) noexcept {
        int n = 0;
        for (const auto& word : bits) n += bit_count(word.load(std::memory_order_relaxed));
        return n;
    }
    // The first texel (lowest column and row) of tile `index`.
    TexelAddress first_texel_of_tile(std::size_t index) const noexcept {
        const std::size_t per_edge = static_cast<std::size_t>(tiles_per_edge_);
        return TexelAddress{static_cast<int>(index / (per_edge * per_edge)), static_cast<int>(index % per_edge) * tile_edge,
                            static_cast<int>((index / per_edge) % per_edge) * tile_edge};
    }

    static bool written(const Tile& tile, int slot) noexcept { return bit_set(tile.written_bits, slot); }
    static bool doubtful(const Tile& tile, int slot) noexcept { return bit_set(tile.doubtful_bits, slot); }
    // Word w of the texels whose value is known with its path record: recorded, and not reached this frame
    // by a store without one (begin_frame() takes those recorded bits away; until then they count here).
    static std::uint64_t recorded_word(const Tile& tile, int w) noexcept {
        return tile.recorded_bits[w].load(std::memory_order_relaxed) & ~tile.unrecorded_bits[w].load(std::memory_order_relaxed);
    }
    static bool recorded(const Tile& tile, int slot) noexcept { return (recorded_word(tile, slot / 64) >> (slot % 64)) & 1u; }

    // f(address) for each texel of an allocated tile that candidates(tile, row within the tile) names (a
    // mask of the row's 16 columns) and keep(tile, slot) accepts, in linear-index order. Tile rows whose
    // mask is empty cost one call, and a face's row of unallocated tiles one pointer load each; so the walk
    // costs what the cube holds, not its 6 N^2 texels. Bands [first_band, last_band) alone (tile_bands());
    // all of them by default.
    template <class Candidates, class Keep, class F>
    void for_each_texel_where(Candidates&& candidates, Keep&& keep, F&& f, int first_band = 0, int last_band = -1) const {
        const Tile* row_tiles[(RAYCACHE_MAX_FACE_SIZE + tile_edge - 1) / tile_edge]; // one tile row's tiles
        if (last_band < 0) last_band = tile_bands();
        for (int band = first_band; band < last_band; ++band) {
            const int face = band / tiles_per_edge_, tile_row = band % tiles_per_edge_;
            bool any = false;
            for (int tile_column = 0; tile_column < tiles_per_edge_; ++tile_column) {
                row_tiles[tile_column] = tile_of(TexelAddress{face, tile_column * tile_edge, tile_row * tile_edge});
                any = any || row_tiles[tile_column];
            }
            if (!any) continue;
            const int row_end = std::min(face_size_, (tile_row + 1) * tile_edge);
            for (int row = tile_row * tile_edge; row < row_end; ++row)
                for (int tile_column = 0; tile_column < tiles_per_edge_; ++tile_column) {
                    const Tile* tile = row_tiles[tile_column];
                    if (!tile) continue;
                    const int r = row - tile_row * tile_edge;
                    const int columns = std::min(tile_edge, face_size_ - tile_column * tile_edge); // on the face
                    for (std::uint32_t mask = candidates(*tile, r) & ((1u << columns) - 1u); mask; mask &= mask - 1) {
                        const int c = count_trailing_zeros(mask);
                        if (keep(*tile, r * tile_edge + c)) f(TexelAddress{face, tile_column * tile_edge + c, row});
                    }
                }
        }
    }

    // settle_budget()'s halves (unchecked: the callers assert the frame rule).
    void give_back_if_refused() noexcept {
        if (!budget_ || budget_->refusals() == state_->refusals_seen) return;
        state_->refusals_seen = budget_->refusals();
        state_->fresh.take_each([&](std::size_t i) {
            state_->wanted.set(i);
            drop_tile(i);
        });
    }
    void allocate_wanted() noexcept {
        if (!budget_) return;
        state_->wanted.take_each([&](std::size_t i) {
            if (state_->tiles[i].load(std::memory_order_relaxed)) return;
            if (Tile* tile = new_tile(false)) state_->tiles[i].store(tile, std::memory_order_relaxed);
        });
    }

    // Frees tile `i` (allocated) with its texels and marks, and gives its bytes back. Between frames.
    void drop_tile(std::size_t i) noexcept {
        Tile* tile = state_->tiles[i].load(std::memory_order_relaxed);
        state_->valid_texels.fetch_sub(tile->valid.load(std::memory_order_relaxed), std::memory_order_relaxed);
        state_->doubtful_texels.fetch_sub(static_cast<std::size_t>(count_bits(tile->doubtful_bits)), std::memory_order_relaxed);
        state_->tiles[i].store(nullptr, std::memory_order_relaxed);
        delete_tile(tile);
        state_->allocated_tiles.fetch_sub(1, std::memory_order_relaxed);
    }

    // One pass over the tiles: clears the written bits (when anything was written), drops stale tiles and
    // makes pending origin boxes and nearest distances visible.
    void end_frame_tiles(bool any_written) noexcept {
        state_->fresh.clear(); // the frame's tiles are kept
        for (std::size_t i = 0, count = tile_count(); i < count; ++i) {
            Tile* tile = state_->tiles[i].load(std::memory_order_relaxed);
            if (!tile) continue;
            if (any_written) {
                for (int w = 0; w < bit_words; ++w) { // a written texel holds a value: its own or a rival's
                    const std::uint64_t written = tile->written_bits[w].load(std::memory_order_relaxed);
                    if (!written) continue;
                    tile->held_bits[w].store(tile->held_bits[w].load(std::memory_order_relaxed) | written, std::memory_order_relaxed);
                    tile->written_bits[w].store(0, std::memory_order_relaxed);
                }
                for (int w = 0; w < bit_words; ++w) { // a same-frame rival without a record: unrecorded
                    const std::uint64_t rivals = tile->unrecorded_bits[w].exchange(0, std::memory_order_relaxed);
                    if (rivals) tile->recorded_bits[w].fetch_and(~rivals, std::memory_order_relaxed);
                }
            }
            if (tile->stale.load(std::memory_order_relaxed)) {
                drop_tile(i);
                state_->dropped_tiles.fetch_add(1, std::memory_order_relaxed);
                continue;
            }
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t lo = tile->pending_min[k].load(std::memory_order_relaxed);
                const std::uint32_t hi = tile->pending_max[k].load(std::memory_order_relaxed);
                if (lo > hi) continue; // no origin stored this frame
                const float a = unordered(lo), b = unordered(hi);
                tile->box_min[k] = tile->has_box ? std::min(tile->box_min[k], a) : a;
                tile->box_max[k] = tile->has_box ? std::max(tile->box_max[k], b) : b;
            }
            if (tile->pending_min[0].load(std::memory_order_relaxed) <= tile->pending_max[0].load(std::memory_order_relaxed))
                tile->has_box = true;
            tile->nearest = std::min(tile->nearest, unordered(tile->pending_nearest.load(std::memory_order_relaxed)));
        }
    }

    RAYCACHE_HOT_FN std::optional<Value> visible_value(const TexelAddress& t) const noexcept { return visible_value(tile_of(t), t); }
    // The same, for `t`'s tile already loaded (null: none). On every lookup's path: inlined. With `why`, a
    // miss also says its cause there: empty, fresh or doubtful.
    RAYCACHE_HOT_FN std::optional<Value> visible_value(const Tile* tile, const TexelAddress& t,
                                                       MissReason* why = nullptr) const noexcept {
        const auto miss = [why](MissReason cause) -> std::optional<Value> {
            if (why) *why = cause;
            return std::nullopt;
        };
        if (!tile) return miss(MissReason::empty);
        // Acquire pairs with the store's release: a word written this frame comes with its written bit,
        // and the cube's written_this_frame flag, set. The flag spares frames without stores the bit load.
        const int slot = slot_of(t);
        const Word word = tile->texels[slot].load(std::memory_order_acquire);
        if (!Texel::is_valid(word)) return miss(MissReason::empty);
        if (state_->written_this_frame.load(std::memory_order_relaxed) && written(*tile, slot)) return miss(MissReason::fresh);
        if (doubtful(*tile, slot)) return miss(MissReason::doubtful);
        return Texel::decode(word);
    }

    bool refuse() noexcept {
        state_->counters.add(refused_stores);
        return false;
    }

    // Asks the processor to start loading the cache line holding `p` (nothing where the compiler has no
    // such hint).
    static void prefetch_line(const void* p) noexcept {
#if defined(__GNUC__) || defined(__clang__)
        __builtin_prefetch(p);
#else
        (void)p;
#endif
    }

    // After texels of `tile` were emptied (their words already invalid): drops their doubtful and recorded
    // bits (`gone`) and takes `values` (those of them that held one) off the counts. Between frames, by one
    // thread at a time for a tile (its bits and count are loaded and stored, not read-modified-written; the
    // cube's counts are, since passes empty a cube's tiles on several threads).
    void forget_emptied(Tile& tile, const std::uint64_t (&gone)[bit_words], std::size_t values) noexcept {
        std::size_t doubtful_gone = 0;
        for (int w = 0; w < bit_words; ++w) {
            if (!gone[w]) continue;
            const std::uint64_t doubtful = tile.doubtful_bits[w].load(std::memory_order_relaxed);
            doubtful_gone += static_cast<std::size_t>(bit_count(doubtful & gone[w]));
            tile.doubtful_bits[w].store(doubtful & ~gone[w], std::memory_order_relaxed);
            tile.recorded_bits[w].store(tile.recorded_bits[w].load(std::memory_order_relaxed) & ~gone[w], std::memory_order_relaxed);
            tile.held_bits[w].store(tile.held_bits[w].load(std::memory_order_relaxed) & ~gone[w], std::memory_order_relaxed);
        }
        if (values) {
            state_->valid_texels.fetch_sub(static_cast<std::int64_t>(values), std::memory_order_relaxed);
            tile.valid.store(tile.valid.load(std::memory_order_relaxed) - static_cast<std::uint32_t>(values), std::memory_order_relaxed);
        }
        if (doubtful_gone) state_->doubtful_texels.fetch_sub(doubtful_gone, std::memory_order_relaxed);
    }

    // Adds the path record of a store that reached texel t's same-frame rivalry to its block's union
    // (atomic or, min, max; loads first, so a block whose union already holds the record is not written).
    void record_path(Tile* tile, const TexelAddress& t, const PathRecord& path) noexcept {
        const int slot = slot_of(t);
        tile->recorded_bits[slot / 64].fetch_or(std::uint64_t{1} << (slot % 64), std::memory_order_relaxed);
        const int block = block_of(t);
        merge_path(tile->records[block], path);
        merge_path(tile->records[first_group_slot + group_of_block(block)], path);
        merge_path(tile->records[tile_union_slot], path);
    }
    // f(TexelAddress, slot within its tile) for every texel of record block `b`.
    template <class F>
    void for_each_texel_of_block(const BlockPlace& b, F&& f) const {
        for (int row = b.row0; row < b.row1; ++row)
            for (int column = b.column0; column < b.column1; ++column) {
                const TexelAddress t{b.face, column, row};
                f(t, slot_of(t));
            }
    }
    // The record block of a texel within its tile.
    static int block_of(const TexelAddress& t) noexcept {
        return static_cast<int>(static_cast<unsigned>(t.row) % tile_edge / record_edge * (tile_edge / record_edge) +
                                static_cast<unsigned>(t.column) % tile_edge / record_edge);
    }
    static void merge_path(PathUnion& r, const PathRecord& path) noexcept {
        if ((r.objects.load(std::memory_order_relaxed) & path.objects) != path.objects)
            r.objects.fetch_or(path.objects, std::memory_order_relaxed);
        // A path that escaped from nowhere makes the union unbounded (PathRecord::merge's rule).
        const std::uint32_t flags = path_flags_of(path) | (path.escapes_from_nowhere() ? path_unbounded : 0u);
        if ((r.flags.load(std::memory_order_relaxed) & flags) != flags) r.flags.fetch_or(flags, std::memory_order_relaxed);
        if ((r.cached_reads.load(std::memory_order_relaxed) & path.cached_reads) != path.cached_reads)
            r.cached_reads.fetch_or(path.cached_reads, std::memory_order_relaxed);
        if (path.has_vertices()) widen(r.vertex_min, r.vertex_max, path.vertex_lo, path.vertex_hi);
        if (path.has_escapes()) widen(r.escape_min, r.escape_max, path.escape_lo, path.escape_hi);
    }
    // Tile `i`, or null when it is not allocated (or past the cube's tiles).
    const Tile* allocated_tile(std::size_t i) const noexcept {
        return i < tile_count() ? state_->tiles[i].load(std::memory_order_acquire) : nullptr;
    }
    Tile* allocated_tile(std::size_t i) noexcept { return const_cast<Tile*>(std::as_const(*this).allocated_tile(i)); }
    // The union of a tile's paths (empty in a cube without records).
    static PathRecord paths_of(const Tile& tile) noexcept {
        return tile.records ? record_of(tile.records[tile_union_slot]) : PathRecord::empty();
    }
    // A union as one PathRecord (empty boxes as PathRecord keeps them).
    static PathRecord record_of(const PathUnion& u) noexcept { return u.keys().record(); }
    // Whether a texel of the tile holds a value stored without a record. Recorded bits are set only on
    // texels holding a value (and cleared when one is emptied), so a tile whose count of values equals its
    // recorded bits has none.
    static bool has_unrecorded(const Tile& tile) noexcept {
        int recorded_count = 0;
        for (int w = 0; w < bit_words; ++w) recorded_count += bit_count(recorded_word(tile, w));
        return static_cast<int>(tile.valid.load(std::memory_order_relaxed)) != recorded_count;
    }
    // The box of the origins the tile's texels were stored from, visible and pending; false when none.
    static bool origins_of(const Tile& tile, glm::vec3& lo_out, glm::vec3& hi_out) noexcept {
        const bool has = tile.has_box || tile.pending_min[0].load(std::memory_order_relaxed) <= tile.pending_max[0].load(std::memory_order_relaxed);
        if (!has) return false;
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t lo = tile.pending_min[k].load(std::memory_order_relaxed);
            const std::uint32_t hi = tile.pending_max[k].load(std::memory_order_relaxed);
            float a = tile.has_box ? tile.box_min[k] : std::numeric_limits<float>::infinity();
            float b = tile.has_box ? tile.box_max[k] : -std::numeric_limits<float>::infinity();
            if (lo <= hi) a = std::min(a, unordered(lo)), b = std::max(b, unordered(hi));
            lo_out[k] = a, hi_out[k] = b;
        }
        return true;
    }
    // Widens the box of ordered floats [min, max] to hold [lo, hi] (atomic min and max per axis).
    static void widen(std::atomic<std::uint32_t> (&min)[3], std::atomic<std::uint32_t> (&max)[3], const glm::vec3& lo,
                      const glm::vec3& hi) noexcept {
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t lo_key = ordered(lo[k] + 0.0f), hi_key = ordered(hi[k] + 0.0f);
            std::uint32_t old_lo = min[k].load(std::memory_order_relaxed);
            while (lo_key < old_lo && !min[k].compare_exchange_weak(old_lo, lo_key, std::memory_order_relaxed)) {}
            std::uint32_t old_hi = max[k].load(std::memory_order_relaxed);
            while (hi_key > old_hi && !max[k].compare_exchange_weak(old_hi, hi_key, std::memory_order_relaxed)) {}
        }
    }
    // The box [lo, hi] that widen() built in [min, max]; lo = 1, hi = -1 (empty) when nothing was added
    // (widen() sets all three axes at once, so one axis tells).
    static void read_box(const std::uint32_t (&min)[3], const std::uint32_t (&max)[3], glm::vec3& lo, glm::vec3& hi) noexcept {
        if (min[0] > max[0]) {
            lo = glm::vec3(1.0f), hi = glm::vec3(-1.0f);
            return;
        }
        // By member, not by glm's operator[] (a switch per component, on invalidation's hot path).
        lo = glm::vec3(unordered(min[0]), unordered(min[1]), unordered(min[2]));
        hi = glm::vec3(unordered(max[0]), unordered(max[1]), unordered(max[2]));
    }

    // Writes `word` into texel t under the frame rule; with `from`, first widens the tile's pending box and
    // nearest distance, or refuses a store that would stretch the box beyond what the tolerance allows.
    // Where a store's ray left from, how far it went, and how much drift its tile allows.
    struct StoreOrigin {
        glm::vec3 origin;
        float hit_distance;
        OriginTolerance tolerance;
    };

    // With `path`, the texel's block records it once the store reaches the same-frame rivalry, whether it
    // wins or not: the block then holds every rival's path whatever order the threads came in, so what a
    // later move drops does not depend on timing.
    bool store_word(const TexelAddress& t, Word word, const StoreOrigin* from = nullptr, const PathRecord* path = nullptr) noexcept {
        if (!Texel::is_valid(word)) return refuse();
        Tile* tile = tile_for_store(t);
        if (!tile) return refuse(); // over the budget
        const int slot = slot_of(t);
        std::atomic<Word>& texel = tile->texels[slot];
        Word old = texel.load(std::memory_order_acquire);
        if (Texel::is_valid(old) && !written(*tile, slot)) return refuse(); // visible: kept
        // Only a word that may be kept widens the box (a same-frame rival may win either way): the box must
        // bound the origins of the values the tile holds, or a doubtful texel retraced every frame from a
        // moving camera would stretch it until no lookup ever missed on drift.
        if (from) {
            const float drift = Tile::allowed_drift(from->tolerance, std::min(tile->nearest, from->hit_distance));
            if (!tile->box_stays_within(from->origin, drift)) return refuse();
            tile->widen_pending(from->origin);
            tile->near_pending(from->hit_distance);
        }
        // Mark the texel as this frame's before writing it, so no reader can see the new word as visible.
        tile->written_bits[slot / 64].fetch_or(std::uint64_t{1} << (slot % 64), std::memory_order_relaxed);
        if (!state_->written_this_frame.load(std::memory_order_relaxed))
            state_->written_this_frame.store(true, std::memory_order_relaxed);
        // A tile without path records never marks a texel recorded, so it needs no unrecorded bits either
        // (one atomic OR less a store in a static scene's cubes).
        if (tile->records) {
            if (path) record_path(tile, t, *path);
            else tile->unrecorded_bits[slot / 64].fetch_or(std::uint64_t{1} << (slot % 64), std::memory_order_relaxed);
        }
        for (;;) {
            if (Texel::is_valid(old) && !(word < old)) return refuse(); // same frame: the smaller word wins
            if (texel.compare_exchange_weak(old, word, std::memory_order_acq_rel, std::memory_order_acquire)) {
                if (!Texel::is_valid(old)) {
                    state_->counters.add(new_values);
                    tile->valid.fetch_add(1, std::memory_order_relaxed);
                }
                state_->counters.add(stores);
                return true;
            }
        }
    }

    int face_size_;
    int tiles_per_edge_;
    std::size_t tile_count_; // 6 x tiles_per_edge_^2
    bool path_records_;
    std::unique_ptr<State> state_;
    std::shared_ptr<MemoryBudget> budget_;
};

using CctCube = CacheCube<CctTexel>;
using CdctCube = CacheCube<CdctTexel>;

} // namespace raycache
