// raycache/invalidation.hpp: between two frames, empties exactly the texels of a cube (CCT or CDCT) that
// moved objects or a moved light can have changed, and keeps every other one.
//
// A CCT texel answers rays leaving the cube's box (or, with the origin test, within `origin_drift` of its
// tile's origin box) in its directions. A CDCT texel holds a point P seen in its directions from the cube's
// centre and answers rays from the box that meet P; every point of such a ray's segment up to P is a point
// of the ball around the box plus a multiple of P's direction (a convex combination of the origin and P,
// both in that set), so it lies in the texel's cone from the box's ball too: the regions' tests serve
// both, and a CDCT texel is finally tested with the segments themselves.
// A texel's value is stale after object X moved from sphere A to sphere B when
//   - its rays' first segment can meet A or B: the region's cone, grown by the origins' ball, meets the sphere
//     (raycache/shared/cone_sphere.h; tested top-down: a face, a 16 x 16 tile, a 4 x 4 group of 2 x 2
//     record blocks, a block, then each texel); for a CDCT texel, whose searches end on its stored surface
//     (its distance, give or take the search's gap limit), the segments from the origins' ball to that
//     shell of its directions meet the sphere (the hull of two balls: raycache_ball_hull_meets_sphere;
//     first for a whole block, with the shell of all its texels' ends);
//   - or the rest of a path stored into its record block can have met X (the block's PathRecord union,
//     raycache/path_record.hpp, tested once the unions of its tile and of its 4 x 4 group of blocks met X): X among the
//     objects hit (Bloom mask), A or B on the segments from the box of hit points to a light (shadow rays), A or
//     B in that box (bounces between hit points), A or B met by rays from that box in the cone of the
//     directions in which bounces escaped, a bounce that escaped with no such bound (unbounded), or a cached
//     object whose own cube changed (transitively, by the caller);
//   - or its store brought no PathRecord (nothing is known about the rest of its path).
// A moved light empties every texel whose path hit something. A block the path tests catch is emptied whole.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"
#include "raycache/cdct.hpp"
#include "raycache/cdct_cache.hpp"
#include "raycache/direction_cells.hpp"
#include "raycache/path_record.hpp"
#include "raycache/shared/cone_sphere.h"

namespace raycache {

// A sphere that bounds an object (before or after a move).
struct BoundingSphere {
    glm::vec3 centre{0.0f};
    float radius = 0.0f;
};

// What changed in the scene since the last frame, for one pass over a cube.
struct SceneChanges {
    struct Move {
        std::uint64_t key = 0;  // the object's key in the PathRecords (PathRecord::hit)
        BoundingSphere before, after;
    };
    std::vector<Move> moved;
    // An object whose appearance changed without its shape moving: a cached mirror whose cube lost texels,
    // in the direction cells `cells` (raycache/direction_cells.hpp; every cell: it changed as a whole).
    struct Changed {
        Changed(std::uint64_t object, std::uint64_t in_cells = every_direction_cell) noexcept : key(object), cells(in_cells) {}
        std::uint64_t key; // the object's key in the PathRecords
        std::uint64_t cells;
    };
    // Texels whose paths hit such an object are emptied when their paths' cached answers read a cell of it
    // that changed (PathRecord::cached_reads: every cell unless the tracer noted them); no geometric test.
    std::vector<Changed> changed;
    // The point lights as they are now (as they were when the texels were stored, unless light_moved).
    std::vector<glm::vec3> lights;
    bool light_moved = false;
};

// Throws std::invalid_argument naming `what` unless the sphere's centre and radius are finite and the
// radius is not negative: every test below would take a NaN for "does not meet" and keep what it changed.
inline void check_bounding_sphere(const BoundingSphere& s, const char* what) {
    if (!shared::raycache_is_finite3(s.centre) || !std::isfinite(s.radius) || !(s.radius >= 0.0f))
        throw std::invalid_argument(std::string("RayCache: ") + what + " needs a finite centre and a finite radius >= 0");
}

// Throws std::invalid_argument unless every light position is finite.
inline void check_lights(const std::vector<glm::vec3>& lights) {
    for (const glm::vec3& light : lights)
        if (!shared::raycache_is_finite3(light))
            throw std::invalid_argument("RayCache: a light of the scene's changes is not finite");
}

// Throws std::invalid_argument unless every moved object's spheres (check_bounding_sphere) and every light
// are finite. invalidate_changes() calls it before touching any texel.
inline void check_scene_changes(const SceneChanges& changes) {
    for (const SceneChanges::Move& m : changes.moved) {
        check_bounding_sphere(m.before, "a moved object's sphere before the move");
        check_bounding_sphere(m.after, "a moved object's sphere after the move");
    }
    check_lights(changes.lights);
}

// Where a cube's rays leave from: its box and the CCT's origin test.
struct CubeRays {
    CubeBounds bounds;
    float origin_drift = -1.0f; // world units; < 0: no origin test (rays from anywhere in the box)
    // The cube answers only rays leaving from within this distance of bounds.centre (SceneCache tracks how
    // far its object's rays leave from); infinity: from anywhere in the box, whose ball bounds them.
    float origin_radius = std::numeric_limits<float>::infinity();
};

// What one pass did to one cube.
struct InvalidationCounts {
    std::size_t valid_before = 0; // texels holding a value before the pass
    std::size_t dropped = 0;      // texels emptied: the three below
    std::size_t dropped_by_path = 0;    // ... with blocks whose path records met a change
    std::size_t dropped_by_cone = 0;    // ... whose own rays' cone met a moved sphere
    std::size_t dropped_unrecorded = 0; // ... whose store brought no path record
    std::size_t blocks = 0;          // record blocks read (CacheCube::BlockState): those holding a value, in
                                     // tiles a change may reach
    std::size_t blocks_by_path = 0;  // blocks emptied whole by their path records
    std::size_t blocks_by_texel = 0; // blocks whose rays (their cone; a CDCT's, up to where its texels' rays
                                     // end) can meet a moved sphere, so each texel was tested
    std::uint64_t changed_cells = 0; // the direction cells of the texels emptied, each grown by a texel
                                     // (direction_cells_of_texels): where lookups may now read otherwise
};

namespace detail {

// The ball around the origins of a tile's rays: the cube's box (with a margin for the tracer's surface
// offsets), or the tile's origin box grown by the drift, whichever is smaller.
struct OriginBall {
    glm::vec3 centre;
    float radius;
};
// The size the margins for the tracer's surface offsets and rounding scale with: the cube's coordinates.
inline float origin_scale(const CubeBounds& bounds) {
    const glm::vec3 c = bounds.centre;
    return std::max(1.0f, std::max(std::abs(c.x), std::max(std::abs(c.y), std::abs(c.z))) + 2.0f * bounds.half_size);
}
// A ball of origins of `radius` grown by that margin.
inline float origin_ball_radius(const CubeBounds& bounds, float radius) { return radius * 1.001f + 1e-3f * origin_scale(bounds); }
inline OriginBall origin_ball(const CubeRays& rays, bool has_origins, const glm::vec3& lo, const glm::vec3& hi) {
    const glm::vec3 c = rays.bounds.centre;
    const float scale = origin_scale(rays.bounds);
    // The box's ball, or the smaller ball the rays are known to leave from (nan counts as unknown).
    const float radius = rays.origin_radius >= 0.0f ? std::min(1.7320509f * rays.bounds.half_size, rays.origin_radius)
                                                    : 1.7320509f * rays.bounds.half_size;
    OriginBall ball{c, origin_ball_radius(rays.bounds, radius)};
    if (has_origins && rays.origin_drift >= 0.0f) {
        const float r = 0.5f * glm::length(hi - lo) + 1.7320509f * rays.origin_drift + 1e-4f * scale;
        if (r < ball.radius) ball = OriginBall{0.5f * (lo + hi), r};
    }
    return ball;
}

} // namespace detail

// The widest ball of origins exact invalidation tests a cube's rays from: the ball around its box, with a
// margin for the tracer's surface offsets. Rays from further out are never checked; a cache that answers
// them must not rely on invalidation.
inline float box_origin_radius(const CubeBounds& bounds) {
    return detail::origin_ball_radius(bounds, 1.7320509f * bounds.half_size);
}

namespace detail {

// Whether meets(sphere) holds for the sphere of a moved object before or after its move.
template <class Meets>
bool any_moved_sphere(const std::vector<SceneChanges::Move>& moved, Meets&& meets) {
    for (const SceneChanges::Move& m : moved)
        if (meets(m.before) || meets(m.after)) return true;
    return false;
}

// Whether rays from `ball` in the directions of cone_of() can meet a moved sphere.
template <class ConeOf>
bool any_sphere_in_cone(const OriginBall& ball, ConeOf&& cone_of, const std::vector<SceneChanges::Move>& moved) {
    if (moved.empty()) return false;
    const shared::raycache_direction_cone cone = cone_of();
    return any_moved_sphere(moved, [&](const BoundingSphere& s) {
        return shared::raycache_rays_from_ball_meet_sphere(ball.centre, ball.radius, cone, s.centre, s.radius);
    });
}

// Where the rays a texel answers end, as distances from the cube's centre: a CDCT texel's searches end on
// its stored surface, within [near, far]; a CCT texel's rays, and a CDCT escape's, do not end (far infinite).
struct TexelReach {
    float near = 0.0f;
    float far = std::numeric_limits<float>::infinity();
};

// Whether a moved sphere can meet the rays of one texel from `ball`. Rays that do not end: its cone
// (any_sphere_in_cone). Rays that end in the shell [reach.near, reach.far] of the texel's directions:
// every such segment runs from a point of `ball` to a point of the shell's ball, so within the hull of the
// two balls, which ends at the stored surface where the cone from the ball would widen on.
template <class ConeOf>
bool texel_rays_meet(const OriginBall& ball, ConeOf&& cone_of, const std::vector<SceneChanges::Move>& moved,
                     const OriginBall& cube_ball, const TexelReach& reach) {
    if (!std::isfinite(reach.far)) return any_sphere_in_cone(ball, cone_of, moved);
    // A segment between two points of a ball around the centre stays in it: rays from the cube's ball ending
    // within reach.far stay within the larger radius, so a sphere beyond that cannot meet them (most spheres,
    // for most texels: the shell's ball, which costs a normalisation, is made only when one is nearer).
    const float bound = std::max(cube_ball.radius, reach.far);
    std::optional<shared::raycache_ball> end;
    return any_moved_sphere(moved, [&](const BoundingSphere& s) {
        if (glm::length(s.centre - cube_ball.centre) - s.radius > bound) return false;
        if (!end) end = shared::raycache_cone_shell_ball(cube_ball.centre, cone_of(), reach.near, reach.far);
        return shared::raycache_ball_hull_meets_sphere(ball.centre, ball.radius, end->centre, end->radius, s.centre, s.radius);
    });
}

// The tests of paths_meeting(), one bit each. Each one bounds every path of the union it is given, so a test
// that finds no path of a tile's union meeting a change finds none of a group of its blocks either: a group
// (and a block of a group) repeats only the tests its larger region's union met.
enum PathTest : unsigned {
    path_test_unbound = 1u << 0, // escapes with no bound on where they went (or started)
    path_test_light = 1u << 1,   // a moved light, and the paths hit something
    path_test_changed = 1u << 2, // a changed object among the objects hit, read where it changed
    path_test_moved = 1u << 3,   // a moved object among them
    path_test_between = 1u << 4, // bounces between hit points: a moved sphere in their box
    path_test_shadow = 1u << 5,  // shadow rays: a moved sphere on the segments from the hit points to a light
    path_test_escape = 1u << 6,  // escaped bounces: a moved sphere met by rays from the hit points in their cone
};
inline constexpr unsigned every_path_test = (1u << 7) - 1u;

// Whether paths that hit the objects of Bloom mask `objects` and read cached answers in the direction cells
// `cached_reads` read a cube of `changes.changed` where it changed (path_test_changed).
inline bool paths_read_changed(std::uint64_t objects, std::uint64_t cached_reads, const SceneChanges& changes) noexcept {
    if (cached_reads == 0) return false; // (paths that read no cube: most of a transitive pass's)
    for (const SceneChanges::Changed& c : changes.changed)
        if ((cached_reads & c.cells) != 0 && may_hold(objects, c.key)) return true;
    return false;
}

// Which of `tests` find that the rest of the paths whose union is `t` (a tile's, a group of blocks', a
// block's) can have met a change: 0 when none. With `first_only`, it stops at the first that does.
inline unsigned paths_meeting(const PathRecord& t, const SceneChanges& changes, unsigned tests = every_path_test, bool first_only = false) {
    unsigned met = 0;
    if (tests == 0) return met;
    // Records that `test` met; true when the caller has its answer.
    auto meets = [&](unsigned test) {
        met |= test;
        return first_only;
    };
    const bool has_vertices = t.has_vertices();
    const bool has_escapes = t.has_escapes();
    // Escapes from points not recorded, or a bounce that escaped with no bound known: no bound.
    if ((tests & path_test_unbound) && (t.escapes_from_nowhere() || t.unbounded) && meets(path_test_unbound)) return met;
    if ((tests & path_test_light) && changes.light_moved && has_vertices && meets(path_test_light)) return met;
    if ((tests & path_test_changed) && paths_read_changed(t.objects, t.cached_reads, changes) && meets(path_test_changed)) return met;
    if (changes.moved.empty()) return met;
    if (tests & path_test_moved)
        for (const SceneChanges::Move& m : changes.moved)
            if (may_hold(t.objects, m.key)) {
                if (meets(path_test_moved)) return met;
                break;
            }
    if (!has_vertices) return met;
    // The ball around the hit points, once per union; hit points so far out that it overflows bound nothing.
    const glm::vec3 centre = 0.5f * (t.vertex_lo + t.vertex_hi);
    const float radius = 0.5f * glm::length(t.vertex_hi - t.vertex_lo) * 1.0001f + 1e-5f;
    // The farthest a point of the box lies from the origin: its corner of largest magnitudes (the corners
    // lo and hi alone can be nearer than another).
    const float farthest = glm::length(glm::max(glm::abs(t.vertex_lo), glm::abs(t.vertex_hi)));
    if (!(shared::raycache_is_finite3(centre) && std::isfinite(radius) && std::isfinite(farthest))) {
        meets(tests & (path_test_between | path_test_shadow | path_test_escape));
        return met;
    }
    // Rays after the first hit leave the hit points offset by the tracer's surface epsilon (PathRecord::escaped):
    // from this ball around them.
    const float surface_offset = 1e-3f * std::max(1.0f, farthest);
    const float rays_from = radius + surface_offset;
    const glm::vec3 offset(surface_offset * 1.001f); // the same around the box of hit points, widened for rounding
    auto each_moved_sphere = [&](auto&& f) {
        for (const SceneChanges::Move& m : changes.moved)
            if (f(m.before) || f(m.after)) return true;
        return false;
    };
    // Bounces between hit points: segments from a point offset from one to another, within the grown box.
    if ((tests & path_test_between) && t.chained &&
        each_moved_sphere([&](const BoundingSphere& s) {
            return shared::raycache_box_meets_sphere(t.vertex_lo - offset, t.vertex_hi + offset, s.centre, s.radius);
        }) &&
        meets(path_test_between))
        return met;
    // Shadow rays end at the light: they lie in the hull of the light and the ball they leave from (not in the
    // whole cone from the light, which goes on past the hit points).
    if ((tests & path_test_shadow) && t.lit)
        for (const glm::vec3& light : changes.lights) {
            if (each_moved_sphere([&](const BoundingSphere& s) {
                    return shared::raycache_ball_hull_meets_sphere(light, 0.0f, centre, rays_from, s.centre, s.radius);
                })) {
                if (meets(path_test_shadow)) return met;
                break;
            }
        }
    if ((tests & path_test_escape) && has_escapes) {
        // Escaped bounces: rays from the hit points' ball facing the sphere, and in the escapes' cone, which
        // costs eight normalisations and is made only for a sphere that the escapes' directions face.
        std::optional<shared::raycache_direction_cone> escapes;
        if (each_moved_sphere([&](const BoundingSphere& s) {
                if (!shared::raycache_direction_box_may_reach_sphere(centre, rays_from, t.escape_lo, t.escape_hi, s.centre, s.radius))
                    return false;
                if (!escapes) escapes = shared::raycache_cone_of_direction_box(t.escape_lo, t.escape_hi);
                return shared::raycache_rays_from_ball_meet_sphere(centre, rays_from, *escapes, s.centre, s.radius);
            }))
            meets(path_test_escape);
    }
    return met;
}

// paths_meeting() of a union in the form a tile keeps it (CacheCube::PathKeys): the same answer. Changes that
// move nothing (a transitive pass's) reach only the unbound test, which asks whether the boxes are empty, and
// the changed cubes' test, which reads the objects and cells as they are: neither needs the boxes decoded.
template <class Keys>
unsigned paths_meeting_keys(const Keys& keys, const SceneChanges& changes, unsigned tests, bool first_only) {
    if (tests == 0) return 0u;
    if (tests == path_test_changed) return paths_read_changed(keys.objects, keys.cached_reads, changes) ? path_test_changed : 0u;
    if (!changes.moved.empty() || changes.light_moved) return paths_meeting(keys.record(), changes, tests, first_only);
    unsigned met = 0;
    if ((tests & path_test_unbound) && ((keys.has_escapes() && !keys.has_vertices()) || keys.unbounded())) {
        met |= path_test_unbound;
        if (first_only) return met;
    }
    if ((tests & path_test_changed) && paths_read_changed(keys.objects, keys.cached_reads, changes)) met |= path_test_changed;
    return met;
}

// Whether the rest of the paths whose union is `t` can have met a change (paths_meeting(), stopping at the
// first test that meets).
inline bool paths_meet(const PathRecord& t, const SceneChanges& changes) { return paths_meeting(t, changes, every_path_test, true) != 0; }

// Calls f(i) for each i in [0, count) on this thread: the parallel_for of the serial overloads (here and
// SceneCache's).
struct SerialFor {
    template <class F>
    void operator()(std::size_t count, F&& f) const {
        for (std::size_t i = 0; i < count; ++i) f(i);
    }
};

} // namespace detail

// One cube's exact invalidation, its tiles split into runs that any threads may take: for a scheduler that
// invalidates many cubes at once (SceneCache spreads every cube's runs over its threads in one go, so a
// large cube's tiles and the small cubes share the threads). Made by make_invalidation_pass() below, which
// checks the changes and settles the cube's budget (on the calling thread); then run(r) once for each r in
// [0, runs()), on any threads (runs share nothing they write but the cube's atomic counts); then finish(),
// once, after every run: the counts, added in run order, so the result does not depend on the threads.
// run(r) throws std::out_of_range for r >= runs().
// The cube, the changes and the pass's other arguments must outlive it. Between frames only.
class InvalidationPass {
public:
    virtual ~InvalidationPass() = default;
    virtual std::size_t runs() const noexcept = 0;
    virtual void run(std::size_t r) = 0;
    virtual InvalidationCounts finish() = 0;
};

// Runs a pass made by make_invalidation_pass() and finishes it: parallel_for(count, f) calls f(i) once for
// each i in [0, count), on any threads, and returns when all have.
template <class ParallelFor>
InvalidationCounts run_invalidation_pass(InvalidationPass& pass, ParallelFor&& parallel_for) {
    if (pass.runs() > 0) parallel_for(pass.runs(), [&pass](std::size_t r) { pass.run(r); });
    return pass.finish();
}

namespace detail {

// A cube's pass; reach(texel): where the rays a texel answers end (TexelReach: nowhere for the CCT);
// texel_rays_may_end: whether reach() can return an end at all (else blocks skip the walk over their
// texels' ends); finished(counts): after the runs (a CDCT cache's pyramid follows its texels).
template <class Texel, class Reach>
class CubeInvalidation final : public InvalidationPass {
public:
    CubeInvalidation(CacheCube<Texel>& cube, const CubeRays& rays, const SceneChanges& changes, Reach reach, bool texel_rays_may_end,
                     std::function<void(const InvalidationCounts&)> finished = {})
        : cube_(cube), rays_(rays), changes_(changes), reach_(std::move(reach)), texel_rays_may_end_(texel_rays_may_end),
          finished_(std::move(finished)), n_(cube.face_size()),
          geometric_(!changes.moved.empty() || changes.light_moved), // else only names of changed objects
          cube_ball_(origin_ball(rays, false, glm::vec3(0.0f), glm::vec3(0.0f))) {
        cube.assert_between_frames();
        check_scene_changes(changes);
        cube.settle_budget(); // the tiles this frame keeps, before their records are read
        counts_.valid_before = cube.valid_texels();
        const bool nothing = changes.moved.empty() && changes.changed.empty() && !changes.light_moved;
        if (nothing) return;
        // Top level: which faces' cones, from the whole cube's ball, can meet a moved sphere at all.
        for (int face = 0; face < RAYCACHE_FACE_COUNT; ++face)
            face_meets_[face] = any_sphere_in_cone(cube_ball_, [&] { return shared::raycache_region_cone(face, 0, 0, n_, n_, n_); }, changes.moved);
        tiles_ = cube.allocated_tile_indices();
        runs_.resize((tiles_.size() + tiles_per_run - 1) / tiles_per_run);
    }

    std::size_t runs() const noexcept override { return runs_.size(); }

    void run(std::size_t r) override {
        if (r >= runs_.size())
            throw std::out_of_range("RayCache: InvalidationPass::run(" + std::to_string(r) + "): the pass has " +
                                    std::to_string(runs_.size()) + " runs");
        Scratch scratch;
        const std::size_t end = std::min(tiles_.size(), (r + 1) * tiles_per_run);
        for (std::size_t i = r * tiles_per_run; i < end; ++i) {
            if (i + 2 < end) cube_.prefetch_tile_summary(tiles_[i + 2]);
            // A pass that moves nothing reads most tiles' unions alone (tile()).
            if (i + 1 < end) geometric_ ? cube_.prefetch_tile_records(tiles_[i + 1]) : cube_.prefetch_tile_union(tiles_[i + 1]);
            tile(tiles_[i], runs_[r], scratch);
        }
    }

    InvalidationCounts finish() override {
        InvalidationCounts counts = counts_;
        for (const InvalidationCounts& r : runs_) {
            counts.blocks += r.blocks;
            counts.dropped += r.dropped;
            counts.dropped_by_path += r.dropped_by_path;
            counts.dropped_by_cone += r.dropped_by_cone;
            counts.dropped_unrecorded += r.dropped_unrecorded;
            counts.blocks_by_path += r.blocks_by_path;
            counts.blocks_by_texel += r.blocks_by_texel;
            counts.changed_cells |= r.changed_cells;
        }
        if (finished_) finished_(counts);
        return counts;
    }

private:
    using Block = typename CacheCube<Texel>::BlockPlace;
    using PathKeys = typename CacheCube<Texel>::PathKeys;
    // Runs of this many allocated tiles, each reading its own tiles' records.
    static constexpr std::size_t tiles_per_run = 16;
    // Tile by tile (blocks come one tile after another), then by the tile's groups of 2 x 2 record blocks
    // (squares of 4 x 4 texels), then by block, then by texel: the union of a group's paths, which its tile
    // keeps (CacheCube::group_keys), and the group's cone are tested first, and most groups miss both, so
    // their blocks need no test of their own and their unions are not read. A group's union holds every
    // path of its blocks, so clearing a group clears its blocks soundly; a block whose escapes have no hit
    // points to start from makes its group's union unbounded (merge_path). A group repeats only the path
    // tests its tile's union met, and a block only those its group's met (PathTest).
    static constexpr int edge = CacheCube<Texel>::tile_edge;
    static constexpr int groups_per_side = CacheCube<Texel>::record_groups_per_side;
    static constexpr std::size_t group_count = CacheCube<Texel>::record_groups;
    static std::size_t group_of(int block) { return static_cast<std::size_t>(CacheCube<Texel>::group_of_block(block)); }
    struct Reached { // a recorded texel's reach, from its block's shell walk
        TexelAddress address;
        TexelReach reach;
    };
    // What a tile's pass reads its blocks into: made once for a run of tiles, not for each tile (64 path
    // records to initialise).
    struct Scratch {
        std::array<Block, CacheCube<Texel>::record_blocks> blocks;      // those holding a value
        std::array<PathKeys, CacheCube<Texel>::record_blocks> paths;    // blocks[i]'s union, as the tile keeps it
        std::array<Reached, CacheCube<Texel>::record_edge * CacheCube<Texel>::record_edge> reaches;
    };

    // Adds the cells of block `t` to what the pass changed when it emptied `dropped` of its texels (the whole
    // block's cells: a block is 2 x 2 texels, and the cells are far coarser).
    void note_changed_cells(InvalidationCounts& c, const Block& t, std::size_t dropped) const noexcept {
        if (dropped == 0 || c.changed_cells == every_direction_cell) return;
        c.changed_cells |= direction_cells_of_texels(t.face, t.column0, t.row0, t.column1, t.row1, n_);
    }

    // Tile `index`, its blocks read here (on the run's thread) into `scratch`, counted into `c`.
    void tile(std::size_t index, InvalidationCounts& c, Scratch& scratch) {
        CacheCube<Texel>& cube = cube_;
        const SceneChanges& changes = changes_;
        const int n = n_;
        // Without moves, only the paths' tests can drop a texel (unrecorded ones stay): a tile whose union
        // meets no change is left before the rest of its summary is read (most tiles of a transitive pass).
        std::optional<unsigned> paths_met;
        if (!geometric_) {
            const std::optional<PathKeys> paths = cube.tile_keys(index);
            if (!paths) return;
            paths_met = paths_meeting_keys(*paths, changes, every_path_test, false);
            if (*paths_met == 0) return;
        }
        const std::optional<typename CacheCube<Texel>::TileSummary> summary = cube.tile_summary(index);
        if (!summary) return;
        // The tile's origin ball and cone, once for its blocks: a block's directions lie within its tile's.
        const OriginBall ball = origin_ball(rays_, summary->has_origins, summary->origin_lo, summary->origin_hi);
        const int face = summary->face, c0 = summary->column0, r0 = summary->row0;
        const bool tile_cone_meets =
            geometric_ && face_meets_[face] &&
            any_sphere_in_cone(ball, [&] { return shared::raycache_region_cone(face, c0, r0, std::min(n, c0 + edge), std::min(n, r0 + edge), n); },
                               changes.moved);
        // A tile whose cone misses, whose every value came with a record, and whose union of paths (a
        // superset of its blocks') misses too keeps everything: its blocks are not read (most tiles).
        const unsigned tile_paths_meet = paths_met ? *paths_met : paths_meeting(summary->paths, changes);
        if (!tile_cone_meets && !summary->any_unrecorded && tile_paths_meet == 0) return;
        // The blocks holding a value (the others have nothing to empty, and their paths answer for no texel),
        // of the groups that hold one: with every value recorded, the groups are found from the recorded
        // bits and only the blocks of the groups that meet a test are read; else every block is (values
        // stored without a record go at any move, wherever they lie). Their unions are read (in key form)
        // only for the blocks of groups whose paths meet a change, and for the blocks that keep texels of
        // a group that lost some.
        auto& blocks = scratch.blocks;
        auto& paths = scratch.paths;
        std::size_t count = 0;
        std::uint32_t group_any = 0;
        if (summary->any_unrecorded) {
            cube.for_each_block_of_tile(index, [&](const Block& b) { blocks[count++] = b; });
            for (std::size_t i = 0; i < count; ++i) group_any |= 1u << group_of(blocks[i].block);
        } else {
            group_any = cube.groups_with_records(index);
        }
        const std::size_t dropped_before = c.dropped;
        std::array<unsigned, group_count> group_paths_meet{}; // the tests that met (paths_meeting)
        std::array<bool, group_count> group_cone_meets{};
        std::uint32_t groups_met = 0;
        for (std::size_t k = 0; k < group_count; ++k) {
            if (!((group_any >> k) & 1u)) continue;
            group_paths_meet[k] = paths_meeting_keys(cube.group_keys(index, static_cast<int>(k)), changes, tile_paths_meet, false);
            // The group's square of texels, clipped to the face as its blocks are.
            constexpr int texels = CacheCube<Texel>::record_group_edge * CacheCube<Texel>::record_edge;
            const int gc0 = c0 + static_cast<int>(k % groups_per_side) * texels, gr0 = r0 + static_cast<int>(k / groups_per_side) * texels;
            group_cone_meets[k] = tile_cone_meets && any_sphere_in_cone(ball, [&] {
                return shared::raycache_region_cone(face, gc0, gr0, std::min(n, gc0 + texels), std::min(n, gr0 + texels), n);
            }, changes.moved);
            if (group_paths_meet[k] || group_cone_meets[k]) groups_met |= 1u << k;
        }
        if (!summary->any_unrecorded) cube.for_each_block_of_tile(index, [&](const Block& b) { blocks[count++] = b; }, groups_met);
        c.blocks += count;
        // The blocks left holding a recorded texel: their union becomes their group's once it lost texels.
        // paths[i] holds blocks[i]'s union when its group's paths met a test (read there, and only there).
        std::array<bool, CacheCube<Texel>::record_blocks> keeps_recorded{};
        std::array<bool, group_count> group_lost{};
        for (std::size_t i = 0; i < count; ++i) {
            const Block& t = blocks[i];
            const std::size_t k = group_of(t.block);
            if (group_paths_meet[k]) paths[i] = cube.block_keys(t);
            if (group_paths_meet[k] && paths_meeting_keys(paths[i], changes, group_paths_meet[k], true)) {
                ++c.blocks_by_path;
                const std::size_t d = cube.invalidate_in_block(t, [](const TexelAddress&, bool) { return true; });
                c.dropped += d;
                c.dropped_by_path += d;
                group_lost[k] = group_lost[k] || d > 0;
                note_changed_cells(c, t, d);
                continue;
            }
            const bool any_recorded = t.valid_texels > t.unrecorded_texels;
            if (!geometric_) { // unrecorded texels went in the first pass
                keeps_recorded[i] = any_recorded;
                continue;
            }
            bool cone_meets = false;
            // The reaches of the block's recorded texels, when the block's shell was tested.
            auto& reaches = scratch.reaches;
            std::size_t reached = 0;
            if (group_cone_meets[k]) {
                const shared::raycache_direction_cone cone = shared::raycache_region_cone(t.face, t.column0, t.row0, t.column1, t.row1, n);
                cone_meets = any_sphere_in_cone(ball, [&] { return cone; }, changes.moved);
                // Rays that end (a CDCT's): the segments to the shell of the ends of all the block's
                // recorded texels, which holds each texel's, tested first; most blocks miss it, and their
                // texels then need no test of their own.
                if (cone_meets && texel_rays_may_end_ && any_recorded) {
                    TexelReach shell{std::numeric_limits<float>::infinity(), 0.0f};
                    cube.for_each_value_of_block(t, [&](const TexelAddress& a, bool recorded) {
                        if (!recorded) return;
                        const TexelReach r = reach_(a);
                        reaches[reached++] = {a, r};
                        shell.near = std::min(shell.near, r.near);
                        shell.far = std::max(shell.far, r.far);
                    });
                    cone_meets = texel_rays_meet(ball, [&] { return cone; }, changes.moved, cube_ball_, shell);
                }
            }
            // A recorded texel's reach, from the walk above when it made one (in the same texel order).
            std::size_t next_reach = 0;
            auto reach_of = [&](const TexelAddress& a) {
                if (next_reach < reached && reaches[next_reach].address == a) return reaches[next_reach++].reach;
                return reach_(a);
            };
            if (cone_meets) ++c.blocks_by_texel;
            else if (t.unrecorded_texels == 0) { // nothing here can have changed
                keeps_recorded[i] = true;
                continue;
            }
            const std::size_t d = cube.invalidate_in_block(t, [&](const TexelAddress& a, bool recorded) {
                if (!recorded) return ++c.dropped_unrecorded, true; // nothing known about the rest of its path
                const bool meets = cone_meets && texel_rays_meet(ball, [&] { return shared::raycache_texel_cone(a.face, a.column, a.row, n); },
                                                                 changes.moved, cube_ball_, reach_of(a));
                c.dropped_by_cone += meets;
                keeps_recorded[i] = keeps_recorded[i] || !meets;
                return meets;
            });
            c.dropped += d;
            group_lost[k] = group_lost[k] || d > 0;
            note_changed_cells(c, t, d);
        }
        // Emptied blocks' paths leave their group's union, and the tile's (a group holding no value keeps
        // none; one that lost nothing keeps its own, a superset of its blocks').
        if (c.dropped != dropped_before) {
            std::array<PathKeys, group_count> kept;
            kept.fill(PathKeys::empty());
            for (std::size_t i = 0; i < count; ++i) {
                const std::size_t k = group_of(blocks[i].block);
                if (group_lost[k] && keeps_recorded[i]) kept[k].merge(group_paths_meet[k] ? paths[i] : cube.block_keys(blocks[i]));
            }
            PathKeys tile_kept = PathKeys::empty();
            for (std::size_t k = 0; k < group_count; ++k) {
                if (group_lost[k] || !((group_any >> k) & 1u)) cube.retighten_group_union(index, static_cast<int>(k), kept[k]);
                else kept[k] = cube.group_keys(index, static_cast<int>(k));
                tile_kept.merge(kept[k]);
            }
            cube.retighten_tile_union(index, tile_kept);
        }
    }

    CacheCube<Texel>& cube_;
    const CubeRays rays_;
    const SceneChanges& changes_;
    const Reach reach_;
    const bool texel_rays_may_end_;
    const std::function<void(const InvalidationCounts&)> finished_;
    const int n_;
    const bool geometric_;
    const OriginBall cube_ball_;
    InvalidationCounts counts_;        // valid_before
    bool face_meets_[RAYCACHE_FACE_COUNT] = {};
    std::vector<std::size_t> tiles_;   // the allocated tiles, in index order
    std::vector<InvalidationCounts> runs_; // each run's counts
};

// Where a CCT texel's rays end: nowhere (its cone).
struct NoReach {
    TexelReach operator()(const TexelAddress&) const noexcept { return {}; }
};

// Where a CDCT texel's rays end: its searches end on its stored surface, within `gap` of its distance
// (make_invalidation_pass for a CdctCube).
struct CdctReach {
    const CdctCube* cube;
    float gap, max_depth;
    TexelReach operator()(const TexelAddress& a) const {
        const CdctTexel::Word word = cube->load_word(a); // the distance alone: the colour is not needed
        TexelReach reach;
        if (!CdctTexel::is_valid(word)) return reach;
        const float distance = shared::raycache_cdct_distance(CdctTexel::to_pair(word));
        if (!(distance < max_depth) || !std::isfinite(gap)) return reach; // an escape, clamped, or no limit
        reach.near = std::max(0.0f, (distance - gap) * 0.9999f - 1e-4f);
        reach.far = (distance + gap) * 1.0001f + 1e-4f;
        return reach;
    }
};

// A CDCT cube's pass (make_invalidation_pass() below), `finished` after its runs.
inline std::unique_ptr<InvalidationPass> cdct_invalidation_pass(CdctCube& cube, const CubeRays& rays, const ReliefParameters& p,
                                                                const SceneChanges& changes,
                                                                std::function<void(const InvalidationCounts&)> finished = {}) {
    const float gap = std::max(p.max_gap, p.epsilon);
    return std::make_unique<CubeInvalidation<CdctTexel, CdctReach>>(cube, CubeRays{rays.bounds, -1.0f, rays.origin_radius}, changes,
                                                                    CdctReach{&cube, gap, p.max_depth}, std::isfinite(gap),
                                                                    std::move(finished));
}

} // namespace detail

// The pass of invalidate_changes() over a CCT cube (`rays` with its origin test), or over a CDCT cube as a
// CCT's (rays that never end: their cones).
template <class Texel>
std::unique_ptr<InvalidationPass> make_invalidation_pass(CacheCube<Texel>& cube, const CubeRays& rays, const SceneChanges& changes) {
    return std::make_unique<detail::CubeInvalidation<Texel, detail::NoReach>>(cube, rays, changes, detail::NoReach{}, false);
}

// The pass of invalidate_changes() over a CDCT cube whose rays leave from within rays.origin_radius of its
// centre (rays.origin_drift is not used: the CDCT has no origin test), searched with `p`: a texel holding
// distance s answers only rays that meet its stored surface, within epsilon of it or at most max_gap behind
// it (the searches' tests; or at the box's exit, inside the box's ball), so its rays end between s - g and
// s + g from the centre, g = max(p.max_gap, p.epsilon): only a moved sphere that meets the segments from the
// box's ball to that shell can have changed it (an escape's rays, or any with no gap limit, do not end:
// the texel's cone).
inline std::unique_ptr<InvalidationPass> make_invalidation_pass(CdctCube& cube, const CubeRays& rays, const ReliefParameters& p,
                                                                const SceneChanges& changes) {
    return detail::cdct_invalidation_pass(cube, rays, p, changes);
}

// The pass over a CDCT cache's cube whose rays leave from within origin_radius of its centre (infinity: from
// anywhere in its box); finish() then rebuilds its depth pyramid when texels were dropped.
inline std::unique_ptr<InvalidationPass> make_invalidation_pass(CdctCache& cache, float origin_radius, const SceneChanges& changes) {
    return detail::cdct_invalidation_pass(cache.cube(), CubeRays{cache.bounds(), -1.0f, origin_radius}, cache.parameters(), changes,
                                          [&cache](const InvalidationCounts& counts) {
                                              if (counts.dropped > 0) cache.rebuild_pyramid();
                                          });
}

// One pass of exact invalidation over a cube: a CCT cube (`rays` with its origin test), or a CDCT cube
// (rays from anywhere in its box: origin_drift < 0; a CdctCache: the overloads below). Between frames only.
// Throws std::invalid_argument for changes check_scene_changes() refuses, before touching any texel.
// Deterministic: the result depends on the cube's contents and `changes` alone. parallel_for(count, f):
// f(i) once for each i in [0, count), on any threads, returning when all have (as tbb::parallel_for);
// runs of the cube's tiles go to f. Without it, on this thread.
template <class Texel, class ParallelFor = detail::SerialFor>
InvalidationCounts invalidate_changes(CacheCube<Texel>& cube, const CubeRays& rays, const SceneChanges& changes,
                                      ParallelFor&& parallel_for = {}) {
    return run_invalidation_pass(*make_invalidation_pass(cube, rays, changes), parallel_for);
}

// invalidate_changes() over a CDCT cube in `bounds`, searched with `p` (make_invalidation_pass()).
template <class ParallelFor = detail::SerialFor>
InvalidationCounts invalidate_changes(CdctCube& cube, const CubeBounds& bounds, const ReliefParameters& p, const SceneChanges& changes,
                                      ParallelFor&& parallel_for = {}) {
    return invalidate_changes(cube, CubeRays{bounds}, p, changes, parallel_for);
}

// The same for a CDCT cube that answers only rays leaving from within rays.origin_radius of its centre
// (rays.origin_drift is not used: the CDCT has no origin test).
template <class ParallelFor = detail::SerialFor>
InvalidationCounts invalidate_changes(CdctCube& cube, const CubeRays& rays, const ReliefParameters& p, const SceneChanges& changes,
                                      ParallelFor&& parallel_for = {}) {
    return run_invalidation_pass(*make_invalidation_pass(cube, rays, p, changes), parallel_for);
}

// invalidate_changes() over a CDCT cache's cube (its rays leave from anywhere in its box), then its depth
// pyramid follows when texels were dropped. Between frames only.
template <class ParallelFor = detail::SerialFor>
InvalidationCounts invalidate_changes(CdctCache& cache, const SceneChanges& changes, ParallelFor&& parallel_for = {}) {
    return invalidate_changes(cache, std::numeric_limits<float>::infinity(), changes, parallel_for);
}

// The same for a cache that answers only rays leaving from within origin_radius of its centre.
template <class ParallelFor = detail::SerialFor>
InvalidationCounts invalidate_changes(CdctCache& cache, float origin_radius, const SceneChanges& changes,
                                      ParallelFor&& parallel_for = {}) {
    return run_invalidation_pass(*make_invalidation_pass(cache, origin_radius, changes), parallel_for);
}

// After a cube was resampled into another (raycache/adaptive_resolution.hpp, resample_into: each texel of
// `to` took a texel of `from` within its own rectangle of the face), gives every valid texel of `to` the
// union of the path records of the blocks of `from` whose rectangles overlap its block's, so the resampled
// texels stay known to exact invalidation. Nothing when either cube keeps no path records. Between frames.
template <class Texel>
void carry_path_records(const CacheCube<Texel>& from, CacheCube<Texel>& to) {
    // Nothing known to carry (the texels came without records), or nowhere to keep it: they stay unrecorded.
    if (!from.keeps_path_records() || !to.keeps_path_records()) return;
    using Block = typename CacheCube<Texel>::BlockState;
    constexpr int edge = CacheCube<Texel>::record_edge;
    // One pass over the old blocks, each merged into the few new blocks its rectangle overlaps (a coarser
    // cube's block spans several old ones), then one over the new blocks: nothing of `from` is copied (an
    // adaptive cube after a cold frame holds ~1500 sparse tiles); the unions take ~72 bytes a new block.
    struct Union {
        PathRecord record = PathRecord::empty();
        bool any = false, unknown = false; // unknown: an overlapping old block held unrecorded texels
    };
    const int to_per_edge = (to.face_size() + edge - 1) / edge;
    std::vector<Union> unions(static_cast<std::size_t>(RAYCACHE_FACE_COUNT * to_per_edge * to_per_edge));
    const float fn = static_cast<float>(from.face_size()), tn = static_cast<float>(to.face_size());
    // New block columns (or rows) whose texels can overlap old texels [lo, hi): the overlap test below
    // decides; one block of margin either side for rounding.
    auto range = [&](int lo, int hi) {
        const float scale = tn / (fn * static_cast<float>(edge));
        return std::make_pair(std::max(0, static_cast<int>(static_cast<float>(lo) * scale) - 1),
                              std::min(to_per_edge - 1, static_cast<int>(static_cast<float>(hi) * scale) + 1));
    };
    const int tn_int = to.face_size();
    from.for_each_block_state([&](const Block& o) {
        // A block holding no value gives no texel to `to` (resample_into() copies values), so no new block
        // needs its paths: after a cold frame most blocks of the sparse tiles are such.
        if (o.valid_texels == 0) return;
        const auto [c_lo, c_hi] = range(o.column0, o.column1);
        const auto [r_lo, r_hi] = range(o.row0, o.row1);
        for (int br = r_lo; br <= r_hi; ++br)
            for (int bc = c_lo; bc <= c_hi; ++bc) {
                const int column0 = bc * edge, row0 = br * edge; // the new block's texels, as for_each_block_state's
                const int column1 = std::min(tn_int, column0 + edge), row1 = std::min(tn_int, row0 + edge);
                const bool overlap = static_cast<float>(o.column0) / fn < static_cast<float>(column1) / tn &&
                                     static_cast<float>(column0) / tn < static_cast<float>(o.column1) / fn &&
                                     static_cast<float>(o.row0) / fn < static_cast<float>(row1) / tn &&
                                     static_cast<float>(row0) / tn < static_cast<float>(o.row1) / fn;
                if (!overlap) continue;
                Union& u = unions[static_cast<std::size_t>((o.face * to_per_edge + br) * to_per_edge + bc)];
                u.any = true;
                u.unknown = u.unknown || o.unrecorded_texels > 0;
                u.record.merge(o.record());
            }
    });
    to.for_each_block_state([&](const Block& t) {
        const Union& u = unions[static_cast<std::size_t>((t.face * to_per_edge + t.row0 / edge) * to_per_edge + t.column0 / edge)];
        if (u.any && !u.unknown) to.record_texels_of_block(t, u.record);
    });
}

} // namespace raycache
