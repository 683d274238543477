// Resting cubes in SceneCache (raycache/resting.hpp), on a real Embree scene: a cube that answers too few of
// its rays lets them through the next frame, but for its probe directions, and works again once those hit.
#include <doctest/doctest.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>

#include <raycache/embree/scene_cache.hpp>

#include "embree_spheres.hpp"
#include "test_cache_files.hpp"

using raycache::MissReason;
using raycache::TracedRay;
using raycache::embree::SceneCache;
using raycache::embree::SceneCacheSettings;
using raycache::embree::SceneCacheStatistics;
using raycache::embree::Technique;

namespace {

// One ray through each texel centre of a 16-texel face (one texel of the test's cubes each).
std::vector<glm::vec3> cell_directions() {
    std::vector<glm::vec3> directions;
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < 16; ++row)
            for (int column = 0; column < 16; ++column)
                directions.push_back(glm::normalize(raycache::texel_direction(raycache::TexelAddress{face, column, row}, 16)));
    return directions;
}

// Those of them that probe a resting cube, by the rule written out here: the top 12 bits of each
// component's float, hashed (multiply by 2654435761, xor the next), probe when the hash's top four bits are 0.
std::size_t probe_count() {
    std::size_t n = 0;
    for (const glm::vec3& d : cell_directions()) {
        std::uint32_t hash = 0;
        for (int k = 0; k < 3; ++k) {
            std::uint32_t bits;
            std::memcpy(&bits, &d[k], sizeof bits);
            hash = (hash ^ (bits >> 20)) * 2654435761u;
        }
        n += hash >> 28 == 0 ? 1 : 0;
    }
    return n;
}

std::uint64_t rested(const SceneCacheStatistics& s) { return s.misses_by[static_cast<std::size_t>(MissReason::resting)]; }

// One frame of SceneCache `caches` (the cube of geometry `object`): every direction leaves from `origin`;
// returns the frame's statistics and counts the rays traced into `traced`.
SceneCacheStatistics frame(SceneCache& caches, unsigned object, glm::vec3 origin, int& traced) {
    for (const glm::vec3& d : cell_directions())
        caches.leaving_ray({object}, origin, d, [&] {
            ++traced;
            return TracedRay{0.5f + 0.5f * d, 10.0f};
        });
    return caches.begin_frame();
}

SceneCache resting_caches(float min_hit_rate) {
    SceneCacheSettings s;
    s.edge_threshold = -1.0f; // every texel answers: the hit rates below are the origin test's alone
    s.min_hit_rate = min_hit_rate;
    return SceneCache(Technique::cct, s);
}

// A mirror whose cube (16-texel faces: one texel a direction cell) saw one cold frame from the top.
struct WarmMirror {
    MirrorAndBall world; // the mirror's cube: centre 0, half-size 1
    SceneCache caches;
    int traced = 0;
    explicit WarmMirror(float min_hit_rate) : caches(resting_caches(min_hit_rate)) {
        caches.attach(world.scene, {world.mirror}, 16);
        from(glm::vec3(0, 1, 0));
    }
    // The next frame, every direction leaving from `origin`.
    SceneCacheStatistics from(glm::vec3 origin) { return frame(caches, world.mirror, origin, traced); }
};

// A mirror's cube (16-texel faces, every texel answering) at the default thresholds, whose traced rays
// each report 4 rays of work: its threshold from work is 1 / 4, where a frame without reports would fall
// back to the fixed 0.5.
struct MirrorReportingWork {
    MirrorAndBall world;
    SceneCache caches;
    const glm::vec3 top{0.0f, 1.0f, 0.0f}, side{1.0f, 0.0f, 0.0f};
    MirrorReportingWork() : caches(Technique::cct, settings()) { caches.attach(world.scene, {world.mirror}, 16); }
    static SceneCacheSettings settings() {
        SceneCacheSettings s;
        s.edge_threshold = -1.0f;
        return s;
    }
    // A frame of every direction, each leaving from origin_of(direction).
    template <class OriginOf>
    SceneCacheStatistics frame_from(OriginOf origin_of) {
        for (const glm::vec3& d : cell_directions())
            caches.leaving_ray({world.mirror}, origin_of(d), d, [&] { return TracedRay{0.5f + 0.5f * d, 10.0f, 4}; });
        return caches.begin_frame();
    }
    SceneCacheStatistics frame_from_top() {
        return frame_from([&](const glm::vec3&) { return top; });
    }
    // Faces 0 and 1 from the top, where their texels were stored (a third of the rays hit); the others from
    // the side, failing the origin test and storing nothing.
    SceneCacheStatistics frame_a_third_from_top() {
        return frame_from([&](const glm::vec3& d) { return raycache::texel_of(d, 16)->face <= 1 ? top : side; });
    }
};

} // namespace

TEST_CASE("a cube whose rays all missed rests: the next frame looks up its probe directions alone") {
    // Frame 0 (WarmMirror) started with an empty cube: all missed, but a cold frame decides nothing.
    WarmMirror w(0.5f);
    const std::size_t rays = 1536, probes = probe_count();
    REQUIRE(probes > 0);
    const glm::vec3 side(1.0f, 0.0f, 0.0f); // 1.4 from the top: far beyond the origin test's 0.1
    // Frame 1 leaves from elsewhere: every tile fails the origin test; the cube rests.
    SceneCacheStatistics s = w.from(side);
    CHECK(s.hits == 0);
    CHECK(s.misses_by[static_cast<std::size_t>(MissReason::origin)] == rays);
    CHECK(rested(s) == 0);
    CHECK(s.resting_cubes == 1);
    // Frame 2, resting: every ray is traced, only the probes were looked up (and stored). The stale tiles
    // were dropped, so the cube started empty: that frame decides nothing either.
    w.traced = 0;
    s = w.from(side);
    CHECK(w.traced == static_cast<int>(rays));
    CHECK(s.lookups == rays); // resting rays count as lookups, so adaptive sizes still see them
    CHECK(rested(s) == rays - probes);
    CHECK(s.misses_by[static_cast<std::size_t>(MissReason::empty)] == probes);
    CHECK(s.stores == probes);
    CHECK(s.resting_cubes == 1);
    // Frame 3, resting: the probes hit what frame 2 stored; the cube works again.
    w.traced = 0;
    s = w.from(side);
    CHECK(s.hits == probes);
    CHECK(w.traced == static_cast<int>(rays - probes));
    CHECK(rested(s) == rays - probes);
    CHECK(s.resting_cubes == 0);
    // Frame 4 works: every ray looked up; the directions let through while resting are empty and refill.
    // Its low hit rate (a sixteenth) decides nothing: a cube just back from resting refills first.
    s = w.from(side);
    CHECK(rested(s) == 0);
    CHECK(s.hits == probes);
    CHECK(s.misses_by[static_cast<std::size_t>(MissReason::empty)] == rays - probes);
    CHECK(s.resting_cubes == 0);
    // Frame 5: every direction hits, and it stays working.
    w.traced = 0;
    s = w.from(side);
    CHECK(s.hits == rays);
    CHECK(w.traced == 0);
    CHECK(s.resting_cubes == 0);
}

TEST_CASE("left unset, the threshold is each cube's break-even from the work of the rays that filled its texels") {
    // Frame 0 (cold) stores the directions of faces 0 and 1 alone; frame 1, from the same point, looks up all
    // of them twice: a third hit, and 1024 misses are traced and stored, each reporting `work` rays (their
    // second lookups are traced too, but store nothing, so they do not count). CCT's default lookup_work is
    // 1 ray, so the cube pays from 1 / work hits on: it rests after frame 1 when work is 2 (needs 50%), not
    // when it is 4 (25%). A min_hit_rate given, or lookup_work 2, is obeyed whatever the work.
    struct Case {
        std::optional<float> min_hit_rate, lookup_work;
        std::uint32_t work;
        bool rests;
    };
    for (const Case& c : {Case{std::nullopt, std::nullopt, 4, false}, Case{std::nullopt, std::nullopt, 2, true},
                          Case{std::nullopt, std::nullopt, 0, true}, // no work reported: CCT's fixed 0.5
                          Case{0.5f, std::nullopt, 4, true}, Case{std::nullopt, 2.0f, 4, true}, Case{0.3f, std::nullopt, 2, false}}) {
        CAPTURE(c.work);
        CAPTURE(c.min_hit_rate.value_or(-1.0f));
        CAPTURE(c.lookup_work.value_or(-1.0f));
        MirrorAndBall world;
        SceneCacheSettings settings;
        settings.edge_threshold = -1.0f;
        settings.min_hit_rate = c.min_hit_rate;
        settings.lookup_work = c.lookup_work;
        SceneCache caches(Technique::cct, settings);
        caches.attach(world.scene, {world.mirror}, 16);
        const glm::vec3 top(0.0f, 1.0f, 0.0f);
        auto run = [&](bool first_faces_only) {
            for (const glm::vec3& d : cell_directions()) {
                if (first_faces_only && raycache::texel_of(d, 16)->face > 1) continue;
                for (int twice = first_faces_only ? 1 : 2; twice > 0; --twice)
                    caches.leaving_ray({world.mirror}, top, d, [&] { return TracedRay{0.5f + 0.5f * d, 10.0f, c.work}; });
            }
            return caches.begin_frame();
        };
        run(true);
        const SceneCacheStatistics s = run(false);
        CHECK(s.hits == 1024);
        CHECK(s.misses_by[static_cast<std::size_t>(MissReason::fresh)] == 1024);
        CHECK(s.work_reports == (c.work ? 1024u : 0u));
        CHECK(s.filled_work == 1024u * c.work);
        CHECK(s.resting_cubes == (c.rests ? 1u : 0u));
    }
}

TEST_CASE("a warm cube that stores nothing keeps the work its texels' rays reported in earlier frames") {
    // Frames 0 and 1 fill every texel from the top, each ray reporting 4 rays. Frame 2 stores nothing: a third
    // of its rays hit, the others leave from the side and fail the origin test. Its threshold is 1 / 4 from the
    // earlier frames' work (it keeps working), not the fixed 0.5 a frame without reports would fall back to.
    MirrorReportingWork m;
    m.frame_from_top();
    CHECK(m.frame_from_top().hits == 1536);
    const SceneCacheStatistics s = m.frame_a_third_from_top();
    CHECK(s.hits == 512);
    CHECK(s.misses_by[static_cast<std::size_t>(MissReason::origin)] == 1024);
    CHECK(s.work_reports == 0);
    CHECK(s.resting_cubes == 0);
}

TEST_CASE("a warm cube keeps its threshold from work through any number of frames that report too little to judge by") {
    // As above, but eight frames between fill and test answer every ray and store nothing. Halving the
    // estimate every frame would leave 1536 / 2^8 = 6 reports (< 32) and fall back to the fixed 0.5, which
    // the test frame's third of hits is below (it would rest); frames with fewer than 32 reports leave it
    // whole, so the threshold stays 1 / 4 and the cube keeps working.
    MirrorReportingWork m;
    CHECK(m.frame_from_top().work_reports == 1536u);
    for (int f = 0; f < 8; ++f) {
        const SceneCacheStatistics s = m.frame_from_top();
        CHECK(s.hits == 1536);
        CHECK(s.work_reports == 0);
    }
    const SceneCacheStatistics s = m.frame_a_third_from_top();
    CHECK(s.hits == 512);
    CHECK(s.work_reports == 0);
    CHECK(s.resting_cubes == 0);
}

TEST_CASE("with min_hit_rate 0 a cube never rests, whatever its hit rate") {
    WarmMirror w(0.0f);
    for (int f = 0; f < 3; ++f) {
        // From alternating points: every frame misses on the origin test or on dropped tiles.
        const SceneCacheStatistics s = w.from(f % 2 ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0));
        CHECK(s.hits == 0);
        CHECK(rested(s) == 0);
        CHECK(s.resting_cubes == 0);
    }
}

TEST_CASE("a cube emptied by clear() is cold again: its next frame decides nothing, and it stops resting") {
    WarmMirror w(0.5f);
    CHECK(w.from(glm::vec3(1, 0, 0)).resting_cubes == 1);
    w.caches.clear();
    const SceneCacheStatistics s = w.from(glm::vec3(1, 0, 0)); // all miss: empty
    CHECK(rested(s) == 0);
    CHECK(s.hits == 0);
    CHECK(s.resting_cubes == 0);
    CHECK(w.from(glm::vec3(1, 0, 0)).hits == 1536);
}

TEST_CASE("a cube loaded from a cache file works, and its first frame decides: it holds the file's texels") {
    // A threshold no cube meets: the warm frame (all 1536 hit) sends the cube to rest.
    WarmMirror w(2.0f);
    REQUIRE(w.from(glm::vec3(0, 1, 0)).resting_cubes == 1);
    ScratchFolder folder("resting-load");
    const raycache::SceneIdentity identity{7, "mirror and ball"};
    w.caches.save(folder.file("resting.rcc"), identity);
    // Loaded into the cache that rests: it works again (a file holds texels, not resting).
    w.caches.load(folder.file("resting.rcc"), identity);
    SceneCacheStatistics s = w.from(glm::vec3(0, 1, 0));
    CHECK(rested(s) == 0);
    CHECK(s.hits == 1536);
    CHECK(s.resting_cubes == 1); // that frame started with the file's texels, so it decided
    // Loaded into a fresh cache: the same.
    SceneCache fresh = resting_caches(2.0f);
    fresh.attach(w.world.scene, {w.world.mirror}, 16);
    fresh.load(folder.file("resting.rcc"), identity);
    int traced = 0;
    s = frame(fresh, w.world.mirror, glm::vec3(0, 1, 0), traced);
    CHECK(traced == 0);
    CHECK(s.resting_cubes == 1);
}

TEST_CASE("cubes emptied by a scene change, or replaced when path records start, decide nothing the next frame") {
    // A ball moves far from the mirror: the first move makes every cube keep path records, which replaces
    // it by an empty one; the frame after finds it empty (all misses) and must not rest it.
    MirrorAndBall w;
    SceneCache caches = resting_caches(0.5f);
    caches.attach(w.scene, {w.mirror}, 16);
    int traced = 0;
    const glm::vec3 top(0, 1, 0);
    frame(caches, w.mirror, top, traced);
    CHECK(frame(caches, w.mirror, top, traced).hits == 1536); // warm, working
    raycache::embree::SceneChange change;
    change.moved.push_back({{w.ball}, {glm::vec3(-6, 0, 0), 0.2f}, {glm::vec3(-6, 0, 1), 0.2f}, std::nullopt});
    caches.scene_changed(change, raycache::embree::Invalidation::exact);
    REQUIRE(caches.keeps_path_records());
    SceneCacheStatistics s = frame(caches, w.mirror, top, traced);
    CHECK(s.hits == 0); // the replaced cube was empty
    CHECK(s.resting_cubes == 0);
    CHECK(frame(caches, w.mirror, top, traced).hits == 1536);
    // Moving the mirror itself empties its cube: the same.
    raycache::embree::SceneChange mirror_moved;
    mirror_moved.moved.push_back({{w.mirror}, {glm::vec3(0, 0, 0), 1.0f}, {glm::vec3(0, 0, 0), 1.0f}, std::nullopt});
    caches.scene_changed(mirror_moved, raycache::embree::Invalidation::exact);
    s = frame(caches, w.mirror, top, traced);
    CHECK(s.hits == 0);
    CHECK(s.resting_cubes == 0);
}

TEST_CASE("min_hit_rate must be a number >= 0, lookup_work a finite number") {
    for (const float bad : {-0.1f, std::numeric_limits<float>::quiet_NaN()}) {
        SceneCacheSettings s;
        s.min_hit_rate = bad;
        CHECK_THROWS_AS(SceneCache(Technique::cct, s), std::invalid_argument);
    }
    SceneCacheSettings s;
    s.min_hit_rate = 2.0f; // above any hit rate: every cube rests once warm (a measurement aid)
    CHECK_NOTHROW(SceneCache(Technique::cdct, s));
    for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        SceneCacheSettings w;
        w.lookup_work = bad;
        CHECK_THROWS_WITH_AS(SceneCache(Technique::cct, w), doctest::Contains("lookup_work"), std::invalid_argument);
    }
    SceneCacheSettings off;
    off.lookup_work = -1.0f; // thresholds ignore work
    CHECK_NOTHROW(SceneCache(Technique::cct, off));
}

TEST_CASE("texels a CDCT search read are counted over the rays looked up, not over the rays a resting cube let through") {
    SceneCacheStatistics s;
    s.lookups = 100;
    s.misses_by[static_cast<std::size_t>(MissReason::resting)] = 60;
    s.texels_read = 80;
    CHECK(s.looked_up() == 40u);
    CHECK(s.texels_per_lookup() == doctest::Approx(2.0));
    s.misses_by[static_cast<std::size_t>(MissReason::resting)] = 100; // every ray let through
    CHECK(s.texels_per_lookup() == 0.0);
}
