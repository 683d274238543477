// raycache/embree/scene_cache.hpp: RayCache for an existing Embree 3 tracer. Maps Embree geometry (and
// instance) ids to caching cubes and wraps Algorithm 1 around the tracer's own secondary-ray trace.
//
// Adopting it, in a Whitted shader, where a ray hit object `hit` and leaves it at `p` in direction `r`:
//
//     raycache::embree::SceneCache caches(raycache::embree::Technique::cct);
//     caches.attach(scene, {mirror_geom_id});   // once, after rtcCommitScene; face size chosen per frame
//     caches.attach(scene, {instance_geom_id}); // an instance: every geometry reached through it
//     caches.attach_primitives(scene, {all_triangles_id}, first, count); // one object of a shared geometry
//     ...
//     glm::vec3 reflected = caches.leaving_ray(raycache::embree::object_of(hit), p, r, [&] {
//         return trace_leaving(p, r, depth + 1);  // your trace: TracedRay{colour, hit distance or inf}
//     });
//     ...
//     caches.begin_frame();                                              // between frames
//
// For refraction, trace the entry and internal bounces as usual and pass the ray that finally leaves
// the object: that is the ray the cube caches.
//
// Memory and resolution. By default (attach() without a face size) each cube's face size follows the
// leaving rays its object received in the last frame (raycache/adaptive_resolution.hpp), and all cubes
// draw on one MemoryBudget (SceneCacheSettings::budget_bytes): each cube's fixed part (tile table,
// bitmaps, counters) and its texel tiles. A tile that does not fit is not cached, its rays are traced; a
// cube grows only as far as the budget holds its larger fixed part; attach() throws std::invalid_argument
// when the budget has no room for another cube. So the cubes' bytes (allocated_bytes()) stay within the
// budget, all but the CDCT relief walk's depth pyramids. An explicit face size keeps a cube at that size.
//
// Warm starts. save() writes every cube to one file and load() reads it back into a SceneCache with the
// same objects attached (raycache/cache_file.hpp: format, checks, atomic writes).
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <embree3/rtcore.h>
#include <glm/glm.hpp>

#include "raycache/raycache.hpp"
#include "raycache/invalidation.hpp"

namespace raycache {

// Helpers of the Embree adapter (geometry measurement and primitive ranges).
namespace detail {
// "first..last" of a primitive range.
inline std::string range_text(unsigned first_prim, unsigned prim_count) {
    return std::to_string(first_prim) + ".." + std::to_string(std::uint64_t{first_prim} + prim_count - 1);
}

// Throws std::invalid_argument unless the range is non-empty and inside a geometry of `total` primitives.
inline void check_primitive_range(unsigned geom_id, unsigned first_prim, unsigned prim_count, unsigned total) {
    if (prim_count == 0)
        throw std::invalid_argument("RayCache: an empty primitive range (prim_count 0) of geometry " +
                                    std::to_string(geom_id) + " has nothing to cache");
    if (first_prim >= total || prim_count > total - first_prim)
        throw std::invalid_argument("RayCache: primitives " + range_text(first_prim, prim_count) +
                                    " are past the end of geometry " + std::to_string(geom_id) + ", which has " +
                                    std::to_string(total) + " primitives (0.." + std::to_string(total - 1) + ")");
}

// f(alone) on a committed scene that holds only geometry `id` of `scene` (Embree answers bounds and point
// queries per scene). Throws std::invalid_argument when `scene` has no geometry `id`.
template <class F>
auto with_geometry_alone(RTCScene scene, unsigned id, F&& f) {
    RTCGeometry geometry = scene ? rtcGetGeometry(scene, id) : nullptr;
    if (!geometry)
        throw std::invalid_argument("RayCache: the Embree scene has no geometry with id " + std::to_string(id) +
                                    " (attach after rtcCommitScene, with the id rtcAttachGeometry returned)");
    RTCDevice device = rtcGetSceneDevice(scene); // a reference of its own, released below
    RTCScene alone = rtcNewScene(device);
    rtcAttachGeometry(alone, geometry);
    rtcCommitScene(alone);
    const auto result = std::forward<F>(f)(alone);
    rtcReleaseScene(alone);
    rtcReleaseDevice(device);
    return result;
}

// triangle_bounds() of a range already checked against the geometry's primitive count.
inline CubeBounds measure_triangles(RTCGeometry geometry, unsigned geom_id, unsigned first_prim, unsigned prim_count) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    glm::vec3 lower(std::numeric_limits<float>::infinity()), upper(-std::numeric_limits<float>::infinity());
    for (unsigned prim = first_prim; prim - first_prim < prim_count; ++prim)
        for (const glm::vec2 corner : {glm::vec2(0, 0), glm::vec2(1, 0), glm::vec2(0, 1)}) {
            glm::vec3 p(nan);
            rtcInterpolate0(geometry, prim, corner.x, corner.y, RTC_BUFFER_TYPE_VERTEX, 0, &p.x, 3);
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                throw std::invalid_argument("RayCache: cannot read finite triangle corners of geometry " +
                                            std::to_string(geom_id) + " (triangle_bounds needs a triangle geometry)");
            lower = glm::min(lower, p);
            upper = glm::max(upper, p);
        }
    return cube_around_box(lower, upper, "primitives " + range_text(first_prim, prim_count) + " of geometry " +
                                             std::to_string(geom_id));
}
} // namespace detail

namespace embree {

// Which technique a SceneCache's cubes use.
enum class Technique { cct, cdct };

// The face size to pass to attach() for a cube whose face size follows its object's rays (the default).
inline constexpr int adaptive_face_size = 0;

// Whether a SceneCache's cubes keep what their stores' paths saw (leaving_ray's recording form, a record
// per 2 x 2 block of texels), which exact invalidation (scene_changed) needs to keep the texels a move
// cannot have changed. A static scene never reads them; without them a tile takes 76% (CCT) or 64% (CDCT)
// less memory, and a cold frame, which allocates most tiles, costs less.
enum class PathRecords {
    // None until the first scene_changed() under Invalidation::exact that moves an object or a light:
    // that call empties every cube (its texels were stored without records, so the move drops them
    // anyway) and from then on the cubes keep records. For caches that may or may not see moves.
    from_first_move,
    always, // from the first frame: a scene known to move keeps the texels of its first frames too
    never,  // exact invalidation then empties every texel at any move, as for stores without a record
};

// Everything a SceneCache can be tuned by; the defaults need no tuning.
struct SceneCacheSettings {
    ReliefParameters relief{};          // the CDCT's search (relief.search: secant, the default, or relief)
    bool depth_pyramid = true;          // CDCT relief search: over a min-depth pyramid (false: the thesis's walk)
    AdaptiveResolution adaptive{};      // how adaptive cubes pick their face size
    // CCT: a hit (the ray's own texel is visible) answers with the bilinear mean of the visible texels
    // around the ray's direction (raycache/filtered_lookup.hpp); false (the default): with the own texel
    // alone. Filtering gains about 1.5 dB on moving cameras at adaptive sizes and costs 15-20% of the frame.
    bool filtered = false;
    // Confidence test, CCT and CDCT (raycache/edge_confidence.hpp): texels whose colour differs from a filled
    // neighbour's by more than this (linear radiance, any channel) are not answered; their rays are
    // traced. Negative: off.
    float edge_threshold = 0.1f;
    // CCT: a texel answers a ray only while the ray leaves within this fraction of the cube's half-size of
    // the origins its tile was stored from; a tile met from further away is dropped and refills (the CCT
    // ignores where rays start, so a circling camera would otherwise read colours from the old viewpoint).
    // Negative: off.
    float origin_drift = 0.1f;
    // CCT: and at most this many radians of parallax: a tile whose rays hit a surface at distance d answers
    // only rays leaving within origin_parallax x d of its origins (a near floor under a mirror ball moves in
    // the reflection long before the far walls do). Applies with origin_drift; infinity: off.
    float origin_parallax = 0.01f;
    std::size_t budget_bytes = std::size_t{256} << 20; // texel tiles of all cubes together
    // When the cubes keep what their stores' paths saw (PathRecords).
    PathRecords path_records = PathRecords::from_first_move;
    // Exact invalidation's transitive step, for paths that hit a cached object whose cube lost texels: true,
    // such a path goes only when the cube lost texels in a direction cell its cached answers read it in
    // (raycache/direction_cells.hpp; paths that track them, PathRecord::track_cached_reads); false, it goes
    // whenever the cube lost any texel, which also drops texels that other rays than the stored one answer
    // through that object's reflections (Results: "Dynamic scenes" says what each keeps and leaves).
    bool transitive_by_direction = true;
    // Diagnostics: a ray the cube answers is traced anyway and its traced colour returned, while the cubes
    // work as usual (looked up, counted, filled on misses, ended). Frames then equal uncached ones, and what
    // they take beyond an uncached frame is the cache's own work. (Rays leaving cached objects inside such a
    // traced hit are looked up too, which a frame that uses its hits skips.) Off by default.
    bool trace_hits = false;
    // Resting cubes (raycache/resting.hpp): a cube whose looked-up rays found fewer than this share of hits
    // in a frame rests the next frame (its rays are traced without lookup or store, but for a sixteenth of
    // the directions, fewer while they find it still not paying, which keep measuring it) and works again
    // once those find this share. Unset: the technique's default_min_hit_rate(), or, when the trace
    // callbacks report what their rays cost (TracedRay::work), each cube's own break-even from it
    // (lookup_work). 0: cubes never rest.
    std::optional<float> min_hit_rate;
    // What one lookup costs, with its share of stores and end-of-frame work, in the units the trace callbacks
    // report TracedRay::work in. While min_hit_rate is unset and the rays that filled a cube's texels reported
    // their work, the cube rests when its hit rate is below lookup_work / (their mean work, over recent frames)
    // (raycache/resting.hpp, resting_threshold). Unset: default_lookup_work(), for work counted in rays
    // (each intersection and shadow ray one). <= 0: the fixed default_min_hit_rate() alone.
    std::optional<float> lookup_work;
};

// SceneCacheSettings::min_hit_rate unset: 0.5 for the CCT, 0.6 for the CDCT (raycache/resting.hpp says why).
inline float default_min_hit_rate(Technique technique) noexcept {
    return raycache::default_min_hit_rate(technique == Technique::cdct);
}

// SceneCacheSettings::lookup_work unset, for work counted in rays traced (intersections and shadow rays
// alike): CCT 1, CDCT 2. A CCT lookup with its stores and end-of-frame work costs about what an Embree ray
// with its shading does on the example tracer (90 ns against 85); a CDCT search about twice that (measured
// side by side with costlier rays: at 1.2, reflective-32's CDCT kept working at 40% hits under 4 shadow
// rays a hit and ran at 0.92x of uncached, at 2 it rested and ran at 0.96x to 0.97x). With the example's
// point light, where a leaving ray that fills a texel takes 1.6 to 1.9 rays, the CCT's threshold is then
// about 0.55 and the CDCT's the ceiling, 0.9: it does not pay there.
inline float default_lookup_work(Technique technique) noexcept { return technique == Technique::cdct ? 2.0f : 1.0f; }

// An object as Embree reports it in a hit: geomID; instID[0] when it was reached through an instance
// (Embree reports RTC_INVALID_GEOMETRY_ID there for a plain hit); primID, which matters only for a
// geometry split into objects by SceneCache::attach_primitives(). object_of(hit) fills all three.
struct ObjectId {
    unsigned geom_id = RTC_INVALID_GEOMETRY_ID;
    unsigned inst_id = RTC_INVALID_GEOMETRY_ID;
    unsigned prim_id = RTC_INVALID_GEOMETRY_ID;
};

// The object an Embree hit landed on: {hit.geomID, hit.instID[0], hit.primID}.
inline ObjectId object_of(const RTCHit& hit) noexcept { return {hit.geomID, hit.instID[0], hit.primID}; }

// The key of an object in PathRecords (PathRecord::hit) and in scene changes: instance and geometry
// (primitive ranges of one geometry share it).
inline std::uint64_t path_key(ObjectId id) noexcept { return std::uint64_t{id.inst_id} << 32 | id.geom_id; }

// What SceneCache::scene_changed() does with the cached texels.
enum class Invalidation {
    none,  // keep every texel (cubes of moved objects are still re-centred): what a static cache would do
    all,   // empty every cube
    exact, // empty the texels the changes can have affected (raycache/invalidation.hpp), keep the rest
};

// One object that moved between two frames: bounding spheres before and after; for an object with a cube,
// optionally where its cube sits now (default: moved by the spheres' centres' offset, same half-size).
// `id` names a geometry or instance (every primitive range of it moves), or with a prim_id the one
// primitive range (attach_primitives()) that holds that primitive.
struct ObjectMove {
    ObjectId id;
    BoundingSphere before, after;
    std::optional<CubeBounds> cube;
};

// Everything that changed between two frames.
struct SceneChange {
    std::vector<ObjectMove> moved;
    bool light_moved = false;
    std::vector<glm::vec3> lights; // the point lights as they are now (for the shadow-ray tests)
};

// What SceneCache::scene_changed() did.
struct InvalidationStatistics {
    std::size_t valid_before = 0;   // texels holding a value, all cubes
    std::size_t dropped = 0;        // texels emptied; under exact, these five:
    std::size_t dropped_with_moved_cubes = 0; // ... in the cubes of moved objects (emptied whole)
    std::size_t dropped_by_cone = 0;          // ... whose own rays' cone met a moved sphere
    std::size_t dropped_by_path = 0;          // ... with record blocks whose paths met a move (or a moved light)
    std::size_t dropped_transitively = 0;     // ... with blocks whose paths hit a cached object whose cube changed
    std::size_t dropped_unrecorded = 0;       // ... whose store brought no path record
    std::size_t cubes_moved = 0;    // cubes re-centred with their objects
    std::size_t cubes_changed = 0;  // cubes that lost a texel (their objects' reflections changed)
    double milliseconds = 0.0;
    double kept_fraction() const noexcept {
        return valid_before ? 1.0 - static_cast<double>(dropped) / static_cast<double>(valid_before) : 1.0;
    }
};

// Counters summed over every cube of a SceneCache, for one frame.
struct SceneCacheStatistics {
    std::uint64_t lookups = 0;
    std::uint64_t hits = 0;
    std::uint64_t misses = 0;
    std::array<std::uint64_t, miss_reason_count> misses_by{}; // misses by MissReason (CubeStatistics)
    std::uint64_t stores = 0;
    std::uint64_t texels_read = 0;     // CDCT searches only
    std::uint64_t max_texels_read = 0; // the most one CDCT search read
    std::size_t valid_texels = 0;
    std::size_t texel_count = 0;
    std::size_t texel_bytes = 0;     // 6 N^2 texels of every cube, as if every tile were allocated
    std::size_t allocated_bytes = 0; // what the cubes hold: allocated tiles and tile tables
    std::size_t pyramid_bytes = 0;   // CDCT depth pyramids
    std::size_t resized_cubes = 0;   // adaptive cubes whose face size changed at this begin_frame()
    std::size_t doubtful_texels = 0; // texels the confidence test does not answer (their rays are traced)
    std::size_t emptied_for_origins = 0; // cubes emptied: rays left further out than an invalidation checked
    std::size_t resting_cubes = 0;   // cubes that rest during the next frame (SceneCacheSettings::min_hit_rate)
    std::uint64_t filled_work = 0;   // what the rays that filled texels this frame reported they cost ...
    std::uint64_t work_reports = 0;  // ... (TracedRay::work), and how many reported it

    // The mean work of a ray that filled a texel and reported it; 0 when none did.
    double mean_filled_work() const noexcept {
        return work_reports ? static_cast<double>(filled_work) / static_cast<double>(work_reports) : 0.0;
    }

    double hit_rate() const noexcept { return lookups ? static_cast<double>(hits) / static_cast<double>(lookups) : 0.0; }
    // The share of the lookups that missed for `why`, 0..1.
    double miss_share(MissReason why) const noexcept {
        return lookups ? static_cast<double>(misses_by[static_cast<std::size_t>(why)]) / static_cast<double>(lookups) : 0.0;
    }
    double valid_fraction() const noexcept {
        return texel_count ? static_cast<double>(valid_texels) / static_cast<double>(texel_count) : 0.0;
    }
    // Lookups the cubes made (resting misses left out: a resting cube reads nothing for them).
    std::uint64_t looked_up() const noexcept { return looked_up_count(lookups, misses_by); }
    // CDCT: texels a search read, over the rays looked up.
    double texels_per_lookup() const noexcept {
        const std::uint64_t n = looked_up();
        return n ? static_cast<double>(texels_read) / static_cast<double>(n) : 0.0;
    }
};

// The cube placement of a geometry of a committed scene: cube_around_box() of its bounds (the library's
// rule, raycache/cube_placement.hpp). For an instance id, the bounds of the whole instance.
// `id` must be one that rtcAttachGeometry returned for `scene` (Embree has no way to ask how many ids a
// scene has, and its debug builds abort on one past the end). Throws std::invalid_argument when that
// geometry was detached, or its bounds are empty or infinite.
inline CubeBounds bounds_of(RTCScene scene, ObjectId id) {
    const unsigned outer = id.inst_id != RTC_INVALID_GEOMETRY_ID ? id.inst_id : id.geom_id;
    const RTCBounds b = detail::with_geometry_alone(scene, outer, [](RTCScene alone) {
        RTCBounds bounds;
        rtcGetSceneBounds(alone, &bounds);
        return bounds;
    });
    return cube_around_box(glm::vec3(b.lower_x, b.lower_y, b.lower_z), glm::vec3(b.upper_x, b.upper_y, b.upper_z),
                           "geometry " + std::to_string(outer));
}

// How many primitives geometry `geom_id` of the committed `scene` has, counted by a point query over all
// of space (Embree 3 has no call that tells). Embree answers point queries for triangle, quad and user
// geometries; for others (curves, points, ...) this throws std::invalid_argument, as for an unknown id.
inline unsigned primitive_count(RTCScene scene, unsigned geom_id) {
    const unsigned count = detail::with_geometry_alone(scene, geom_id, [](RTCScene alone) {
        RTCPointQuery query{};
        query.radius = std::numeric_limits<float>::infinity();
        RTCPointQueryContext context;
        rtcInitPointQueryContext(&context);
        unsigned end = 0; // one past the largest primID met
        rtcPointQuery(alone, &query, &context, [](RTCPointQueryFunctionArguments* a) {
            unsigned& e = *static_cast<unsigned*>(a->userPtr);
            e = std::max(e, a->primID + 1);
            return false;
        }, &end);
        return end;
    });
    if (count == 0)
        throw std::invalid_argument("RayCache: cannot count the primitives of geometry " + std::to_string(geom_id) +
                                    " (Embree's point queries reach triangle, quad and user geometries only)");
    return count;
}

// The cube placement (as bounds_of) of triangles first_prim .. first_prim + prim_count - 1 of triangle
// geometry `geom_id` (RTC_GEOMETRY_TYPE_TRIANGLE) of the committed `scene`, from their corners as
// rtcInterpolate reads them (any vertex format and stride). For other geometry types pass your own
// bounds. Throws std::invalid_argument when the range is empty or past the geometry's primitive_count(),
// or the corners cannot be read or are not finite.
inline CubeBounds triangle_bounds(RTCScene scene, unsigned geom_id, unsigned first_prim, unsigned prim_count) {
    detail::check_primitive_range(geom_id, first_prim, prim_count, primitive_count(scene, geom_id));
    return detail::measure_triangles(rtcGetGeometry(scene, geom_id), geom_id, first_prim, prim_count);
}

// The caching cubes of one Embree scene, one per attached object, all of one technique.
// Threads: leaving_ray() from any number of threads at once; attach(), begin_frame() and clear()
// between frames, on one thread.
class SceneCache {
    // How far from its cube's centre an object's leaving rays start. Exact invalidation tests the rays from
    // the ball of radius seen (the furthest origin any ray was stored from or answered for) grown by 2%,
    // for a round object about its own sphere where the box's ball is up to 1.73 times wider. From then on
    // the cube answers only rays from within `limit` (that radius): a texel it kept is known unchanged for
    // those alone. A ray from further out is traced and neither answered nor stored; at the next begin_frame()
    // the cube is emptied and answers rays from anywhere again, its ball widened. A maximum, so the result
    // is the same on any number of threads.
    struct OriginReach {
        std::atomic<float> seen{0.0f};
        float limit = std::numeric_limits<float>::infinity(); // between frames only
        float limit_squared = std::numeric_limits<float>::infinity();

        // Whether this frame's lookups may answer, and stores keep, a ray leaving from `offset` (origin -
        // centre); its distance widens `seen`. Thread-safe; a relaxed read unless the ray is the furthest.
        bool admits(const glm::vec3& offset) noexcept {
            const float squared = glm::dot(offset, offset);
            if (!std::isfinite(squared)) return false; // a bad origin: traced alone
            float most = seen.load(std::memory_order_relaxed);
            if (squared > most * most) {
                const float distance = std::sqrt(squared);
                while (distance > most && !seen.compare_exchange_weak(most, distance, std::memory_order_relaxed)) {
                }
            }
            return squared <= limit_squared;
        }
        // The ball exact invalidation tests, which the cube's answers are then limited to; never wider than
        // the ball around the box (box_radius: box_origin_radius()), the widest it tests. Between frames.
        float restrict_to_seen(float box_radius) noexcept {
            const float furthest = seen.load(std::memory_order_relaxed);
            if (!(furthest > 0.0f)) return limit; // no ray yet (a pre-filled cube): from anywhere in the box
            // 2% of room: the rays of a camera that moves on leave from points of the surface not met yet,
            // a little further out where the tracer's offset grows, and each wider one would empty the cube.
            limit = std::min(limit, std::min(furthest * 1.02f, box_radius));
            limit_squared = limit * limit;
            return limit;
        }
        // True (and the limit lifted) when a ray came from outside the limit: the cube must be emptied.
        bool outgrown() noexcept {
            if (!(seen.load(std::memory_order_relaxed) > limit)) return false;
            lift();
            return true;
        }
        void lift() noexcept { limit = limit_squared = std::numeric_limits<float>::infinity(); }
        // An emptied cube: nothing it holds was stored from anywhere. Between frames.
        void forget() noexcept {
            lift();
            seen.store(0.0f, std::memory_order_relaxed);
        }
        // As a cache file recorded them (load): `limit` infinity for none.
        void restore(float seen_radius, float limit_radius) noexcept {
            seen.store(seen_radius, std::memory_order_relaxed);
            limit = limit_radius;
            limit_squared = limit_radius * limit_radius;
        }
    };

    // One attached object: where its cube sits, and the cube of the cache's technique.
    struct Entry {
        ObjectId id;
        CubeBounds bounds;
        std::unique_ptr<CctCube> cct;
        std::unique_ptr<CdctCache> cdct;             // its cube, bounds, parameters and (depth_pyramid) pyramid
        std::unique_ptr<DirectionCoverage> coverage; // adaptive cubes only: directions of this frame's rays
        bool sized = false; // adaptive: sized once from counted rays (later moves need the hysteresis)
        std::unique_ptr<OriginReach> origins = std::make_unique<OriginReach>();
        // The counters of cubes this entry's emptied or replaced since the last begin_frame() (scene_changed()
        // may run between a frame and its begin_frame()): that frame's statistics and sizing still count them.
        CubeStatistics carried{};
        // raycache/resting.hpp: whether the cube rests this frame, and whether it started the frame empty.
        RestingState rest{};
        bool cold = true;
        // The work of the rays that filled its texels (TracedRay::work) and how many reported it, over recent
        // frames (raycache::next_work_estimate): a warm cube on a still camera, or a resting one, stores
        // little, yet its hits save what its texels' rays cost.
        WorkEstimate work{};
        StillRays still{}; // adaptive: whether its rays hold still (finer faces: still_rays_per_texel)
    };

    // Primitives first .. end - 1 of one geometry, which have the cube entries_[entry].
    struct PrimitiveRange {
        unsigned first, end;
        int entry;
    };
    // A geometry split into primitive ranges: its primitive count, and its ranges sorted and disjoint.
    struct RangedGeometry {
        unsigned primitive_count;
        std::vector<PrimitiveRange> ranges;
    };

    // f(cube) on the entry's cube, whichever technique it holds (f is instantiated for both).
    template <class F>
    static decltype(auto) with_cube(Entry& e, F&& f) {
        return e.cct ? f(*e.cct) : f(e.cdct->cube());
    }
    template <class F>
    static decltype(auto) with_cube(const Entry& e, F&& f) {
        return e.cct ? f(static_cast<const CctCube&>(*e.cct)) : f(static_cast<const CdctCube&>(e.cdct->cube()));
    }

public:
    // Throws std::invalid_argument for bad relief parameters (used by the CDCT only). With depth_pyramid
    // (the default), each CDCT cube keeps a DepthPyramid so its searches skip empty space; without, the
    // search is the thesis's fixed-step walk.
    explicit SceneCache(Technique technique, ReliefParameters relief = {}, bool depth_pyramid = true)
        : SceneCache(technique, make_settings(relief, depth_pyramid)) {}
    // Throws std::invalid_argument naming the field for bad settings.
    SceneCache(Technique technique, const SceneCacheSettings& settings)
        : technique_(technique), relief_(settings.relief), use_pyramid_(settings.depth_pyramid),
          adaptive_(settings.adaptive), filtered_(settings.filtered), edge_threshold_(settings.edge_threshold),
          origin_drift_(settings.origin_drift), origin_parallax_(settings.origin_parallax), path_records_(settings.path_records == PathRecords::always),
          record_policy_(settings.path_records), transitive_by_direction_(settings.transitive_by_direction), trace_hits_(settings.trace_hits), min_hit_rate_(settings.min_hit_rate.value_or(default_min_hit_rate(technique))),
          threshold_from_work_(!settings.min_hit_rate), lookup_work_(settings.lookup_work.value_or(default_lookup_work(technique))),
          budget_(std::make_shared<MemoryBudget>(settings.budget_bytes)), first_face_size_(settings.adaptive.first_face_size) {
        validate(relief_);
        validate(adaptive_);
        if (!(origin_parallax_ > 0.0f))
            throw std::invalid_argument("RayCache SceneCacheSettings::origin_parallax must be > 0 (infinity: off), got " +
                                        std::to_string(origin_parallax_));
        if (std::isnan(origin_drift_))
            throw std::invalid_argument("RayCache SceneCacheSettings::origin_drift must be a number (negative: off)");
        if (!(min_hit_rate_ >= 0.0f))
            throw std::invalid_argument("RayCache SceneCacheSettings::min_hit_rate must be >= 0 (0: cubes never rest), got " +
                                        std::to_string(min_hit_rate_));
        if (!std::isfinite(lookup_work_))
            throw std::invalid_argument("RayCache SceneCacheSettings::lookup_work must be a finite number (<= 0: thresholds ignore work)");
    }

    Technique technique() const noexcept { return technique_; }
    const ReliefParameters& relief() const noexcept { return relief_; }
    const MemoryBudget& budget() const noexcept { return *budget_; }

    // Gives object `id` of the committed `scene` a cube placed by bounds_of(), of face_size texels per edge,
    // or (adaptive_face_size, the default) one whose face size follows the rays its object receives.
    // `id` may be a plain geometry, an (instance, geometry) pair, or an instance alone ({instance id}): then
    // every geometry reached through that instance shares the instance's cube.
    // Throws std::invalid_argument for a bad face size, an unknown geometry, an id attached twice, or a budget
    // with no room for another cube's fixed part (CacheCube::fixed_bytes() of the size it would start at);
    // nothing is attached then.
    void attach(RTCScene scene, ObjectId id, int face_size = adaptive_face_size) {
        attach(id, face_size, bounds_of(scene, id));
    }

    // Gives object `id` a cube around `bounds` (face_size as above).
    void attach(ObjectId id, int face_size, CubeBounds bounds) {
        check_attachable(id, bounds);
        if (id.prim_id != RTC_INVALID_GEOMETRY_ID)
            throw std::invalid_argument("RayCache: attach() gives a whole geometry a cube; give primitive " +
                                        std::to_string(id.prim_id) + "'s range its own with attach_primitives()");
        if (has_cache(id))
            throw std::invalid_argument("RayCache: geometry " + std::to_string(id.geom_id) + " already has a cube");
        if (slot_of(id) < -1)
            throw std::invalid_argument("RayCache: geometry " + std::to_string(id.geom_id) +
                                        " is split into primitive ranges with cubes of their own; it cannot also have one as a whole");
        slot(id) = add_entry(id, face_size, bounds);
    }

    // Gives primitives first_prim .. first_prim + prim_count - 1 of `geometry` a cube of their own, for
    // tracers that keep several objects in one Embree geometry. A hit finds it when its ObjectId carries
    // the hit's primID (object_of(hit)); a hit on a primitive of that geometry outside every range finds
    // no cube. This overload measures the cube's placement with triangle_bounds(), so it needs a triangle
    // geometry (RTC_GEOMETRY_TYPE_TRIANGLE) of `scene` not reached through an instance; for other
    // geometries, pass the bounds. face_size as in attach(). Throws std::invalid_argument for an empty
    // range, one past the geometry's primitive_count(), one overlapping a range with a cube, a geometry
    // that has a cube as a whole (attach()), or a bad face size.
    void attach_primitives(RTCScene scene, ObjectId geometry, unsigned first_prim, unsigned prim_count,
                           int face_size = adaptive_face_size) {
        if (geometry.inst_id != RTC_INVALID_GEOMETRY_ID)
            throw std::invalid_argument("RayCache: primitives inside instance " + std::to_string(geometry.inst_id) +
                                        " cannot be measured in world space; pass their cube's bounds to attach_primitives()");
        const unsigned total = known_primitive_count(scene, geometry);
        detail::check_primitive_range(geometry.geom_id, first_prim, prim_count, total);
        const CubeBounds bounds = detail::measure_triangles(rtcGetGeometry(scene, geometry.geom_id), geometry.geom_id,
                                                            first_prim, prim_count);
        attach_range(geometry, first_prim, prim_count, face_size, bounds, total);
    }

    // attach_primitives() with the caller's bounds (world space), for any geometry type whose primitives
    // Embree can count (primitive_count()). `scene` is the scene that holds geometry.geom_id: for a
    // geometry reached through instance geometry.inst_id, the instanced scene.
    void attach_primitives(RTCScene scene, ObjectId geometry, unsigned first_prim, unsigned prim_count, int face_size,
                           CubeBounds bounds) {
        check_attachable(geometry, bounds);
        attach_range(geometry, first_prim, prim_count, face_size, bounds, known_primitive_count(scene, geometry));
    }

    bool has_cache(ObjectId id) const noexcept { return find(id) >= 0; }
    std::size_t object_count() const noexcept { return entries_.size(); }

    // The objects with cubes, in attach order (a primitive range: its geometry, prim_id = its first primitive).
    std::vector<ObjectId> objects() const {
        std::vector<ObjectId> ids;
        for (const Entry& e : entries_) ids.push_back(e.id);
        return ids;
    }

    // Face size of object `id`'s cube; 0 when it has none.
    int face_size(ObjectId id) const noexcept {
        const int index = find(id);
        if (index < 0) return 0;
        return with_cube(entries_[static_cast<std::size_t>(index)], [](const auto& cube) { return cube.face_size(); });
    }

    // Pre-fills one row of one face of object `id`'s cube (see raycache/prefill.hpp): every empty texel is
    // traced from the cube's centre outwards. trace: `TracedRay trace(glm::vec3 origin, glm::vec3 direction)`,
    // which must pass through object `id` itself (for example by continuing past hits on its geometry).
    // Rows may be filled from many threads at once; the stores become visible at the next begin_frame().
    // Returns the texels stored (0 for an object without a cube).
    template <class Trace>
    std::size_t prefill_row(ObjectId id, int face, int row, Trace&& trace) {
        const int index = find(id);
        if (index < 0) return 0;
        Entry& e = entries_[static_cast<std::size_t>(index)];
        return with_cube(e, [&](auto& cube) { return raycache::prefill_row(cube, e.bounds, relief_, face, row, trace); });
    }

    // Algorithm 1 around the caller's trace: the colour brought back by the ray leaving object `id` at
    // `origin` in `direction` (the reflected ray; for refraction the ray that finally leaves the object).
    // trace: callable `TracedRay trace()` (colour, and distance along the unit direction to its hit,
    // infinity when it escaped; the CCT keeps the nearest per tile to bound parallax), or `TracedRay
    // trace(PathRecord&)`, which also reports what the path hit (raycache/path_record.hpp) so that
    // scene_changed() can keep what a move cannot have changed. It runs on a miss; its colour is returned
    // unchanged (under SceneCacheSettings::trace_hits it runs on a hit too, and its colour is returned).
    // Objects without a cube: returns trace().color. Thread-safe.
    // enclosing: for a ray nested in the trace of another cached ray (a bounce of its path), that path's
    // record: when this cube answers the ray, the directions its texels were read in are noted there
    // (PathRecord::read_cached), so exact invalidation keeps the enclosing path's texel when this cube loses
    // texels only elsewhere. A tracer that passes it for every nested leaving ray calls
    // PathRecord::track_cached_reads() at the start of its recording trace; null: nothing noted.
    template <class Trace>
    glm::vec3 leaving_ray(ObjectId id, const glm::vec3& origin, const glm::vec3& direction, Trace&& trace,
                          PathRecord* enclosing = nullptr) {
        static_assert(std::is_invocable_r_v<TracedRay, Trace&> || std::is_invocable_r_v<TracedRay, Trace&, PathRecord&>,
                      "RayCache SceneCache::leaving_ray: trace must be callable as `raycache::TracedRay trace()` or "
                      "`raycache::TracedRay trace(raycache::PathRecord&)`");
        return enclosing ? noting_reads(id, origin, direction, trace, *enclosing) : answered(id, origin, direction, trace);
    }

private:
    // leaving_ray() without an enclosing path.
    template <class Trace>
    glm::vec3 answered(ObjectId id, const glm::vec3& origin, const glm::vec3& direction, Trace& trace) {
        if (!trace_hits_) return through_cube(id, origin, direction, trace);
        // SceneCacheSettings::trace_hits: whether the cube answered is known by whether trace() ran. The
        // wrapper takes whichever form `trace` has (its return type keeps the other form out of overloads).
        bool traced = false;
        auto noting = [&](auto&... path) -> decltype(trace(path...)) {
            traced = true;
            return trace(path...);
        };
        const glm::vec3 colour = through_cube(id, origin, direction, noting);
        return traced ? colour : trace_alone(trace);
    }

    // leaving_ray() for a ray nested in the path `enclosing` records. When the cube answers it (trace() did
    // not run), the enclosing path depends on what the answering texel saw and on the cube's texels where
    // it was read: the texel's record block's union joins the enclosing record (so a move that its paths
    // met drops the enclosing texel, even once the cube's texel has been replaced), and the directions
    // read are noted, with the cube's key among the objects hit (PathRecord::read_cached: a move that empties
    // the cube's texels there drops the enclosing texel transitively): the ray's own for the CCT (a filtered lookup's other taps lie within
    // the texel that invalidation grows a changed region by), and for the CDCT the cone from the centre
    // through the points its search read, every one on the ray past the box exit
    // (raycache/shared/depth_secant.h, relief_walk.h).
    template <class Trace>
    glm::vec3 noting_reads(ObjectId id, const glm::vec3& origin, const glm::vec3& direction, Trace& trace, PathRecord& enclosing) {
        if (trace_hits_) return answered(id, origin, direction, trace); // every ray traced: nothing read
        bool traced = false;
        auto noting = [&](auto&... path) -> decltype(trace(path...)) {
            traced = true;
            return trace(path...);
        };
        ReliefResult found;
        const Entry* answering = nullptr;
        const glm::vec3 colour = through_cube(id, origin, direction, noting, &found, &answering);
        if (traced) return colour;
        if (!answering || !shared::raycache_is_direction(direction)) return colour; // (answered by no cube: traced)
        const Entry& e = *answering;
        // The enclosing path read this cube: it carries the cube's key, which the transitive step names the
        // cube by when it changes. A hit's key can differ from it: a cube attached to an instance alone is
        // named by the instance, hits through the instance by (instance, geometry).
        enclosing.objects |= object_bits(path_key(e.id));
        if (technique_ == Technique::cct) {
            const std::optional<TexelAddress> t = e.cct->texel_of(direction);
            if (t) enclosing.merge(e.cct->answer_record(*t));
            if (filtered_) {
                const shared::raycache_filter_taps taps = shared::raycache_filter_taps_of(direction, e.cct->face_size());
                for (int k = 0; k < taps.count; ++k) {
                    const shared::raycache_texel_address& a = taps.texel[k];
                    enclosing.merge(e.cct->answer_record(TexelAddress{a.face, a.column, a.row}));
                }
            }
            enclosing.read_cached(direction, direction);
            return colour;
        }
        // A relief walk's answering texel is not tracked: its answer counts as read from anywhere in the cube,
        // as a path that does not track its cached reads (the whole-cube rule).
        if (relief_.search != DepthSearch::secant) {
            enclosing.cached_reads = every_direction_cell;
            return colour;
        }
        // The search's own start: its first read, at the box exit (s.t), and the texel whose colour answered,
        // read at the answer's distance along the ray, are the points it read them at.
        const shared::raycache_secant_search s = shared::raycache_secant_start(
            origin, direction, e.bounds.centre, e.bounds.half_size, relief_.epsilon, relief_.max_gap, relief_.max_reads);
        const std::optional<TexelAddress> t = e.cdct->cube().texel_of(shared::raycache_secant_point(s, found.distance));
        if (!t) {
            enclosing.cached_reads = every_direction_cell;
            return colour;
        }
        enclosing.merge(e.cdct->cube().answer_record(*t));
        const glm::vec3 exit = shared::raycache_secant_point(s, s.t);
        const float length = glm::length(exit);
        if (!(length > 0.0f) || !std::isfinite(length)) {
            enclosing.cached_reads = every_direction_cell;
            return colour;
        }
        const glm::vec3 from = exit / length;
        enclosing.read_cached(glm::min(from, s.d), glm::max(from, s.d));
        return colour;
    }

    // trace() for a ray no cube looks at or stores into: the recording form with a record nobody keeps.
    template <class Trace>
    static glm::vec3 trace_alone(Trace& trace) {
        if constexpr (std::is_invocable_r_v<TracedRay, Trace&, PathRecord&>) {
            PathRecord unused;
            return trace(unused).color;
        } else {
            return trace().color;
        }
    }

    // leaving_ray() through the cube: looked up, and on a miss traced and stored.
    // `found`, when given, receives a CDCT search's outcome (untouched when no search ran); `entry`, when
    // given, the object's cube (null when it has none), so that noting_reads() need not find it again.
    template <class Trace>
    glm::vec3 through_cube(ObjectId id, const glm::vec3& origin, const glm::vec3& direction, Trace&& trace,
                           ReliefResult* found = nullptr, const Entry** entry = nullptr) {
        const int index = find(id);
        if (index < 0) return trace_alone(trace);
        Entry& e = entries_[static_cast<std::size_t>(index)];
        if (entry) *entry = &e;
        // A ray from outside what the last exact invalidation checked: traced alone, a miss (OriginReach).
        const bool answerable = e.origins->admits(origin - e.bounds.centre);
        // A resting cube (raycache/resting.hpp) looks up its probe directions alone; it keeps its face size
        // while it rests, so the other rays need no face choice.
        if (answerable && e.rest.resting && !is_probe_direction(direction, e.rest)) {
            with_cube(e, [](auto& cube) { cube.record_miss(MissReason::resting); });
            return trace_alone(trace);
        }
        if (technique_ == Technique::cct) {
            // The recording form lets exact invalidation keep what a move cannot have changed.
            const OriginTolerance tolerance{origin_drift_ * e.bounds.half_size, origin_parallax_};
            const std::optional<TexelAddress> texel = e.cct->texel_of(direction); // found once, for both
            if (e.coverage && texel) e.coverage->mark(*texel, e.cct->face_size());
            return cct_cached_trace_at(*e.cct, answerable ? texel : std::nullopt, direction, origin,
                                       origin_drift_ >= 0.0f ? &tolerance : nullptr, filtered_, trace);
        }
        if (e.coverage) e.coverage->mark(direction);
        if (!answerable) {
            e.cdct->cube().record_miss(MissReason::outside);
            return trace_alone(trace);
        }
        int read = 0;
        const glm::vec3 color = e.cdct->cached_trace(origin, direction, trace, &read, found);
        texels_read_.add(0, static_cast<std::uint64_t>(read));
        // A rarely-taken CAS: only a search that reads more than every one before it writes.
        std::uint64_t most = max_texels_read_.load(std::memory_order_relaxed);
        while (static_cast<std::uint64_t>(read) > most &&
               !max_texels_read_.compare_exchange_weak(most, static_cast<std::uint64_t>(read), std::memory_order_relaxed)) {
        }
        return color;
    }

public:
    // Between frames, after objects (or lights) moved: cubes of moved objects move with them, emptied
    // (except under Invalidation::none); the other cubes lose what `policy` says. Under exact, a CCT cube
    // or CDCT cube loses the texels the moves can have changed (raycache/invalidation.hpp: their rays'
    // cones, and what their paths saw as leaving_ray's recording callback reported it; texels filled through
    // the plain callback or loaded count as having seen everything), then, transitively, the texels whose
    // paths hit a cached object whose cube lost texels.
    // Deterministic; between frames only (before or after begin_frame()). Throws std::invalid_argument, before
    // anything changes, for a sphere or light that is not finite, a negative radius, or a moved cube's bounds
    // that are empty or not finite.
    InvalidationStatistics scene_changed(const SceneChange& change, Invalidation policy) {
        return scene_changed(change, policy, detail::SerialFor{});
    }

    // scene_changed() with each pass's cubes invalidated on the caller's threads: parallel_for(count, f) as
    // begin_frame()'s (f(i) once for each i in [0, count), on any threads, returning when all have). The
    // cubes of a pass share nothing they write but the budget's byte counter, and each cube's result
    // depends on its own texels and the changes alone, so the result is scene_changed()'s.
    template <class ParallelFor>
    InvalidationStatistics scene_changed(const SceneChange& change, Invalidation policy, ParallelFor&& parallel_for) {
        const auto started = std::chrono::steady_clock::now();
        SceneChanges changes;
        changes.lights = change.lights;
        changes.light_moved = change.light_moved;
        for (const ObjectMove& m : change.moved) {
            changes.moved.push_back({path_key(m.id), m.before, m.after});
            if (m.cube && !raycache::detail::is_usable(*m.cube))
                throw std::invalid_argument("RayCache: scene_changed: a moved object's cube has empty or infinite bounds");
        }
        check_scene_changes(changes); // bad input is refused before anything moves
        InvalidationStatistics stats;
        for (const Entry& e : entries_) stats.valid_before += with_cube(e, [](const auto& cube) { return cube.valid_texels(); });
        std::vector<char> changed(entries_.size(), 0), moved(entries_.size(), 0); // moved: emptied with its object
        // The direction cells each cube lost texels in since the transitive pass that last read them.
        std::vector<std::uint64_t> lost_cells(entries_.size(), 0);
        for (const ObjectMove& m : change.moved) {
            // A primitive names its range's cube alone (none when no range holds it); a whole geometry all its cubes.
            const int range = m.id.prim_id == RTC_INVALID_GEOMETRY_ID ? -1 : find(m.id);
            for (std::size_t i = 0; i < entries_.size(); ++i) {
                Entry& e = entries_[i];
                if (path_key(e.id) != path_key(m.id)) continue;
                if (m.id.prim_id != RTC_INVALID_GEOMETRY_ID && static_cast<int>(i) != range) continue;
                e.bounds = m.cube ? *m.cube : CubeBounds{e.bounds.centre + (m.after.centre - m.before.centre), e.bounds.half_size};
                if (e.cdct) e.cdct->move_to(e.bounds); // its searches and stores measure from the centre
                ++stats.cubes_moved;
                if (policy == Invalidation::none) continue;
                const std::size_t emptied = empty_cube(e);
                stats.dropped += emptied;
                stats.dropped_with_moved_cubes += emptied;
                changed[i] = moved[i] = 1;
                lost_cells[i] = every_direction_cell;
            }
        }
        if (policy == Invalidation::all)
            for (std::size_t i = 0; i < entries_.size(); ++i) stats.dropped += empty_cube(entries_[i]), changed[i] = 1;
        if (policy == Invalidation::exact) {
            std::vector<std::size_t> next; // entries that changed in the last pass
            for (std::size_t i = 0; i < entries_.size(); ++i)
                if (changed[i]) next.push_back(i);
            // One pass, in parallel, over the cubes that have not changed yet (the first) or that did not move
            // with their objects (the transitive ones: a cube that lost texels to the move may still hold texels
            // whose paths read a cube that changed since); then, in entry order, what it did.
            std::vector<std::size_t> todo;
            std::vector<InvalidationCounts> counts;
            auto pass = [&](const SceneChanges& c, bool transitive) {
                todo.clear();
                for (std::size_t i = 0; i < entries_.size(); ++i)
                    if (transitive ? !moved[i] : !changed[i]) todo.push_back(i);
                // Every cube's runs of tiles in one parallel_for: a cube of many tiles (a mirror that fills
                // the view) shares its tiles among the threads while the small cubes' runs fill the gaps,
                // with no wait between cubes. The passes are made here, in entry order (each settles its
                // cube's budget), and finished in parallel (a CDCT pyramid each).
                std::vector<std::unique_ptr<InvalidationPass>> passes;
                std::vector<std::pair<std::size_t, std::size_t>> runs; // (pass, run)
                for (std::size_t k = 0; k < todo.size(); ++k) {
                    passes.push_back(invalidation_pass(entries_[todo[k]], c));
                    for (std::size_t r = 0; r < passes.back()->runs(); ++r) runs.emplace_back(k, r);
                }
                const std::function<void(std::size_t)> run = [&](std::size_t j) { passes[runs[j].first]->run(runs[j].second); };
                parallel_for(runs.size(), run);
                counts.assign(todo.size(), InvalidationCounts{});
                const std::function<void(std::size_t)> finish = [&](std::size_t k) { counts[k] = passes[k]->finish(); };
                parallel_for(todo.size(), finish);
                for (std::size_t k = 0; k < todo.size(); ++k) {
                    stats.dropped += counts[k].dropped;
                    (transitive ? stats.dropped_transitively : stats.dropped_by_path) += counts[k].dropped_by_path;
                    stats.dropped_by_cone += counts[k].dropped_by_cone;
                    stats.dropped_unrecorded += counts[k].dropped_unrecorded;
                    if (!counts[k].dropped) continue;
                    const std::size_t i = todo[k];
                    changed[i] = 1;
                    next.push_back(i);
                    // A search over a depth pyramid reads coarse levels, which follow texels outside its cells.
                    const bool coarse_reads = entries_[i].cdct && entries_[i].cdct->pyramid();
                    lost_cells[i] |= coarse_reads || !transitive_by_direction_ ? every_direction_cell : counts[k].changed_cells;
                }
            };
            pass(changes, false);
            // A path that met a cached object may have read that object's cube: when the cube changed where the
            // path read it, so may the path.
            while (!next.empty()) {
                SceneChanges seen;
                for (std::size_t i : next) seen.changed.push_back({path_key(entries_[i].id), lost_cells[i]}), lost_cells[i] = 0;
                next.clear();
                pass(seen, true);
            }
            const bool geometric = !changes.moved.empty() || changes.light_moved;
            if (geometric && !path_records_ && record_policy_ == PathRecords::from_first_move) {
                // The first move: the cubes, stored without records, lost every texel to it; from now on their
                // replacements keep records (anything left is counted as dropped for want of one); this
                // frame's counts carry over (make_cube). Tiles with records are larger: adaptive cubes not
                // sized by a frame yet start where a cold frame's tiles fit the budget again.
                path_records_ = true;
                for (std::size_t i = 0; i < entries_.size(); ++i) {
                    Entry& e = entries_[i];
                    const std::size_t left = with_cube(e, [](const auto& cube) { return cube.valid_texels(); });
                    stats.dropped += left;
                    stats.dropped_unrecorded += left;
                    changed[i] = changed[i] || left > 0;
                    e.origins->forget(); // an empty cube, as empty_cube() leaves it
                    make_cube(e, with_cube(e, [](const auto& cube) { return cube.face_size(); }));
                }
                shrink_first_face_size(entries_.size());
            }
        }
        for (char c : changed) stats.cubes_changed += c ? 1 : 0;
        stats.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
        return stats;
    }

    // Ends a frame on every cube (this frame's stores become visible) and returns the frame's totals.
    // Adaptive cubes then take the face size their object's rays call for: a smaller one is filled from
    // the old cube (resample_into), a larger one starts empty.
    SceneCacheStatistics begin_frame() {
        return begin_frame(detail::SerialFor{});
    }

    // begin_frame() with the end-of-frame work spread over the caller's threads (the confidence test by
    // bands of every cube's tile rows, then each cube's own: making the frame's stores visible, the CDCT's
    // pyramid): parallel_for(count, f) must call f(i)
    // once for each i in [0, count), on any threads, and return when all calls have (for example through
    // tbb::parallel_for). There the cubes share only the budget's byte counter, which they give bytes back
    // to, so the result is begin_frame()'s. What allocates from the budget runs on the calling thread, in
    // attach order: the passes before, and resizing adaptive cubes after unless the budget has room for
    // every resized cube whatever it holds (adapt()).
    template <class ParallelFor>
    SceneCacheStatistics begin_frame(ParallelFor&& parallel_for) {
        SceneCacheStatistics total;
        // First, before anything reads the frame's stores or allocates between frames: if the budget refused
        // tiles this frame, none of the frame's new tiles is kept (which ones fit depended on thread timing):
        // every cube gives them back, then the tiles the frame wanted are allocated, empty, cube by cube.
        for (Entry& e : entries_) with_cube(e, [](auto& cube) { cube.give_back_refused_frame(); });
        for (Entry& e : entries_) with_cube(e, [](auto& cube) { cube.allocate_wanted_tiles(); });
        // The new face sizes first: a cube about to be replaced needs no confidence test of its own (the
        // smaller cube that takes its texels is tested after resampling; a larger one starts empty), which
        // after a cold frame is most of the test's work (every cube shrinks from its first size).
        const std::vector<Resize> resizes = plan_resizes();
        std::vector<char> replaced(entries_.size(), 0);
        for (const Resize& r : resizes) replaced[r.entry] = 1;
        mark_doubtful_edges_of_frame(parallel_for, replaced);
        std::vector<CubeStatistics> frames(entries_.size());
        const std::function<void(std::size_t)> end_cube = [&](std::size_t i) {
            Entry& e = entries_[i];
            frames[i] = e.cct ? e.cct->begin_frame() : e.cdct->begin_frame(); // the CDCT's: pyramid too
            add_counts(frames[i], e.carried);
            e.carried = CubeStatistics{};
        };
        parallel_for(entries_.size(), end_cube);
        for (const CubeStatistics& frame : frames) add(total, frame);
        for (std::size_t i = 0; i < entries_.size(); ++i) {
            Entry& e = entries_[i];
            e.work = next_work_estimate(e.work, frames[i].filled_work, frames[i].work_reports);
            e.rest = next_resting_state(e.rest, frames[i], resting_threshold_of(e), e.cold);
        }
        // A cube that met rays from outside what its last invalidation checked starts afresh, unlimited.
        for (Entry& e : entries_)
            if (e.origins->outgrown()) total.valid_texels -= empty_cube(e), total.emptied_for_origins += 1;
        total.resized_cubes = adapt(resizes, parallel_for);
        for (Entry& e : entries_) {
            total.resting_cubes += e.rest.resting ? 1 : 0;
            e.cold = with_cube(e, [](const auto& cube) { return cube.valid_texels(); }) == 0; // as the next frame starts
        }
        total.texels_read = texels_read_.sum(0);
        total.max_texels_read = max_texels_read_.exchange(0, std::memory_order_relaxed);
        total.texel_bytes = texel_bytes();
        total.allocated_bytes = allocated_bytes();
        total.pyramid_bytes = pyramid_bytes();
        for (const Entry& e : entries_) total.doubtful_texels += with_cube(e, [](const auto& cube) { return cube.doubtful_texels(); });
        texels_read_.reset();
        return total;
    }

    // The current frame's totals so far, without ending it.
    SceneCacheStatistics statistics() const {
        SceneCacheStatistics total;
        for (const Entry& e : entries_) add(total, counts_of(e));
        total.texels_read = texels_read_.sum(0);
        total.max_texels_read = max_texels_read_.load(std::memory_order_relaxed);
        total.texel_bytes = texel_bytes();
        total.allocated_bytes = allocated_bytes();
        total.pyramid_bytes = pyramid_bytes();
        return total;
    }

    // Whether the cubes keep what their stores' paths saw, now (SceneCacheSettings::path_records; under
    // PathRecords::from_first_move, from the first move on). While they do not, leaving_ray's plain callback
    // does what the recording one does, without the records nobody keeps. Between frames.
    bool keeps_path_records() const noexcept { return path_records_; }

    // One object's cube counters; std::nullopt when it has none.
    std::optional<CubeStatistics> object_statistics(ObjectId id) const {
        const int index = find(id);
        if (index < 0) return std::nullopt;
        return counts_of(entries_[static_cast<std::size_t>(index)]);
    }

    // f(ObjectId, const CubeBounds&, const CctCube*) for every attached object in attach order; the cube is
    // null for the CDCT. For oracles and tools that read the texels. Between frames.
    template <class F>
    void for_each_cct_cube(F&& f) const {
        for (const Entry& e : entries_) f(e.id, e.bounds, static_cast<const CctCube*>(e.cct.get()));
    }
    // f(ObjectId, const CdctCache*) likewise for the CDCT (null for the CCT); the cache holds the bounds.
    template <class F>
    void for_each_cdct_cache(F&& f) const {
        for (const Entry& e : entries_) f(e.id, static_cast<const CdctCache*>(e.cdct.get()));
    }

    // How far from its cube's centre a ray of object `id` may leave and still be answered: infinity (from
    // anywhere in the box) until an exact scene_changed(), then the furthest origin met before it (see
    // leaving_ray); infinity again after a move that emptied the cube (a moved object's, or every cube at
    // the first move of PathRecords::from_first_move). std::nullopt when it has no cube. Between frames.
    std::optional<float> answered_origin_radius(ObjectId id) const {
        const int index = find(id);
        if (index < 0) return std::nullopt;
        return entries_[static_cast<std::size_t>(index)].origins->limit;
    }

    // Where object `id`'s cube sits; std::nullopt when it has none.
    std::optional<CubeBounds> object_bounds(ObjectId id) const {
        const int index = find(id);
        if (index < 0) return std::nullopt;
        return entries_[static_cast<std::size_t>(index)].bounds;
    }

    // Empties every cube (the objects keep their cubes) and resets the counters.
    void clear() {
        for (Entry& e : entries_) empty_cube(e), e.carried = CubeStatistics{}, e.rest = RestingState{}, e.work = WorkEstimate{};
        texels_read_.reset();
        max_texels_read_.store(0, std::memory_order_relaxed);
    }

    // Writes every cube (its texels, face size and placement, keyed by its object id, and how far out its
    // rays left and it answers, answered_origin_radius()) and `scene`, the
    // caller's identity of the scene, to `path` (raycache/cache_file.hpp): atomically, so a process killed
    // during the save leaves the old file or the new one. Between frames. Throws CacheFileError naming the
    // file and the system's reason when it cannot be written.
    void save(const std::string& path, const SceneIdentity& scene) const {
        if (technique_ == Technique::cct)
            save_cache_file(path, scene, cubes_to_save<CctTexel>());
        else
            save_cache_file(path, scene, cubes_to_save<CdctTexel>());
    }

    // Replaces every cube by the one saved for its object in `path`: texels visible from the next frame,
    // tiles' origin boxes and doubtful marks as saved, depth pyramids rebuilt; adaptive cubes take the face
    // size they were saved with. The file must hold this cache's technique, `scene`, one cube for each
    // attached object and no other, each at the same placement and (for a cube of a fixed face size) of that
    // face size. Otherwise, or when it is truncated, corrupted
    // or of a newer format, throws CacheFileError saying what is wrong, and the cache is left as it was.
    // The file's tiles are allocated before the old cubes give theirs back: the budget must hold both.
    // Between frames.
    void load(const std::string& path, const SceneIdentity& scene) {
        const std::vector<std::uint8_t> bytes = read_whole_file(path);
        if (technique_ == Technique::cct)
            load_cubes<CctTexel>(bytes, path, scene);
        else
            load_cubes<CdctTexel>(bytes, path, scene);
    }

    // Texel memory of all cubes: sum of 6 * N^2 * (4 bytes CCT, 8 bytes CDCT).
    std::size_t texel_bytes() const noexcept {
        std::size_t bytes = 0;
        for (const Entry& e : entries_) bytes += with_cube(e, [](const auto& cube) { return cube.texel_bytes(); });
        return bytes;
    }

    // What the cubes hold now: allocated texel tiles and tile tables (see CacheCube::bytes()).
    std::size_t allocated_bytes() const noexcept {
        std::size_t bytes = 0;
        for (const Entry& e : entries_) bytes += with_cube(e, [](const auto& cube) { return cube.bytes(); });
        return bytes;
    }

    // Memory of the CDCT depth pyramids (about a third of a float per texel).
    std::size_t pyramid_bytes() const noexcept {
        std::size_t bytes = 0;
        for (const Entry& e : entries_) bytes += e.cdct ? e.cdct->pyramid_bytes() : 0;
        return bytes;
    }

private:
    // Empties an entry's cube (and rebuilds its pyramid); the texels it held. Holding nothing that a move
    // was checked for, it may answer rays from anywhere again.
    std::size_t empty_cube(Entry& e) {
        carry_counts(e);
        e.cold = true;
        e.still.resized = true; // its next frame's misses say nothing about whether its rays moved
        e.origins->forget();
        const std::size_t valid = with_cube(e, [](const auto& cube) { return cube.valid_texels(); });
        if (e.cct) e.cct->clear();
        else e.cdct->clear(); // and its pyramid
        return valid;
    }
    // The exact invalidation pass over an entry's cube (make_invalidation_pass()).
    std::unique_ptr<InvalidationPass> invalidation_pass(Entry& e, const SceneChanges& changes) {
        // Every origin stored from or answered so far, within the box's ball (tested at most).
        const float reach = e.origins->restrict_to_seen(box_origin_radius(e.bounds));
        if (!e.cct) return make_invalidation_pass(*e.cdct, reach, changes); // and its pyramid
        const float drift = origin_drift_ >= 0.0f ? origin_drift_ * e.bounds.half_size : -1.0f;
        return make_invalidation_pass(*e.cct, CubeRays{e.bounds, drift, reach}, changes);
    }

    // The entry of `id`: a plain geometry, an (instance, geometry) pair, or else the whole instance; in a
    // geometry split into primitive ranges, the range that holds id.prim_id. -1: none. By reference: every
    // cached ray calls it, and a 12-byte id passed by value is packed on the stack and reloaded in one wider
    // load, which stalls on store forwarding (a sixth of the Embree tracer's leaving-ray code in a profile).
    // Always inlined: as calls, it and CacheCube::record_miss cost each resting ray about 20 instructions.
    RAYCACHE_HOT_FN int find(const ObjectId& id) const noexcept {
        if (id.inst_id == RTC_INVALID_GEOMETRY_ID) return resolve(direct(id.geom_id), id.prim_id);
        const auto it = instanced_.find({id.inst_id, id.geom_id});
        return it != instanced_.end() ? resolve(it->second, id.prim_id) : resolve(direct(id.inst_id), RTC_INVALID_GEOMETRY_ID);
    }
    int direct(unsigned geom_id) const noexcept { return geom_id < direct_.size() ? direct_[geom_id] : -1; }
    // The entry a slot of direct_ or instanced_ names: itself (-1: none), or for a ranged geometry (slot
    // -2 - i, ranged_[i]) the range holding `prim_id`, by binary search.
    int resolve(int slot, unsigned prim_id) const noexcept {
        if (slot >= -1) return slot;
        const std::vector<PrimitiveRange>& ranges = split(slot).ranges;
        const std::size_t after = first_after(ranges, prim_id);
        return after > 0 && prim_id < ranges[after - 1].end ? ranges[after - 1].entry : -1;
    }
    // The split geometry a slot < -1 names.
    const RangedGeometry& split(int slot) const noexcept { return ranged_[static_cast<std::size_t>(-2 - slot)]; }
    // The index of the first of the sorted `ranges` that starts after primitive `prim`.
    static std::size_t first_after(const std::vector<PrimitiveRange>& ranges, unsigned prim) noexcept {
        const auto after = std::upper_bound(ranges.begin(), ranges.end(), prim,
                                            [](unsigned p, const PrimitiveRange& r) { return p < r.first; });
        return static_cast<std::size_t>(after - ranges.begin());
    }
    // The slot of exactly this (instance, geometry), whatever the instance as a whole has; -1 when none.
    int slot_of(ObjectId id) const noexcept {
        if (id.inst_id == RTC_INVALID_GEOMETRY_ID) return direct(id.geom_id);
        const auto it = instanced_.find({id.inst_id, id.geom_id});
        return it != instanced_.end() ? it->second : -1;
    }
    // The slot of this (instance, geometry), made (as -1) when missing.
    int& slot(ObjectId id) {
        if (id.inst_id != RTC_INVALID_GEOMETRY_ID) return instanced_.try_emplace({id.inst_id, id.geom_id}, -1).first->second;
        if (direct_.size() <= id.geom_id) direct_.resize(id.geom_id + std::size_t{1}, -1);
        return direct_[id.geom_id];
    }

    static void check_attachable(ObjectId id, const CubeBounds& bounds) {
        if (id.geom_id == RTC_INVALID_GEOMETRY_ID)
            throw std::invalid_argument("RayCache: cannot attach a cube to RTC_INVALID_GEOMETRY_ID");
        if (!detail::is_usable(bounds))
            throw std::invalid_argument("RayCache: cube bounds need a finite centre and a half-size > 0");
    }

    // A new entry for object `id` with a cube around `bounds` (face_size as in attach()); its index. Throws
    // std::invalid_argument, attaching nothing, when the budget has no room for the cube's fixed part.
    int add_entry(ObjectId id, int face_size, const CubeBounds& bounds) {
        const bool adaptive = face_size == adaptive_face_size;
        if (adaptive) shrink_first_face_size(entries_.size() + 1);
        const int size = adaptive ? first_face_size_ : face_size;
        const std::size_t fixed = is_valid_face_size(size) ? cube_fixed_bytes(size) : 0; // else make_cube throws
        if (fixed > budget_->room())
            throw std::invalid_argument("RayCache: the memory budget (" + std::to_string(budget_->limit()) + " bytes, " +
                                        std::to_string(budget_->used()) + " taken by " + std::to_string(entries_.size()) +
                                        " cubes) has no room for another cube of face size " + std::to_string(size) + " (" +
                                        std::to_string(fixed) + " bytes before any texel); raise SceneCacheSettings::budget_bytes" +
                                        (adaptive ? "" : " or give it fewer texels"));
        Entry entry{id, bounds, nullptr, nullptr, nullptr, false, std::make_unique<OriginReach>()};
        make_cube(entry, size);
        if (adaptive) entry.coverage = std::make_unique<DirectionCoverage>();
        entries_.push_back(std::move(entry));
        return static_cast<int>(entries_.size() - 1);
    }

    // Whether cubes loaded from a cache file keep path records: as the cache's own, or (before the first move
    // of PathRecords::from_first_move) when the file holds any, and then the cache keeps them from then on
    // (load_cubes()): a loaded cube's next move keeps what the saved one's would.
    std::optional<bool> records_to_load() const noexcept {
        if (path_records_) return true; // PathRecords::always included
        if (record_policy_ == PathRecords::never) return false;
        return std::nullopt;
    }

    // The bytes of one of the cubes' tiles.
    std::size_t tile_bytes() const noexcept {
        return technique_ == Technique::cct ? CctCube::tile_bytes(path_records_) : CdctCube::tile_bytes(path_records_);
    }
    // What a cube of `face_size` takes from the budget before any tile (CacheCube::fixed_bytes()), and the
    // bounds the planners use for it (adaptive_resolution.hpp): a tile's share and a cube's.
    std::size_t cube_fixed_bytes(int face_size) const noexcept {
        return technique_ == Technique::cct ? CctCube::fixed_bytes(face_size) : CdctCube::fixed_bytes(face_size);
    }
    static constexpr std::size_t entry_bytes() noexcept { return std::max(CctCube::fixed_bytes_per_tile, CdctCube::fixed_bytes_per_tile); }
    static constexpr std::size_t cube_bytes() noexcept {
        return std::max(CctCube::fixed_bytes_per_cube(), CdctCube::fixed_bytes_per_cube());
    }

    // With `cubes` cubes on the budget, adaptive cubes start at the largest step at which each could fill
    // all its tiles within its share (first_face_size_within), so a cold frame fits however its rays spread.
    // Adaptive cubes that are larger and still empty, never sized by a frame, start over at that size.
    void shrink_first_face_size(std::size_t cubes) {
        const int size = first_face_size_within(adaptive_, cubes, budget_->limit(), tile_bytes(), entry_bytes(), cube_bytes());
        if (size >= first_face_size_) return;
        first_face_size_ = size;
        for (Entry& e : entries_) {
            const bool empty = with_cube(e, [&](const auto& cube) { return cube.face_size() > size && cube.allocated_tiles() == 0; });
            if (e.coverage && !e.sized && empty) make_cube(e, size);
        }
    }

    // The primitive count of `geometry` (in `scene`), asked of Embree once per split geometry.
    unsigned known_primitive_count(RTCScene scene, ObjectId geometry) const {
        const int s = slot_of(geometry);
        return s < -1 ? split(s).primitive_count : primitive_count(scene, geometry.geom_id);
    }

    // attach_primitives() once the geometry's primitive count `total` is known.
    void attach_range(ObjectId geometry, unsigned first_prim, unsigned prim_count, int face_size, const CubeBounds& bounds,
                      unsigned total) {
        detail::check_primitive_range(geometry.geom_id, first_prim, prim_count, total);
        const ObjectId whole{geometry.geom_id, geometry.inst_id};
        if (has_cache(whole))
            throw std::invalid_argument("RayCache: geometry " + std::to_string(geometry.geom_id) +
                                        " already has a cube for all its primitives; a range of it cannot have its own");
        int s = slot_of(whole);
        std::size_t at = 0; // where the new range goes among the geometry's ranges
        if (s < -1) {
            const std::vector<PrimitiveRange>& ranges = split(s).ranges;
            at = first_after(ranges, first_prim);
            const PrimitiveRange* clash = at > 0 && ranges[at - 1].end > first_prim ? &ranges[at - 1]
                                          : at < ranges.size() && ranges[at].first - first_prim < prim_count ? &ranges[at]
                                                                                                              : nullptr;
            if (clash)
                throw std::invalid_argument("RayCache: primitives " + detail::range_text(first_prim, prim_count) +
                                            " of geometry " + std::to_string(geometry.geom_id) + " overlap primitives " +
                                            detail::range_text(clash->first, clash->end - clash->first) +
                                            ", which already have a cube");
        }
        const int index = add_entry(ObjectId{geometry.geom_id, geometry.inst_id, first_prim}, face_size, bounds);
        if (s >= -1) {
            ranged_.push_back(RangedGeometry{total, {}});
            s = slot(whole) = -2 - static_cast<int>(ranged_.size() - 1);
        }
        std::vector<PrimitiveRange>& ranges = ranged_[static_cast<std::size_t>(-2 - s)].ranges;
        ranges.insert(ranges.begin() + static_cast<std::ptrdiff_t>(at), PrimitiveRange{first_prim, first_prim + prim_count, index});
    }

    static SceneCacheSettings make_settings(const ReliefParameters& relief, bool depth_pyramid) {
        SceneCacheSettings s;
        s.relief = relief;
        s.depth_pyramid = depth_pyramid;
        return s;
    }

    // Gives `e` a new, empty cube (and pyramid) of `face_size` drawing on the budget.
    void make_cube(Entry& e, int face_size) {
        if (e.cct || e.cdct) carry_counts(e); // a cube replaced within a frame: its counts stay the frame's
        e.cold = true; // empty (begin_frame() looks again after filling a smaller one from the old)
        e.still.resized = true; // its next frame's misses say nothing about whether its rays moved
        if (technique_ == Technique::cct) {
            e.cct = std::make_unique<CctCube>(face_size, budget_, path_records_);
        } else {
            e.cdct = std::make_unique<CdctCache>(std::make_unique<CdctCube>(face_size, budget_, path_records_), e.bounds, relief_, use_pyramid_);
        }
    }

    // The confidence test over the frame's stores (raycache/edge_confidence.hpp), spread over the caller's
    // threads by bands of tile rows of every cube, not cube by cube: along a walkthrough one object often
    // receives most of the rays (behind-32's front mirror takes seven in eight of the stores), and its cube
    // alone held the other threads up (5 to 13 ms of a 1024 x 1024 frame, on 4 threads as on 16). The budget
    // must be settled first (begin_frame() does).
    template <class ParallelFor>
    void mark_doubtful_edges_of_frame(ParallelFor&& parallel_for, const std::vector<char>& replaced) {
        if (!shared::raycache_edge_test_enabled(edge_threshold_)) return;
        std::vector<std::pair<std::size_t, int>> bands; // (entry, band)
        for (std::size_t i = 0; i < entries_.size(); ++i) {
            if (replaced[i]) continue;
            const int count = with_cube(entries_[i], [](const auto& cube) { return cube.tile_bands(); });
            for (int b = 0; b < count; ++b) bands.emplace_back(i, b);
        }
        const std::function<void(std::size_t)> mark = [&](std::size_t k) {
            const std::size_t i = bands[k].first; // not a structured binding: C++17 lambdas cannot capture one
            const int band = bands[k].second;
            with_cube(entries_[i], [&](auto& cube) { mark_doubtful_edges_in_bands(cube, edge_threshold_, band, band + 1); });
        };
        parallel_for(bands.size(), mark);
    }

    // An adaptive entry's new face size after a frame.
    struct Resize {
        std::size_t entry;
        int face_size;
    };
    // The face sizes the adaptive entries' rays of this frame (their cubes' lookups so far) call for, for
    // the entries whose size changes. Choosing them is cheap and serial; the frame must have ended (no
    // lookups after this). Resets the entries' direction coverage.
    std::vector<Resize> plan_resizes() {
        std::vector<Resize> resizes;
        // What the budget has room for: the still rule's finer faces take no more (largest_face_size_within).
        std::size_t room = budget_->room();
        for (std::size_t i = 0; i < entries_.size(); ++i) {
            Entry& e = entries_[i];
            if (!e.coverage) continue;
            if (e.rest.resting) { // its coverage holds the probes' cells alone; the size it had stays
                e.coverage->reset();
                e.still.settled_frames = 0;
                continue;
            }
            const int current = with_cube(e, [](const auto& cube) { return cube.face_size(); });
            const CubeStatistics frame = counts_of(e);
            const std::uint64_t rays = frame.lookups;
            const double covered = e.coverage->fraction();
            const int adapted = adapted_face_size(current, e.sized, rays, covered, adaptive_);
            int next = face_size_with_still_rule(current, adapted, e.sized, frame, covered, e.still, adaptive_);
            if (next > current) { // within the room, its own bytes freed: a larger cube's fixed part, and finer faces
                                  // for still rays the tiles those rays reach too
                const std::size_t held = with_cube(e, [](const auto& cube) { return cube.bytes(); });
                const std::size_t available = room > SIZE_MAX - held ? SIZE_MAX : room + held; // no limit: SIZE_MAX
                const double filled = next > adapted ? covered : 0.0;
                next = largest_face_size_within(current, next, filled, available, tile_bytes(), entry_bytes(), cube_bytes());
                if (next > current && available != SIZE_MAX) { // what the larger cube takes is no room for the next
                    const std::size_t taken = rays_cube_bytes(next, filled, tile_bytes(), entry_bytes(), cube_bytes());
                    room = available > taken ? available - taken : 0;
                }
            }
            e.sized = e.sized || rays > 0;
            e.coverage->reset();
            if (next != current) resizes.push_back(Resize{i, next}); // make_cube() marks it resized
        }
        return resizes;
    }

    // The hit rate below which entry `e` rests next frame (raycache/resting.hpp), from the work its texels'
    // rays reported over the frames so far.
    float resting_threshold_of(const Entry& e) const noexcept {
        if (!(min_hit_rate_ > 0.0f)) return 0.0f; // never resting
        return threshold_from_work_ ? resting_threshold(e.work.work, e.work.reports, lookup_work_, min_hit_rate_) : min_hit_rate_;
    }

    // Gives each entry of `resizes` (plan_resizes()) its new cube: a smaller one filled from the old (resampling,
    // records, confidence test, pyramid), a larger one empty. The resizes run on the caller's threads when the
    // budget has room for every new cube with all its tiles allocated: then no allocation can be refused,
    // whatever the order, and the result is the serial one. Otherwise one after the other in attach order,
    // so which allocation a full budget refuses does not depend on timing. Returns how many cubes changed size.
    template <class ParallelFor>
    std::size_t adapt(const std::vector<Resize>& resizes, ParallelFor&& parallel_for) {
        const std::size_t tile = tile_bytes();
        std::size_t worst = 0; // bytes, if every smaller new cube filled all its tiles (a larger one starts empty)
        for (const Resize& r : resizes) {
            const int current = with_cube(entries_[r.entry], [](const auto& cube) { return cube.face_size(); });
            worst += full_cube_bytes(r.face_size, r.face_size < current ? tile : 0, entry_bytes(), cube_bytes());
        }
        const std::function<void(std::size_t)> resize = [&](std::size_t k) { resize_entry(entries_[resizes[k].entry], resizes[k].face_size); };
        if (worst <= budget_->room()) { // (every resize's worst case is more than 0 bytes: its fixed part)
            parallel_for(resizes.size(), resize);
        } else {
            for (std::size_t k = 0; k < resizes.size(); ++k) resize(k);
        }
        return resizes.size();
    }

    // Gives adaptive entry `e` a cube of `face_size`: a smaller one filled from the old one, a larger one
    // empty. Between frames; entries may be resized on different threads at once.
    void resize_entry(Entry& e, int face_size) {
        const int current = with_cube(e, [](const auto& cube) { return cube.face_size(); });
        Entry old{e.id, e.bounds, std::move(e.cct), std::move(e.cdct), nullptr, false, nullptr};
        make_cube(e, face_size);
        if (face_size < current) {
            if (technique_ == Technique::cct) {
                resample_into(*old.cct, *e.cct);
                carry_path_records(*old.cct, *e.cct); // so exact invalidation still knows what they saw
            } else {
                resample_into(old.cdct->cube(), e.cdct->cube());
                carry_path_records(old.cdct->cube(), e.cdct->cube());
            }
            with_cube(e, [&](auto& cube) { mark_doubtful_edges(cube, edge_threshold_); });
            with_cube(e, [](auto& cube) { cube.begin_frame(); }); // the resampled texels are visible next frame
            if (e.cdct) e.cdct->rebuild_pyramid();
        }
    }

    // An entry's key in a cache file: object = instance id << 32 | geometry id; part = 0 for a whole
    // geometry or instance, first primitive << 32 | primitive count for a range (attach_primitives).
    using FileKey = std::pair<std::uint64_t, std::uint64_t>;
    FileKey file_key(const Entry& e) const {
        std::uint64_t part = 0;
        if (e.id.prim_id != RTC_INVALID_GEOMETRY_ID) {
            const std::vector<PrimitiveRange>& ranges = split(slot_of(e.id)).ranges;
            const PrimitiveRange& r = ranges[first_after(ranges, e.id.prim_id) - 1];
            part = std::uint64_t{r.first} << 32 | (r.end - r.first);
        }
        return {std::uint64_t{e.id.inst_id} << 32 | e.id.geom_id, part};
    }
    // "geometry 3", "geometry 1 of instance 5", "primitives 10..19 of geometry 2".
    static std::string key_text(const FileKey& key) {
        const auto geometry = static_cast<unsigned>(key.first & 0xFFFFFFFFu), instance = static_cast<unsigned>(key.first >> 32);
        std::string text = "geometry " + std::to_string(geometry);
        if (instance != RTC_INVALID_GEOMETRY_ID) text += " of instance " + std::to_string(instance);
        if (key.second)
            text = "primitives " + detail::range_text(static_cast<unsigned>(key.second >> 32), static_cast<unsigned>(key.second)) +
                   " of " + text;
        return text;
    }

    // The entry's cube of technique Texel.
    static const CctCube* cube_of(const Entry& e, CctTexel) { return e.cct.get(); }
    static const CdctCube* cube_of(const Entry& e, CdctTexel) { return &e.cdct->cube(); }

    template <class Texel>
    std::vector<CubeToSave<Texel>> cubes_to_save() const {
        std::vector<CubeToSave<Texel>> cubes;
        for (const Entry& e : entries_) {
            const FileKey key = file_key(e);
            cubes.push_back(CubeToSave<Texel>{key.first, e.bounds, cube_of(e, Texel{}), key.second,
                                              e.origins->seen.load(std::memory_order_relaxed), e.origins->limit});
        }
        return cubes;
    }

    // load(): the file's cubes, matched to the entries and checked, then swapped in all at once.
    template <class Texel>
    void load_cubes(const std::vector<std::uint8_t>& bytes, const std::string& path, const SceneIdentity& scene) {
        const std::string source = "cache file '" + path + "'";
        std::vector<LoadedCube<Texel>> loaded = decode_cache<Texel>(bytes.data(), bytes.size(), scene, budget_, source, records_to_load());
        auto fail = [&](const std::string& what) {
            throw CacheFileError("RayCache: " + source + ": " + what + "; nothing was loaded");
        };
        std::map<FileKey, std::size_t> by_key;
        for (std::size_t i = 0; i < loaded.size(); ++i) by_key[{loaded[i].object, loaded[i].part}] = i;
        std::vector<std::size_t> source_of(entries_.size());
        for (std::size_t i = 0; i < entries_.size(); ++i) {
            const Entry& e = entries_[i];
            const std::string object = key_text(file_key(e));
            const auto it = by_key.find(file_key(e));
            if (it == by_key.end()) fail(object + " has a cube here but none in the file");
            const LoadedCube<Texel>& c = loaded[it->second];
            if (!same_placement(c.bounds, e.bounds))
                fail(object + "'s cube sits at " + raycache::describe(e.bounds) + ", in the file at " + raycache::describe(c.bounds));
            const int here = cube_of(e, Texel{})->face_size();
            if (!e.coverage && c.cube->face_size() != here)
                fail(object + "'s cube has " + std::to_string(here) + "-texel faces (fixed), in the file " +
                     std::to_string(c.cube->face_size()));
            source_of[i] = it->second;
            by_key.erase(it);
        }
        if (!by_key.empty())
            fail("the file has a cube for " + key_text(by_key.begin()->first) + ", which has none here (" +
                 std::to_string(by_key.size()) + " such cubes)");
        // The texels become visible (their tiles' origin boxes and doubtful marks came with them); a CDCT
        // cube goes into a new CdctCache, which rebuilds its depth pyramid from the texels.
        std::vector<std::unique_ptr<CdctCache>> caches(entries_.size());
        for (std::size_t i = 0; i < entries_.size(); ++i) {
            loaded[source_of[i]].cube->begin_frame();
            if constexpr (std::is_same_v<Texel, CdctTexel>)
                caches[i] = std::make_unique<CdctCache>(std::move(loaded[source_of[i]].cube), entries_[i].bounds, relief_,
                                                        use_pyramid_);
        }
        // Nothing below throws: every entry takes its new cube, or none does.
        for (std::size_t i = 0; i < entries_.size(); ++i) {
            Entry& e = entries_[i];
            if constexpr (std::is_same_v<Texel, CdctTexel>)
                e.cdct = std::move(caches[i]);
            else
                e.cct = std::move(loaded[source_of[i]].cube);
            if (e.coverage) e.coverage->reset();
            // Where the saved cube's rays left from, and how far out it answered: its texels were checked by
            // exact invalidation for rays from within that limit alone (files before format 3: no limit, and
            // the rays' origins not known, so the next move tests from the box's ball).
            const LoadedCube<Texel>& c = loaded[source_of[i]];
            e.origins->restore(c.origins_seen, c.origins_limit);
            // A cube that holds texels received rays, so its face size came from counting them: later
            // moves take the hysteresis, as in the cache that saved it (the file keeps no flag for that).
            e.sized = with_cube(e, [](const auto& cube) { return cube.valid_texels() > 0; });
            // A file holds texels, not whether a cube rests: a loaded cube works, and its next frame decides
            // unless it starts empty (as after begin_frame()).
            e.rest = RestingState{};
            e.cold = !e.sized;
            // A file with path records makes the cache keep them from now on (records_to_load()).
            path_records_ = path_records_ || with_cube(e, [](const auto& cube) { return cube.keeps_path_records(); });
        }
    }

    // A cube's counters with those its entry carried over from cubes replaced this frame.
    static CubeStatistics counts_of(const Entry& e) {
        CubeStatistics s = with_cube(e, [](const auto& cube) { return cube.statistics(); });
        add_counts(s, e.carried);
        return s;
    }
    // Adds the counters (not the texel counts) of `from` to `to`, a CubeStatistics or SceneCacheStatistics.
    template <class Totals>
    static void add_counts(Totals& to, const CubeStatistics& from) {
        to.lookups += from.lookups;
        to.hits += from.hits;
        to.misses += from.misses;
        for (std::size_t k = 0; k < miss_reason_count; ++k) to.misses_by[k] += from.misses_by[k];
        to.stores += from.stores;
        to.filled_work += from.filled_work;
        to.work_reports += from.work_reports;
        if constexpr (std::is_same_v<Totals, CubeStatistics>) to.refused_stores += from.refused_stores;
    }
    void carry_counts(Entry& e) { add_counts(e.carried, with_cube(e, [](const auto& cube) { return cube.statistics(); })); }

    static void add(SceneCacheStatistics& total, const CubeStatistics& s) {
        add_counts(total, s);
        total.valid_texels += s.valid_texels;
        total.texel_count += s.texel_count;
    }

    Technique technique_;
    ReliefParameters relief_;
    bool use_pyramid_;
    AdaptiveResolution adaptive_;
    bool filtered_;
    float edge_threshold_;
    float origin_drift_;
    float origin_parallax_;
    bool path_records_;          // the cubes keep path records now (SceneCacheSettings::path_records)
    PathRecords record_policy_;
    bool transitive_by_direction_;
    bool trace_hits_;            // SceneCacheSettings::trace_hits
    float min_hit_rate_;         // SceneCacheSettings::min_hit_rate, or the technique's default
    bool threshold_from_work_;   // min_hit_rate unset: each cube's threshold from its rays' work where reported
    float lookup_work_;          // SceneCacheSettings::lookup_work
    std::shared_ptr<MemoryBudget> budget_; // shared with every cube
    int first_face_size_;                  // adaptive cubes start here (shrink_first_face_size)
    std::vector<Entry> entries_;
    // Slots: an entry (>= 0), none (-1), or a geometry split into primitive ranges (-2 - its index in ranged_).
    std::vector<int> direct_;                                // geom_id -> slot, objects not instanced
    std::map<std::pair<unsigned, unsigned>, int> instanced_; // (inst_id, geom_id) -> slot
    std::vector<RangedGeometry> ranged_;
    detail::StripedCounters<1> texels_read_;
    std::atomic<std::uint64_t> max_texels_read_{0};
};

} // namespace embree
} // namespace raycache
