// How far from a cube's centre SceneCache answers rays, on real Embree scenes: anywhere in the box until
// exact invalidation, then only as far out as the object's rays left (2% more), which lets a move keep
// texels that only rays from the box's corners could have seen changed.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <cstdint>
#include <limits>
#include <vector>

#include <unistd.h>

#include <raycache/embree/scene_cache.hpp>

#include "embree_spheres.hpp"

using raycache::PathRecord;
using raycache::TracedRay;
using raycache::embree::Invalidation;
using raycache::embree::ObjectId;
using raycache::embree::PathRecords;
using raycache::embree::SceneCache;
using raycache::embree::SceneCacheSettings;
using raycache::embree::Technique;

namespace {

const float infinity = std::numeric_limits<float>::infinity();

// A mirror sphere of radius 1 at the origin and a small ball that moves.
using World = MirrorAndBall;

// CCT caches keyed by direction alone (no origin test), so only the origin reach decides what answers;
// path records kept from the first store (a scene that moves), unless told otherwise.
SceneCache direction_keyed_cct(PathRecords records = PathRecords::always) {
    SceneCacheSettings s;
    s.origin_drift = -1.0f;
    s.edge_threshold = -1.0f;
    s.path_records = records;
    return SceneCache(Technique::cct, s);
}

// A move of the small ball that no stored ray comes near.
raycache::embree::SceneChange far_move(const World& w) {
    raycache::embree::SceneChange change;
    change.moved.push_back({ObjectId{w.ball}, {glm::vec3(-6, 0, 0), 0.2f}, {glm::vec3(-6, 0, 1), 0.2f}, std::nullopt});
    return change;
}

} // namespace

TEST_CASE("a cube answers rays from anywhere in its box until an exact move, then only from as far out as its rays left") {
    World w;
    SceneCache caches = direction_keyed_cct();
    caches.attach(w.scene, {w.mirror}, 64);
    int traces = 0;
    const glm::vec3 colour(0.25f, 0.5f, 0.75f);
    // Straight up, escaping: the path hits nothing (a recording trace, so invalidation can keep the texel).
    auto up_from = [&](glm::vec3 origin) {
        return caches.leaving_ray({w.mirror}, origin, glm::vec3(0, 1, 0), [&](PathRecord&) {
            ++traces;
            return TracedRay{colour, infinity};
        });
    };
    const glm::vec3 top(0.0f, 1.01f, 0.0f), corner(0.7f, 0.7f, 0.7f); // 1.01 and 1.21 from the centre
    up_from(top);
    caches.begin_frame();
    CHECK(*caches.answered_origin_radius({w.mirror}) == infinity);
    up_from(top);
    CHECK(traces == 1); // answered
    caches.begin_frame();

    const auto moved = caches.scene_changed(far_move(w), Invalidation::exact);
    CHECK(moved.dropped == 0);
    CHECK(*caches.answered_origin_radius({w.mirror}) == doctest::Approx(1.01f * 1.02f));
    CHECK_FALSE(caches.answered_origin_radius({w.ball}).has_value()); // no cube

    CHECK(up_from(top) == colour); // answered from the cube (RGB9E5 holds these three exactly)
    CHECK(traces == 1);
    CHECK(up_from(corner) == colour); // from further out: traced, its value returned unchanged
    CHECK(traces == 2);
    const auto frame = caches.begin_frame();
    CHECK(frame.lookups == 2);
    CHECK(frame.hits == 1);
    CHECK(frame.stores == 0); // a ray from outside the reach is not stored either
    CHECK(frame.emptied_for_origins == 1); // so the cube starts afresh, answering rays from anywhere
    CHECK(frame.valid_texels == 0);
    CHECK(*caches.answered_origin_radius({w.mirror}) == infinity);

    // Filled again, it answers the corner's ray; the next move limits it to the corner's distance.
    up_from(corner);
    caches.begin_frame();
    up_from(corner);
    CHECK(traces == 3);
    caches.begin_frame();
    caches.scene_changed(far_move(w), Invalidation::exact);
    CHECK(*caches.answered_origin_radius({w.mirror}) == doctest::Approx(glm::length(corner) * 1.02f));
}

TEST_CASE("a move that only rays from the box's corners could see keeps the texel once the cube knows its rays leave its sphere") {
    // The texel straight up from the mirror (column and row 32 of the +y face at 64 texels: directions
    // within 0.025 rad of its axis, tilted 0.022 rad towards +x and +z). The ball moves to (1.6, 3, 0),
    // radius 0.2, 0.474 rad off that axis. Rays from a ball of radius R around the centre meet it only if
    // rays from the centre meet it grown by R: within asin((0.2 + R) / 3.4) of its direction. From the
    // mirror's own rays (R = 1.01 x 1.02, + 0.1% + 0.002 of margin: 1.035) that is 0.372 rad, short of 0.474
    // - 0.025; from the box's ball (R = 1.735) 0.605 rad, which holds the texel's axis.
    World w;
    SceneCache caches = direction_keyed_cct();
    caches.attach(w.scene, {w.mirror}, 64);
    auto up = [&] {
        return caches.leaving_ray({w.mirror}, glm::vec3(0.0f, 1.01f, 0.0f), glm::vec3(0, 1, 0),
                                  [&](PathRecord&) { return TracedRay{glm::vec3(0.5f), infinity}; });
    };
    up();
    caches.begin_frame();
    REQUIRE(caches.statistics().valid_texels == 1);
    raycache::embree::SceneChange change;
    change.moved.push_back({ObjectId{w.ball}, {glm::vec3(-6, 0, 0), 0.2f}, {glm::vec3(1.6f, 3.0f, 0.0f), 0.2f}, std::nullopt});
    const auto kept = caches.scene_changed(change, Invalidation::exact);
    CHECK(kept.dropped == 0);
    // Moved on to (0.6, 3, 0), 0.197 rad off the axis: met from the mirror's ball too (within 0.372).
    raycache::embree::SceneChange closer;
    closer.moved.push_back({ObjectId{w.ball}, {glm::vec3(1.6f, 3.0f, 0.0f), 0.2f}, {glm::vec3(0.6f, 3.0f, 0.0f), 0.2f}, std::nullopt});
    const auto dropped = caches.scene_changed(closer, Invalidation::exact);
    CHECK(dropped.dropped == 1);
    CHECK(dropped.dropped_by_cone == 1);
}

TEST_CASE("CDCT: a texel's segments start from the mirror's own rays once a move limits them, not from the box's corners") {
    // The texel straight up holds a surface 4 above the mirror's top (5.01 from the centre). Its segments
    // run from the ball of origins to the shell of its directions at 5.01 -+ 0.5 (the search's max_gap),
    // within 0.52 of the y axis. At y = 2 the hull of the two balls lies within 1.035 - (1.035 - 0.52) x 2 /
    // 5 = 0.83 of the axis for the mirror's own rays, within 1.735 - (1.735 - 0.52) x 2 / 5 = 1.25 for the
    // box's ball. A ball of radius 0.12 at (1.1, 2, 0) spans 0.98 .. 1.22 from the axis: kept. One of
    // radius 0.2 at (0.3, 2.5, 0), on the segment from the mirror's top to the surface: dropped.
    World w;
    const std::uint64_t surface = raycache::embree::path_key(ObjectId{w.ball}) + 1000; // what the stored ray hit
    const std::uint64_t mover = raycache::embree::path_key(ObjectId{w.ball});
    REQUIRE((raycache::object_bits(surface) & raycache::object_bits(mover)) != raycache::object_bits(mover)); // no Bloom alias
    SceneCacheSettings s;
    s.edge_threshold = -1.0f;
    s.relief.max_gap = 0.5f;
    s.path_records = PathRecords::always;
    SceneCache caches(Technique::cdct, s);
    caches.attach(w.scene, {w.mirror}, 64);
    auto up = [&] {
        return caches.leaving_ray({w.mirror}, glm::vec3(0.0f, 1.01f, 0.0f), glm::vec3(0, 1, 0),
                                  [&](PathRecord& path) {
                                      path.hit(surface, glm::vec3(0.0f, 5.01f, 0.0f));
                                      return TracedRay{glm::vec3(0.5f), 4.0f};
                                  });
    };
    up();
    caches.begin_frame();
    REQUIRE(caches.statistics().valid_texels == 1);
    auto move_to = [&](glm::vec3 from, glm::vec3 to, float radius) {
        raycache::embree::SceneChange change;
        change.moved.push_back({ObjectId{w.ball}, {from, radius}, {to, radius}, std::nullopt});
        return caches.scene_changed(change, Invalidation::exact).dropped;
    };
    CHECK(move_to({-6, 0, 0}, {1.1f, 2.0f, 0.0f}, 0.12f) == 0);
    CHECK(*caches.answered_origin_radius({w.mirror}) == doctest::Approx(1.01f * 1.02f));
    CHECK(move_to({1.1f, 2.0f, 0.0f}, {0.3f, 2.5f, 0.0f}, 0.2f) == 1);
}

TEST_CASE("a saved cube keeps its limit: loaded into a fresh cache, it still traces rays from outside what a move checked") {
    World w;
    const std::string path = "/tmp/raycache-origin-reach-" + std::to_string(::getpid()) + ".rcc";
    const raycache::SceneIdentity scene{42, "origin reach"};
    auto up_from = [&](SceneCache& caches, glm::vec3 origin, int& traces) {
        return caches.leaving_ray({w.mirror}, origin, glm::vec3(0, 1, 0), [&](PathRecord&) {
            ++traces;
            return TracedRay{glm::vec3(0.5f), infinity};
        });
    };
    int traces = 0;
    SceneCache saved = direction_keyed_cct();
    saved.attach(w.scene, {w.mirror}, 64);
    up_from(saved, glm::vec3(0.0f, 1.01f, 0.0f), traces);
    saved.begin_frame();
    saved.scene_changed(far_move(w), Invalidation::exact);
    const float limit = *saved.answered_origin_radius({w.mirror});
    REQUIRE(limit == doctest::Approx(1.01f * 1.02f));
    saved.save(path, scene);

    SceneCache loaded = direction_keyed_cct();
    loaded.attach(w.scene, {w.mirror}, 64);
    loaded.load(path, scene);
    std::remove(path.c_str());
    CHECK(*loaded.answered_origin_radius({w.mirror}) == limit);
    up_from(loaded, glm::vec3(0.0f, 1.01f, 0.0f), traces);
    CHECK(traces == 1); // answered from the loaded texel
    up_from(loaded, glm::vec3(0.7f, 0.7f, 0.7f), traces);
    CHECK(traces == 2); // from further out than the move was checked for: traced, as in the saved cache
}

TEST_CASE("an emptied cube forgets how far out its rays left, the limit never exceeds the box's ball") {
    World w;
    SceneCache caches = direction_keyed_cct();
    caches.attach(w.scene, {w.mirror}, 64);
    auto up_from = [&](glm::vec3 origin) {
        return caches.leaving_ray({w.mirror}, origin, glm::vec3(0, 1, 0),
                                  [&](PathRecord&) { return TracedRay{glm::vec3(0.5f), infinity}; });
    };
    // A ray from far outside the box (5 from the centre; the box's ball reaches 1.73): the limit stops at
    // the ball exact invalidation tests at most, box_origin_radius().
    up_from(glm::vec3(0.0f, 5.0f, 0.0f));
    caches.begin_frame();
    caches.scene_changed(far_move(w), Invalidation::exact);
    const float box = raycache::box_origin_radius(raycache::CubeBounds{glm::vec3(0.0f), 1.0f});
    CHECK(box == doctest::Approx(1.7320508f * 1.001f + 0.002f));
    CHECK(*caches.answered_origin_radius({w.mirror}) == box);
    up_from(glm::vec3(0.0f, 5.0f, 0.0f)); // outside it: traced, and the cube starts afresh
    CHECK(caches.begin_frame().emptied_for_origins == 1);
    // Emptied, it forgot the ray from 5 out: filled from 1.01, the next move limits it to 1.01 x 1.02.
    up_from(glm::vec3(0.0f, 1.01f, 0.0f));
    caches.begin_frame();
    caches.scene_changed(far_move(w), Invalidation::exact);
    CHECK(*caches.answered_origin_radius({w.mirror}) == doctest::Approx(1.01f * 1.02f));
    // clear() forgets too.
    caches.clear();
    CHECK(*caches.answered_origin_radius({w.mirror}) == infinity);
}

TEST_CASE("a scene cache without path records charges smaller tiles, and its exact invalidation drops what a recording one keeps") {
    // The same recorded store, far from the move, with path records (kept) and without (dropped as a store
    // without a record); each cache's one tile costs CctCube::tile_bytes(path_records), beside the same
    // tile table.
    World w;
    std::size_t bytes[2] = {};
    for (const bool records : {true, false}) {
        CAPTURE(records);
        SceneCacheSettings s;
        s.origin_drift = -1.0f;
        s.edge_threshold = -1.0f;
        s.path_records = records ? PathRecords::always : PathRecords::never;
        SceneCache caches(Technique::cct, s);
        caches.attach(w.scene, {w.mirror}, 64);
        caches.leaving_ray({w.mirror}, glm::vec3(0.0f, 1.01f, 0.0f), glm::vec3(0, 1, 0),
                           [&](PathRecord&) { return TracedRay{glm::vec3(0.5f), infinity}; });
        const auto frame = caches.begin_frame();
        bytes[records] = frame.allocated_bytes;
        const auto moved = caches.scene_changed(far_move(w), Invalidation::exact);
        CHECK(moved.dropped == (records ? 0u : 1u));
        CHECK(moved.dropped_unrecorded == (records ? 0u : 1u));
    }
    CHECK(bytes[true] - bytes[false] == raycache::CctCube::tile_bytes(true) - raycache::CctCube::tile_bytes(false));
    CHECK(raycache::CctCube::tile_bytes(true) - raycache::CctCube::tile_bytes(false) == 5832u); // 64 block records of 72 bytes, 16 group unions and the tile's
}

TEST_CASE("by default a scene cache keeps path records from its first exact move on, which empties its cubes once") {
    World w;
    SceneCache caches = direction_keyed_cct(PathRecords::from_first_move); // the default
    caches.attach(w.scene, {w.mirror}, 64);
    auto store_up = [&] {
        caches.leaving_ray({w.mirror}, glm::vec3(0.0f, 1.01f, 0.0f), glm::vec3(0, 1, 0),
                           [&](PathRecord&) { return TracedRay{glm::vec3(0.5f), infinity}; });
        return caches.begin_frame();
    };
    const std::size_t before = store_up().allocated_bytes; // one tile without records
    // Policies other than exact, and an exact call that moves nothing, keep the cubes as they are.
    caches.scene_changed({}, Invalidation::exact);
    CHECK(caches.begin_frame().allocated_bytes == before);
    // The first move: the record-less texel goes (far as the move is), and the cube is replaced, empty.
    const auto first = caches.scene_changed(far_move(w), Invalidation::exact);
    CHECK(first.dropped == 1u);
    CHECK(first.dropped_unrecorded == 1u);
    CHECK(caches.begin_frame().valid_texels == 0u);
    // From then on the stores keep records: the same far move keeps the texel, whose tile holds them.
    const std::size_t after = store_up().allocated_bytes;
    CHECK(after - before == raycache::CctCube::tile_bytes(true) - raycache::CctCube::tile_bytes(false));
    const auto second = caches.scene_changed(far_move(w), Invalidation::exact);
    CHECK(second.dropped == 0u);
    CHECK(caches.begin_frame().valid_texels == 1u);
}

TEST_CASE("by default a cache loads a file's path records when it holds any, and keeps records from then on") {
    // A default cache after its first move (records kept) saves a texel; a fresh default cache loads it and
    // keeps it through a far move, as the saving cache would. A default cache that never moved saves a file
    // without records, which loads into record-less tiles.
    World w;
    const raycache::SceneIdentity scene{43, "records in files"};
    const std::string moved_file = "/tmp/raycache-records-moved-" + std::to_string(::getpid()) + ".rcc";
    const std::string static_file = "/tmp/raycache-records-static-" + std::to_string(::getpid()) + ".rcc";
    auto store_up = [&](SceneCache& caches) {
        caches.leaving_ray({w.mirror}, glm::vec3(0.0f, 1.01f, 0.0f), glm::vec3(0, 1, 0),
                           [&](PathRecord&) { return TracedRay{glm::vec3(0.5f), infinity}; });
        return caches.begin_frame();
    };
    SceneCache moved = direction_keyed_cct(PathRecords::from_first_move);
    moved.attach(w.scene, {w.mirror}, 64);
    moved.scene_changed(far_move(w), Invalidation::exact); // the first move: records from now on
    store_up(moved);
    moved.save(moved_file, scene);
    SceneCache still = direction_keyed_cct(PathRecords::from_first_move);
    still.attach(w.scene, {w.mirror}, 64);
    const std::size_t static_bytes = store_up(still).allocated_bytes;
    still.save(static_file, scene);

    SceneCache loaded = direction_keyed_cct(PathRecords::from_first_move);
    loaded.attach(w.scene, {w.mirror}, 64);
    loaded.load(moved_file, scene);
    CHECK(moved.scene_changed(far_move(w), Invalidation::exact).dropped == 0u);
    const auto after_load = loaded.scene_changed(far_move(w), Invalidation::exact);
    CHECK(after_load.dropped == 0u);
    CHECK(loaded.begin_frame().valid_texels == 1u);

    SceneCache loaded_static = direction_keyed_cct(PathRecords::from_first_move);
    loaded_static.attach(w.scene, {w.mirror}, 64);
    loaded_static.load(static_file, scene);
    CHECK(loaded_static.begin_frame().allocated_bytes == static_bytes); // no records allocated
    std::remove(moved_file.c_str());
    std::remove(static_file.c_str());
}

TEST_CASE("a moved light is a first move too, afterwards unsized adaptive cubes start where tiles with records fit the budget") {
    // As the adapter's budget test derives by hand, with t = tile + table entry: a budget of 1100 t lets one
    // cube start at 181 texels (6 x 12^2 = 864 t), not 256 (1536 t). With 1288-byte t (no records) that is
    // 181; once records are kept (7120-byte t), the same bytes hold 198 of them: 64 (6 x 4^2 = 96 t) and
    // not 91 (216 t).
    World w;
    const std::size_t alone = raycache::CctCube::tile_bytes(false) + sizeof(void*);
    SceneCacheSettings s;
    s.budget_bytes = 1100 * alone;
    SceneCache caches(Technique::cct, s);
    caches.attach(w.scene, {w.mirror}); // adaptive
    CHECK(caches.face_size({w.mirror}) == 181);
    raycache::embree::SceneChange light;
    light.light_moved = true;
    light.lights = {glm::vec3(0.0f, 10.0f, 0.0f)};
    caches.scene_changed(light, Invalidation::exact);
    CHECK(caches.face_size({w.mirror}) == 64);
    // The cube keeps records now: a far move keeps what it stores.
    caches.leaving_ray({w.mirror}, glm::vec3(0.0f, 1.01f, 0.0f), glm::vec3(0, 1, 0),
                       [&](PathRecord&) { return TracedRay{glm::vec3(0.5f), infinity}; });
    caches.begin_frame();
    CHECK(caches.scene_changed(far_move(w), Invalidation::exact).dropped == 0u);
}
