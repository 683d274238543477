// raycache/path_record.hpp: what a traced path saw, as the tracer reports it, so a cache can later drop
// exactly the texels a moved object can have changed (raycache/invalidation.hpp).
//
// A cached ray's value depends on its first segment (the ray itself: covered by the texel's cone) and on
// the rest of its path: the objects it hit, the shadow rays from its hit points to the light, and further
// bounces. The tracer fills one PathRecord per traced leaving ray (SceneCache::leaving_ray with a callback
// that takes a PathRecord&, or cct_cached_trace() with a trace taking a PathRecord&); each 2 x 2 block of a
// cube's 16 x 16 tiles keeps the union of the records of the stores into it (CacheCube::store with a path:
// 8 + 24 + 24 + 4 bytes a block, padded to 64, then 8 for the direction cells of its cached reads, and a
// bit per texel saying its store brought a record).
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <cmath>
#include <cstdint>
#include <limits>

#include <glm/glm.hpp>

#include "raycache/direction_cells.hpp"

namespace raycache {

// The two bits of a 64-bit Bloom mask that stand for object `key` (any 64-bit id; equal keys, equal bits).
// Two bits of 64: a tile whose paths hit 3 objects answers "maybe" for an unrelated one 0.8% of the time.
inline std::uint64_t object_bits(std::uint64_t key) noexcept {
    // splitmix64's finaliser: neighbouring ids land on unrelated bits.
    key += 0x9E3779B97F4A7C15ull;
    key = (key ^ (key >> 30)) * 0xBF58476D1CE4E5B9ull;
    key = (key ^ (key >> 27)) * 0x94D049BB133111EBull;
    key ^= key >> 31;
    return (std::uint64_t{1} << (key & 63u)) | (std::uint64_t{1} << ((key >> 6) & 63u));
}

// Whether the Bloom mask `objects` may hold object `key` (both its bits set; false only when it surely does not).
inline bool may_hold(std::uint64_t objects, std::uint64_t key) noexcept {
    const std::uint64_t bits = object_bits(key);
    return (objects & bits) == bits;
}

// What one traced path saw after leaving the cached object.
struct PathRecord {
    // Bloom mask (object_bits) of every object a ray of the path hit, the first hit included.
    std::uint64_t objects = 0;
    // Box of the path's hit points (empty while lo > hi).
    glm::vec3 vertex_lo{std::numeric_limits<float>::infinity()};
    glm::vec3 vertex_hi{-std::numeric_limits<float>::infinity()};
    // A shadow ray went from a hit point to the light (so the segments hit point -> light matter).
    bool lit = false;
    // A bounce after the first hit was traced from one hit point to another (segments inside the box).
    bool chained = false;
    // Box of the unit directions of the bounces after the first hit that escaped to infinity, each from one
    // of the path's hit points (empty while lo > hi): rays from the hit points' box within the cone of these
    // directions, so a move far from that cone cannot have blocked them.
    glm::vec3 escape_lo{std::numeric_limits<float>::infinity()};
    glm::vec3 escape_hi{-std::numeric_limits<float>::infinity()};
    // A bounce escaped with no bound known on its segment (not from a hit point, or no direction given):
    // any move may change the path.
    bool unbounded = false;
    // The direction cells (raycache/direction_cells.hpp) in which cubes answered rays nested in the path (a
    // bounce that left a cached object and was answered by its cube): when such a cube loses texels only in
    // other cells, the path still holds. A fresh record knows nothing of them: every cell, so a path that hit
    // a cached object counts as having read all of its cube. A tracer that passes the record of each path to
    // the leaving rays nested in it (SceneCache::leaving_ray's `enclosing`) calls track_cached_reads() first.
    std::uint64_t cached_reads = every_direction_cell;

    // A union of no paths: nothing hit, nothing read (what merge() starts from).
    static PathRecord empty() noexcept {
        PathRecord r;
        r.cached_reads = 0;
        return r;
    }

    // The path hit object `key` at `point`.
    void hit(std::uint64_t key, const glm::vec3& point) noexcept {
        objects |= object_bits(key);
        vertex_lo = glm::min(vertex_lo, point);
        vertex_hi = glm::max(vertex_hi, point);
    }
    // A bounce after the first hit, leaving one of the path's hit points (recorded with hit(); the tracer's
    // surface offset of up to 1e-3 x max(1, |coordinates|) is allowed for), escaped in `direction` (any
    // length; a zero or non-finite one records the path as unbounded).
    void escaped(const glm::vec3& direction) noexcept {
        const float l = glm::length(direction);
        if (!(l > 0.0f) || !std::isfinite(l)) {
            unbounded = true;
            return;
        }
        const glm::vec3 d = direction / l;
        escape_lo = glm::min(escape_lo, d);
        escape_hi = glm::max(escape_hi, d);
    }
    // From here on every cached answer nested in the path is noted with read_cached(): none so far.
    void track_cached_reads() noexcept { cached_reads = 0; }
    // A cube answered a ray nested in the path from its texels in the directions of the box [lo, hi] (any
    // lengths; for a CCT, the ray's direction; for a CDCT search, the points it read, seen from the centre).
    void read_cached(const glm::vec3& lo, const glm::vec3& hi) noexcept { cached_reads |= direction_cells_of_box(lo, hi); }
    bool has_vertices() const noexcept { return vertex_lo.x <= vertex_hi.x; }
    bool has_escapes() const noexcept { return escape_lo.x <= escape_hi.x; }
    // Escapes with no hit point before them: no bound on where they started. Merged with another path's hit
    // points they would seem to start there, so a union holding such a path is unbounded.
    bool escapes_from_nowhere() const noexcept { return has_escapes() && !has_vertices(); }
    // Adds what another record saw (a nested leaving ray's path is part of the outer one); unbounded when
    // either escaped from nowhere (escapes_from_nowhere).
    void merge(const PathRecord& other) noexcept {
        const bool loose = escapes_from_nowhere() || other.escapes_from_nowhere();
        objects |= other.objects;
        vertex_lo = glm::min(vertex_lo, other.vertex_lo);
        vertex_hi = glm::max(vertex_hi, other.vertex_hi);
        escape_lo = glm::min(escape_lo, other.escape_lo);
        escape_hi = glm::max(escape_hi, other.escape_hi);
        lit = lit || other.lit;
        chained = chained || other.chained;
        unbounded = unbounded || other.unbounded || loose;
        cached_reads |= other.cached_reads;
    }
};

} // namespace raycache
