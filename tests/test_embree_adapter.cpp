// The Embree adapter on real Embree scenes: bounds from geometry, id mapping (plain and instanced), and
// Algorithm 1 around a trace that calls rtcIntersect1.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include <raycache/embree/scene_cache.hpp>

#include "embree_spheres.hpp"

using raycache::TracedRay;
using raycache::embree::ObjectId;
using raycache::embree::SceneCache;
using raycache::embree::Technique;
using raycache::embree::Invalidation;
using raycache::embree::SceneChange;
using raycache::BoundingSphere;

namespace {

// A device and a committed scene: a sphere of radius 0.5 at (1, 2, 3) (id 0), a floor quad
// x in [-8, 8], z in [-6, 6] at y = -1 (id 1), and a sphere of radius 1 at (-3, 0, 0) (id 2).
struct World {
    RTCDevice device = rtcNewDevice(nullptr);
    RTCScene scene = rtcNewScene(device);
    unsigned mirror = 0, floor = 0, ball = 0;

    unsigned add_sphere(RTCScene target, glm::vec3 c, float r) { return add_embree_sphere(device, target, c, r); }
    World() {
        mirror = add_sphere(scene, {1, 2, 3}, 0.5f);
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 4));
        const float quad[12] = {-8, -1, -6, 8, -1, -6, 8, -1, 6, -8, -1, 6};
        for (int i = 0; i < 12; ++i) v[i] = quad[i];
        auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), 2));
        const unsigned tris[6] = {0, 1, 2, 0, 2, 3};
        for (int i = 0; i < 6; ++i) t[i] = tris[i];
        rtcCommitGeometry(g);
        floor = rtcAttachGeometry(scene, g);
        rtcReleaseGeometry(g);
        ball = add_sphere(scene, {-3, 0, 0}, 1.0f);
        rtcCommitScene(scene);
    }
    ~World() {
        rtcReleaseScene(scene);
        rtcReleaseDevice(device);
    }

    // Distance along unit d from o to the first hit, and what was hit (RTC_INVALID_GEOMETRY_ID: nothing).
    std::pair<float, unsigned> intersect(glm::vec3 o, glm::vec3 d) const {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRayHit rh{};
        rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
        rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
        rh.ray.tnear = 1e-4f;
        rh.ray.tfar = std::numeric_limits<float>::infinity();
        rh.ray.mask = 0xFFFFFFFFu; // Debian's Embree is built with ray masks: a zero mask hits nothing
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &context, &rh);
        return {rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? std::numeric_limits<float>::infinity() : rh.ray.tfar, rh.hit.geomID};
    }
};

// Instances committed scene `inner` into `top`, moved by `offset`; the instance's geometry id in `top`.
unsigned add_instance(RTCDevice device, RTCScene top, RTCScene inner, glm::vec3 offset) {
    RTCGeometry instance = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(instance, inner);
    const float transform[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, offset.x, offset.y, offset.z}; // column-major 3x4
    rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, transform);
    rtcCommitGeometry(instance);
    const unsigned id = rtcAttachGeometry(top, instance);
    rtcReleaseGeometry(instance);
    return id;
}

// One unit direction through each texel centre of an N x N cube: 6 N^2 rays over every direction.
std::vector<glm::vec3> texel_centres(int n) {
    std::vector<glm::vec3> directions;
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column)
                directions.push_back(glm::normalize(texel_direction(raycache::TexelAddress{face, column, row}, n)));
    return directions;
}

// A still camera: `frames` frames of the same rays leaving `mirror` at (1, 2, 3) in `directions`, traced to
// the colour 0.5 + 0.5 d; per frame, the hits its begin_frame() reported and the cube's face size after it.
struct StillFrames {
    std::vector<std::uint64_t> hits;
    std::vector<int> sizes;
};
StillFrames still_frames(SceneCache& caches, unsigned mirror, const std::vector<glm::vec3>& directions, int frames) {
    StillFrames out;
    for (int f = 0; f < frames; ++f) {
        for (const glm::vec3& d : directions)
            caches.leaving_ray({mirror}, glm::vec3(1, 2, 3), d, [&] { return TracedRay{0.5f + 0.5f * d, 1.0f}; });
        out.hits.push_back(caches.begin_frame().hits);
        out.sizes.push_back(caches.face_size({mirror}));
    }
    return out;
}

} // namespace

TEST_CASE("cube bounds come from the Embree geometry: centre of its box, largest half-extent") {
    World w;
    const raycache::CubeBounds sphere = raycache::embree::bounds_of(w.scene, {w.mirror});
    CHECK(sphere.centre.x == doctest::Approx(1.0f).epsilon(1e-4));
    CHECK(sphere.centre.y == doctest::Approx(2.0f).epsilon(1e-4));
    CHECK(sphere.centre.z == doctest::Approx(3.0f).epsilon(1e-4));
    CHECK(sphere.half_size == doctest::Approx(0.5f).epsilon(1e-3));
    // The quad spans 16 x 0 x 12: centre (0, -1, 0), half-size 8 along x.
    const raycache::CubeBounds quad = raycache::embree::bounds_of(w.scene, {w.floor});
    CHECK(quad.centre.x == doctest::Approx(0.0f));
    CHECK(quad.centre.y == doctest::Approx(-1.0f));
    CHECK(quad.half_size == doctest::Approx(8.0f));
    // Measuring did not disturb the scene: rays still hit the sphere.
    CHECK(w.intersect({1, 2, 0}, {0, 0, 1}).second == w.mirror);
    // A detached geometry has no bounds to give.
    rtcDetachGeometry(w.scene, w.ball);
    rtcCommitScene(w.scene);
    CHECK_THROWS_WITH_AS(raycache::embree::bounds_of(w.scene, {w.ball}), doctest::Contains("no geometry"), std::invalid_argument);
}

TEST_CASE("only attached ids have cubes, plain and instanced ids are told apart, and attach errors are clear") {
    World w;
    SceneCache caches(Technique::cct);
    caches.attach(w.scene, {w.mirror}, 16);
    caches.attach({w.ball, 5}, 8, raycache::CubeBounds{{0, 0, 0}, 1.0f}); // geometry `ball` inside instance 5
    CHECK(caches.has_cache({w.mirror}));
    CHECK_FALSE(caches.has_cache({w.floor}));
    CHECK_FALSE(caches.has_cache({w.ball}));      // not through the instance: no cube
    CHECK(caches.has_cache({w.ball, 5}));
    CHECK_FALSE(caches.has_cache({w.ball, 6}));
    CHECK_FALSE(caches.has_cache({12345}));
    CHECK(caches.object_count() == 2);
    CHECK(caches.texel_bytes() == 6 * 16 * 16 * 4 + 6 * 8 * 8 * 4);
    CHECK_THROWS_WITH_AS(caches.attach(w.scene, {w.mirror}, 16), doctest::Contains("already"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(caches.attach(w.scene, {w.floor}, -1), doctest::Contains("face size"), std::invalid_argument);
    rtcDetachGeometry(w.scene, w.floor);
    rtcCommitScene(w.scene);
    CHECK_THROWS_WITH_AS(caches.attach(w.scene, {w.floor}, 16), doctest::Contains("no geometry"), std::invalid_argument);
    CHECK_THROWS_AS(SceneCache(Technique::cdct, raycache::ReliefParameters{0.0f, 0.01f, 10, 100.0f}), std::invalid_argument);
    for (const float parallax : {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN()}) {
        raycache::embree::SceneCacheSettings bad;
        bad.origin_parallax = parallax;
        CHECK_THROWS_WITH_AS(SceneCache(Technique::cct, bad), doctest::Contains("origin_parallax"), std::invalid_argument);
    }
    raycache::embree::SceneCacheSettings off;
    off.origin_parallax = std::numeric_limits<float>::infinity();
    CHECK_NOTHROW(SceneCache(Technique::cct, off));
}

TEST_CASE("a reflected ray traced with rtcIntersect1 is cached: traced in the cold frame, answered in the next") {
    World w;
    SceneCache caches(Technique::cct);
    caches.attach(w.scene, {w.mirror}, 64);
    int traces = 0;
    // From the bottom of the mirror sphere straight down: the floor at y = -1 is 2.5 below.
    const glm::vec3 p(1, 1.5f, 3), r(0, -1, 0);
    auto trace = [&] {
        ++traces;
        const auto [t, id] = w.intersect(p, r);
        return TracedRay{id == w.floor ? glm::vec3(0.25f, 0.5f, 0.75f) : glm::vec3(0.0f), t};
    };
    const glm::vec3 cold = caches.leaving_ray({w.mirror}, p, r, trace);
    CHECK(cold == glm::vec3(0.25f, 0.5f, 0.75f)); // exact: the traced value, not re-encoded
    CHECK(traces == 1);
    const auto frame0 = caches.begin_frame();
    CHECK(frame0.lookups == 1);
    CHECK(frame0.misses == 1);
    CHECK(frame0.misses_by[static_cast<std::size_t>(raycache::MissReason::empty)] == 1); // nothing stored yet
    CHECK(frame0.miss_share(raycache::MissReason::empty) == 1.0);
    CHECK(frame0.stores == 1);
    const glm::vec3 warm = caches.leaving_ray({w.mirror}, p, r, trace);
    CHECK(traces == 1);
    CHECK(warm.x == doctest::Approx(0.25f).epsilon(0.002));
    CHECK(warm.z == doctest::Approx(0.75f).epsilon(0.002));
    CHECK(caches.begin_frame().hits == 1);
    // An object without a cube traces every time.
    caches.leaving_ray({w.floor}, p, r, trace);
    caches.leaving_ray({w.floor}, p, r, trace);
    CHECK(traces == 3);
}

namespace {
void check_cdct_finds_stored_hit(bool pyramid) {
    World w;
    SceneCache caches(Technique::cdct, raycache::ReliefParameters{0.05f, 0.005f, 2000, 100.0f}, pyramid);
    caches.attach(w.scene, {w.mirror}, 64);
    // Fill: rays leaving the sphere's bottom half downwards hit the floor (colour by x of the hit).
    int traces = 0;
    auto leave = [&](glm::vec3 p, glm::vec3 r) {
        return caches.leaving_ray({w.mirror}, p, r, [&] {
            ++traces;
            const auto [t, id] = w.intersect(p, glm::normalize(r));
            const glm::vec3 hit = p + t * glm::normalize(r);
            return TracedRay{id == w.floor ? glm::vec3(0.5f + 0.1f * hit.x, 0.2f, 0.2f) : glm::vec3(0.0f), t};
        });
    };
    // A fan of rays from the sphere's lowest point covers the floor around (1, -1, 3): seen from the
    // centre, 3 above the floor, its hits are 0.05 / 3 = 0.017 apart in tangent, denser than the
    // 2 / 64 = 0.031 of a texel, so no texel on the way is left empty (an empty one would make it a miss).
    const glm::vec3 centre(1, 2, 3);
    for (int i = -40; i <= 40; ++i)
        for (int j = -40; j <= 40; ++j) leave(centre + glm::vec3(0, -0.5f, 0), glm::vec3(i * 0.02f, -1.0f, j * 0.02f));
    const int fill_traces = traces;
    CHECK(fill_traces == 81 * 81);
    caches.begin_frame();
    // From another point of the sphere, aimed at the floor point (1.3, -1, 3.2): parallax-correct answer.
    const glm::vec3 origin = centre + 0.5f * glm::normalize(glm::vec3(0.3f, -1.0f, 0.1f));
    const glm::vec3 target(1.3f, -1.0f, 3.2f);
    const glm::vec3 color = leave(origin, target - origin);
    CHECK(traces == fill_traces); // answered from the cube
    CHECK(color.x == doctest::Approx(0.5f + 0.1f * 1.3f).epsilon(0.01));
    const auto s = caches.begin_frame();
    CHECK(s.hits == 1);
    CHECK(s.texels_read > 1);
    CHECK(s.max_texels_read == s.texels_read); // one search: the most is the total
}
} // namespace

TEST_CASE("the CDCT stores a traced hit at its distance, so a ray from elsewhere towards that point finds it") {
    SUBCASE("with the thesis's linear search") { check_cdct_finds_stored_hit(false); }
    SUBCASE("with the depth pyramid") { check_cdct_finds_stored_hit(true); }
}

TEST_CASE("pre-filling an object's cube through the adapter traces every texel once, from the centre outwards") {
    World w;
    SceneCache caches(Technique::cdct, raycache::ReliefParameters{0.05f, 0.005f, 2000, 100.0f});
    caches.attach(w.scene, {w.mirror}, 16);
    CHECK(caches.objects().size() == 1);
    CHECK(caches.face_size({w.mirror}) == 16);
    CHECK(caches.face_size({w.floor}) == 0);
    std::size_t stored = 0;
    int mirror_hits = 0;
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < 16; ++row)
            stored += caches.prefill_row({w.mirror}, face, row, [&](glm::vec3 o, glm::vec3 d) {
                mirror_hits += o == glm::vec3(1, 2, 3); // rays start at the cube's centre...
                const auto [t, id] = w.intersect(o + 0.5001f * d, d); // ...and pass through the sphere
                return TracedRay{id == w.floor ? glm::vec3(0.5f) : glm::vec3(0.1f), t + 0.5001f};
            });
    CHECK(stored == 6 * 16 * 16);
    CHECK(mirror_hits == 6 * 16 * 16);
    const auto s = caches.begin_frame();
    CHECK(s.valid_texels == 6 * 16 * 16);
    // A second pre-fill finds nothing empty.
    CHECK(caches.prefill_row({w.mirror}, 3, 0, [&](glm::vec3, glm::vec3) { return TracedRay{}; }) == 0);
    // Every search now answers: straight down from the sphere's bottom, the floor's colour.
    int traces = 0;
    const glm::vec3 c = caches.leaving_ray({w.mirror}, {1, 1.5f, 3}, {0.1f, -1, 0}, [&] { ++traces; return TracedRay{}; });
    CHECK(traces == 0);
    CHECK(c.x == doctest::Approx(0.5f).epsilon(0.01));
}

TEST_CASE("an adaptive cube shrinks to the size a frame's rays fill, and the next frame hits on every one of them") {
    World w;
    SceneCache caches(Technique::cct);
    caches.attach(w.scene, {w.mirror}); // adaptive: starts at AdaptiveResolution::first_face_size
    CHECK(caches.face_size({w.mirror}) == 256);
    // One ray through each texel centre of a 32 x 32 cube: 6144 rays over every direction, so one ray a
    // texel at N = 32 (6 * 32^2 = 6144), the size the cube must take.
    const std::vector<glm::vec3> directions = texel_centres(32);
    auto colour_of = [](glm::vec3 d) { return 0.5f + 0.5f * d; };
    int traced = 0;
    auto frame = [&] {
        for (const glm::vec3& d : directions) {
            const glm::vec3 c = caches.leaving_ray({w.mirror}, glm::vec3(1, 2, 3), d, [&] {
                ++traced;
                return TracedRay{colour_of(d), 1.0f};
            });
            CHECK(glm::length(c - colour_of(d)) < 0.01f);
        }
        return caches.begin_frame();
    };
    const auto first = frame();
    CHECK(first.misses == 6144u);
    // One ray a texel of the 256-texel cube: each found its texel empty; none met one stored that frame.
    CHECK(first.misses_by[static_cast<std::size_t>(raycache::MissReason::empty)] == 6144u);
    CHECK(first.resized_cubes == 1u);
    CHECK(caches.face_size({w.mirror}) == 32);
    traced = 0;
    const auto second = frame();
    CHECK(traced == 0);
    CHECK(second.hits == 6144u);
    CHECK(second.resized_cubes == 0u);
    CHECK(caches.face_size({w.mirror}) == 32);
}

TEST_CASE("an adaptive cube whose rays come back to the same texels frame after frame takes finer faces, once") {
    // The 6144 rays of the test above, every frame (a still camera). Frame 1 sizes the cube to 32 (one ray
    // a texel); frame 2, right after that resize, is not judged; frames 3 to 5 hit every ray (still_frames
    // = 3), so the cube takes still_rays_per_texel = 0.1: sqrt(6144 / (0.1 * 6)) = 101.2, whose nearest step
    // is 91 (0.15 octave away; 128 is 0.34). Frame 6 starts that cube empty (not judged either); from frame
    // 7 it hits every ray again and keeps 91 (101.2 is within the hysteresis).
    World w;
    SceneCache caches(Technique::cct);
    caches.attach(w.scene, {w.mirror});
    const StillFrames frames = still_frames(caches, w.mirror, texel_centres(32), 9);
    CHECK(frames.sizes == std::vector<int>{32, 32, 32, 32, 91, 91, 91, 91, 91});
    CHECK(frames.hits == std::vector<std::uint64_t>{0, 6144, 6144, 6144, 6144, 0, 6144, 6144, 6144});
}

TEST_CASE("a still camera's cube takes only the finer faces its budget has room for, and keeps them") {
    // The rays of the test above under a budget of 200,000 bytes. By hand (CCT tiles of a static scene:
    // 1280 bytes, 8-byte table entries): the first faces are the largest step a full cube fits, 64 (96
    // tiles, 123,648 bytes; 91 would take 278,208), and the cold frame's rays call for 32. After frame 5
    // the still rule wants 91, which the room (200,000 less the 32-cube, whose own 30,912 bytes go with it)
    // cannot hold for rays over every direction; 64 fits: frame 6 starts it empty, and from frame 7 it
    // answers every ray and stays. Without the cap the 91-cube could not keep its tiles, its misses on
    // empty texels would end the still rule and it would shrink and refine again.
    World w;
    raycache::embree::SceneCacheSettings settings;
    settings.budget_bytes = 200000;
    SceneCache caches(Technique::cct, settings);
    caches.attach(w.scene, {w.mirror});
    CHECK(caches.face_size({w.mirror}) == 64);
    const std::vector<glm::vec3> directions = texel_centres(32);
    const StillFrames frames = still_frames(caches, w.mirror, directions, 12);
    CHECK(frames.sizes == std::vector<int>{32, 32, 32, 32, 64, 64, 64, 64, 64, 64, 64, 64});
    CHECK(frames.hits == std::vector<std::uint64_t>{0, 6144, 6144, 6144, 6144, 0, 6144, 6144, 6144, 6144, 6144, 6144});
    CHECK(caches.statistics().allocated_bytes <= 200000u);
    // No limit (the largest budget): the finer faces are the ones wanted, 91, as under the default budget.
    raycache::embree::SceneCacheSettings unlimited;
    unlimited.budget_bytes = std::numeric_limits<std::size_t>::max();
    SceneCache free_caches(Technique::cct, unlimited);
    free_caches.attach(w.scene, {w.mirror});
    CHECK(still_frames(free_caches, w.mirror, directions, 6).sizes.back() == 91);
}

TEST_CASE("a frame's counts survive scene_changed before its begin_frame: the statistics and the adaptive size still see its rays") {
    // As the test above: 6144 rays, one through each texel centre of a 32 x 32 cube, call for N = 32. Here
    // the ball moves between the frame and its begin_frame(), which empties (Invalidation::all) or replaces
    // (the first move of PathRecords::from_first_move, under exact) the mirror's cube.
    for (const Invalidation policy : {Invalidation::all, Invalidation::exact}) {
        CAPTURE(static_cast<int>(policy));
        World w;
        SceneCache caches(Technique::cct);
        caches.attach(w.scene, {w.mirror});
        int traced = 0;
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < 32; ++row)
                for (int column = 0; column < 32; ++column) {
                    const glm::vec3 d = glm::normalize(texel_direction(raycache::TexelAddress{face, column, row}, 32));
                    caches.leaving_ray({w.mirror}, glm::vec3(1, 2, 3), d, [&] {
                        ++traced;
                        return TracedRay{glm::vec3(0.5f), 1.0f};
                    });
                }
        REQUIRE(traced == 6144);
        SceneChange change;
        change.moved.push_back({{w.ball}, BoundingSphere{{-3, 0, 0}, 1.0f}, BoundingSphere{{-3, 0.5f, 0}, 1.0f}, std::nullopt});
        CHECK_FALSE(caches.keeps_path_records()); // PathRecords::from_first_move, before the first move
        caches.scene_changed(change, policy);
        CHECK(caches.keeps_path_records() == (policy == Invalidation::exact)); // the switch comes with exact
        CHECK(caches.statistics().lookups == 6144u); // still the frame's, before it ends
        const auto frame = caches.begin_frame();
        CHECK(frame.lookups == 6144u);
        CHECK(frame.misses == 6144u);
        CHECK(frame.misses_by[static_cast<std::size_t>(raycache::MissReason::empty)] == 6144u);
        CHECK(frame.stores == 6144u);
        CHECK(caches.face_size({w.mirror}) == 32);
        CHECK(caches.begin_frame().lookups == 0u); // counted once
    }
}

TEST_CASE("a cube attached with an explicit face size keeps it whatever the rays") {
    World w;
    SceneCache caches(Technique::cct);
    caches.attach(w.scene, {w.mirror}, 128);
    for (int i = 0; i < 50; ++i)
        caches.leaving_ray({w.mirror}, glm::vec3(0), glm::vec3(1, 0.01f * static_cast<float>(i), 0), [] { return TracedRay{glm::vec3(1), 1.0f}; });
    CHECK(caches.begin_frame().resized_cubes == 0u);
    CHECK(caches.face_size({w.mirror}) == 128);
}

TEST_CASE("adaptive cubes start small enough that every cube sharing the budget could fill all its tiles") {
    // By hand, with t = tile + table entry bytes: a full cube of N has 6 ceil(N/16)^2 tiles, so 181 takes
    // 864 t, 128 384 t, 91 216 t, 64 96 t, 45 54 t, plus a byte a tile for its bitmap bits (rounded up) and
    // a cube's fixed part F (under 13,000 bytes). A budget of 960 t: one cube's share fits 181 (not 256:
    // 1536 t); two cubes 128; three and four 91; five to nine 64; ten (a share of exactly 96 t, which the
    // 64-cube's bitmap bytes and F overrun) and eleven 45.
    // (Tiles without path records: a cache keeps none before its first move.)
    const std::size_t t = raycache::CctCube::tile_bytes(false) + sizeof(void*);
    REQUIRE(raycache::CctCube::fixed_bytes_per_cube() < 13000u); // so the shares above hold F
    raycache::embree::SceneCacheSettings settings;
    settings.budget_bytes = 960 * t;
    SceneCache caches(Technique::cct, settings);
    const raycache::CubeBounds bounds{glm::vec3(0.0f), 1.0f};
    const std::vector<std::pair<unsigned, int>> expected{{1, 181}, {2, 128}, {3, 91}, {4, 91}, {5, 64}, {9, 64}, {10, 45}, {11, 45}};
    unsigned attached = 0;
    for (const auto& [cubes, size] : expected) {
        while (attached < cubes) caches.attach({attached++}, raycache::embree::adaptive_face_size, bounds);
        CAPTURE(cubes);
        for (unsigned id = 0; id < attached; ++id) CHECK(caches.face_size({id}) == size); // earlier ones shrink too
    }
    // A cube of an explicit size keeps it, and counts: twelve cubes' shares still fit 45 (54 t < 80 t).
    caches.attach({100}, 128, bounds);
    CHECK(caches.face_size({100}) == 128);
    CHECK(caches.face_size({0}) == 45);

    // A cold frame that stores into every tile of every adaptive cube fits: nothing refused.
    std::vector<glm::vec3> tile_centres;
    for (int face = 0; face < 6; ++face)
        for (int row : {8, 24, 40})
            for (int column : {8, 24, 40})
                tile_centres.push_back(glm::normalize(texel_direction(raycache::TexelAddress{face, column, row}, 45)));
    for (unsigned id = 0; id < attached; ++id)
        for (const glm::vec3& d : tile_centres)
            caches.leaving_ray({id}, glm::vec3(0.0f), d, [] { return TracedRay{glm::vec3(0.5f), 1.0f}; });
    const auto frame = caches.begin_frame();
    CHECK(caches.budget().refusals() == 0u);
    CHECK(frame.stores == 11u * 54u);

    // Cubes a frame has sized are not started over when more cubes come.
    std::vector<int> sized;
    for (unsigned id = 0; id < attached; ++id) sized.push_back(caches.face_size({id}));
    for (unsigned id = 200; id < 240; ++id) caches.attach({id}, raycache::embree::adaptive_face_size, bounds);
    for (unsigned id = 0; id < attached; ++id) CHECK(caches.face_size({id}) == sized[id]);
    CHECK(caches.face_size({200}) < 45);
}

TEST_CASE("a budget with no room for another cube's fixed part refuses the attach, and attaches nothing") {
    // Each cube takes its fixed part (tile table, bitmaps, counters: CacheCube::fixed_bytes) from the budget
    // before any texel. Adaptive cubes on a budget too small for any tile start at the smallest size, 8.
    const std::size_t small = raycache::CctCube::fixed_bytes(8);
    raycache::embree::SceneCacheSettings settings;
    settings.budget_bytes = 3 * small + small / 2;
    SceneCache caches(Technique::cct, settings);
    const raycache::CubeBounds bounds{glm::vec3(0.0f), 1.0f};
    for (unsigned id = 0; id < 3; ++id) caches.attach({id}, raycache::embree::adaptive_face_size, bounds);
    for (unsigned id = 0; id < 3; ++id) CHECK(caches.face_size({id}) == 8);
    CHECK(caches.budget().used() == 3 * small);
    CHECK_THROWS_AS(caches.attach({3}, raycache::embree::adaptive_face_size, bounds), std::invalid_argument);
    CHECK_THROWS_WITH(caches.attach({3}, 8, bounds), doctest::Contains("no room for another cube"));
    CHECK(caches.object_count() == 3u);
    CHECK_FALSE(caches.has_cache({3}));
    CHECK(caches.statistics().allocated_bytes == 3 * small);
    CHECK(caches.statistics().allocated_bytes <= settings.budget_bytes);
    // The cube that was refused traces its rays, uncached.
    int traced = 0;
    caches.leaving_ray({3}, glm::vec3(0.0f), glm::vec3(1, 0, 0), [&] { return ++traced, TracedRay{glm::vec3(1.0f), 1.0f}; });
    CHECK(traced == 1);
}

TEST_CASE("adaptive cubes grow only as far as the budget holds their larger tile tables") {
    // By hand: a cube of 8 texels a face has 6 tiles (one a face), one of 16 too, one of 23 or 32 has 24.
    // The planner reserves for a cube of N its bound, P + 9 bytes a tile (CacheCube::fixed_bytes_per_cube()
    // = P, which counts the two bitmap words; an 8-byte table entry and a byte for its two bitmap bits a
    // tile), and lets a cube's own bytes go with it: the 8-cube's fixed part is P + 48 (6 entries; its two
    // bitmap words are in P). Four cubes of 8 on a budget with 300 bytes to spare (no tile fits: 1280
    // bytes); each frame sends every cube a ray through each texel centre of a 32-cube, which calls for 32.
    // The first cube grows to 32 (P + 216 within the 300 + P + 48 it has), leaving 132 bytes reserved;
    // the others cannot (132 + P + 48 < P + 216) and take 16, whose bound P + 54 they have room for.
    // Their memory is then 32's fixed part (18 entries more than 8's) and three of 8's: within the budget,
    // where four 32-cubes would pass it.
    const std::size_t small = raycache::CctCube::fixed_bytes(8);
    REQUIRE(small - raycache::CctCube::fixed_bytes_per_cube() == 48u);
    REQUIRE(raycache::CctCube::fixed_bytes(16) == small);
    REQUIRE(raycache::CctCube::fixed_bytes(32) - small == 144u);
    raycache::embree::SceneCacheSettings settings;
    settings.budget_bytes = 4 * small + 300;
    REQUIRE(4 * raycache::CctCube::fixed_bytes(32) > settings.budget_bytes);
    SceneCache caches(Technique::cct, settings);
    const raycache::CubeBounds bounds{glm::vec3(0.0f), 1.0f};
    for (unsigned id = 0; id < 4; ++id) caches.attach({id}, raycache::embree::adaptive_face_size, bounds);
    const std::vector<glm::vec3> directions = texel_centres(32);
    for (int frame = 0; frame < 3; ++frame) {
        CAPTURE(frame);
        for (unsigned id = 0; id < 4; ++id)
            for (const glm::vec3& d : directions)
                caches.leaving_ray({id}, glm::vec3(0.0f), d, [&] { return TracedRay{0.5f + 0.5f * d, 1.0f}; });
        const auto stats = caches.begin_frame();
        CHECK(stats.allocated_bytes == small * 3 + raycache::CctCube::fixed_bytes(32));
        CHECK(caches.budget().used() <= settings.budget_bytes);
        CHECK(caches.face_size({0}) == 32);
        for (unsigned id = 1; id < 4; ++id) CHECK(caches.face_size({id}) == 16);
    }
}

TEST_CASE("an instance attached by its own id caches every geometry reached through it") {
    World w;
    // A second scene holding one sphere, instanced into a new top-level scene.
    RTCScene inner = rtcNewScene(w.device);
    const unsigned inner_sphere = w.add_sphere(inner, {0, 0, 0}, 1.0f);
    rtcCommitScene(inner);
    RTCScene top = rtcNewScene(w.device);
    const unsigned instance_id = add_instance(w.device, top, inner, {5, 0, 0}); // moved to x = 5
    rtcCommitScene(top);
    {
        SceneCache caches(Technique::cct);
        caches.attach(top, {instance_id}, 16); // as the README shows for any object
        const auto bounds = caches.object_bounds({instance_id});
        REQUIRE(bounds);
        CHECK(bounds->centre.x == doctest::Approx(5.0f));
        // A hit reports (geomID = the sphere inside, instID[0] = the instance): it must find the cube.
        const ObjectId hit{inner_sphere, instance_id};
        CHECK(caches.has_cache(hit));
        caches.leaving_ray(hit, glm::vec3(6, 0, 0), glm::vec3(1, 0, 0), [] { return TracedRay{glm::vec3(0.5f), 2.0f}; });
        const auto s = caches.begin_frame();
        CHECK(s.lookups == 1u);
        CHECK(s.stores == 1u);
    }
    rtcReleaseScene(top);
    rtcReleaseScene(inner);
}

namespace {

// One Embree triangle geometry holding three objects, as a tracer that keeps every triangle together
// builds it: object A, triangles 0-1, a unit square at z = 5 over x, y in [0, 1]; object B, triangles 2-5,
// two 2 x 2 squares at z = 5 and z = 6 over x in [3, 5], y in [0, 2]; a backdrop, triangles 6-7, at z = 10
// over x, y in [-10, 10]. Vertices are FLOAT3 in a 16-byte stride, with junk in the fourth float.
struct Soup {
    RTCDevice device = rtcNewDevice(nullptr);
    RTCScene scene = rtcNewScene(device);
    unsigned soup = 0;

    Soup() {
        const float squares[4][5] = {{0, 1, 0, 1, 5}, {3, 5, 0, 2, 5}, {3, 5, 0, 2, 6}, {-10, 10, -10, 10, 10}};
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 4 * sizeof(float), 16));
        auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), 8));
        for (unsigned q = 0; q < 4; ++q) {
            const float* s = squares[q];
            const float corners[4][2] = {{s[0], s[2]}, {s[1], s[2]}, {s[1], s[3]}, {s[0], s[3]}};
            for (unsigned c = 0; c < 4; ++c) {
                float* p = v + 4 * (4 * q + c);
                p[0] = corners[c][0], p[1] = corners[c][1], p[2] = s[4], p[3] = -1e30f;
            }
            const unsigned tris[6] = {0, 1, 2, 0, 2, 3};
            for (unsigned i = 0; i < 6; ++i) t[6 * q + i] = 4 * q + tris[i];
        }
        rtcCommitGeometry(g);
        soup = rtcAttachGeometry(scene, g);
        rtcReleaseGeometry(g);
        rtcCommitScene(scene);
    }
    ~Soup() {
        rtcReleaseScene(scene);
        rtcReleaseDevice(device);
    }
};

// The hit of a ray from `o` along unit `d` in `scene`, as a tracer gets it from rtcIntersect1. instID[0]
// starts as junk: Embree itself must report RTC_INVALID_GEOMETRY_ID there for a hit outside instances.
RTCHit hit_in(RTCScene scene, glm::vec3 o, glm::vec3 d) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh{};
    rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
    rh.ray.tfar = std::numeric_limits<float>::infinity();
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = 12345;
    rtcIntersect1(scene, &context, &rh);
    return rh.hit;
}

void check_bounds(const std::optional<raycache::CubeBounds>& b, glm::vec3 centre, float half_size) {
    REQUIRE(b);
    CHECK(b->centre.x == doctest::Approx(centre.x));
    CHECK(b->centre.y == doctest::Approx(centre.y));
    CHECK(b->centre.z == doctest::Approx(centre.z));
    CHECK(b->half_size == doctest::Approx(half_size));
}

} // namespace

TEST_CASE("primitives are counted and triangle ranges measured from the Embree geometry, whatever its vertex stride") {
    Soup s;
    CHECK(raycache::embree::primitive_count(s.scene, s.soup) == 8u);
    World w;
    CHECK(raycache::embree::primitive_count(w.scene, w.floor) == 2u);
    CHECK_THROWS_WITH_AS(raycache::embree::primitive_count(w.scene, w.mirror), doctest::Contains("cannot count the primitives"),
                         std::invalid_argument); // a sphere: Embree's point queries do not reach it
    const raycache::CubeBounds b = raycache::embree::triangle_bounds(s.scene, s.soup, 2, 4);
    CHECK(b.centre.x == doctest::Approx(4.0f));
    CHECK(b.centre.y == doctest::Approx(1.0f));
    CHECK(b.centre.z == doctest::Approx(5.5f));
    CHECK(b.half_size == doctest::Approx(1.0f));
    CHECK_THROWS_WITH_AS(raycache::embree::triangle_bounds(s.scene, s.soup, 6, 3),
                         doctest::Contains("primitives 6..8 are past the end of geometry 0, which has 8 primitives"),
                         std::invalid_argument);
}

TEST_CASE("a move naming one primitive moves only the cube of its range, one naming the geometry every range's") {
    // Soup: A (triangles 0-1) around (0.5, 0.5, 5), half-size 0.5; B (triangles 2-5) around (4, 1, 5.5), half-size 1.
    for (const Technique technique : {Technique::cct, Technique::cdct}) {
        CAPTURE(static_cast<int>(technique));
        Soup s;
        SceneCache caches(technique);
        caches.attach_primitives(s.scene, {s.soup}, 0, 2, 16);
        caches.attach_primitives(s.scene, {s.soup}, 2, 4, 16);
        const ObjectId a{s.soup, RTC_INVALID_GEOMETRY_ID, 0}, b{s.soup, RTC_INVALID_GEOMETRY_ID, 2};
        // B moves by (10, 0, 0), named by its triangle 3.
        SceneChange change;
        change.moved.push_back({ObjectId{s.soup, RTC_INVALID_GEOMETRY_ID, 3}, BoundingSphere{{4, 1, 5.5f}, 1.5f},
                                BoundingSphere{{14, 1, 5.5f}, 1.5f}, std::nullopt});
        CHECK(caches.scene_changed(change, Invalidation::none).cubes_moved == 1u);
        check_bounds(caches.object_bounds(a), {0.5f, 0.5f, 5.0f}, 0.5f);
        check_bounds(caches.object_bounds(b), {14.0f, 1.0f, 5.5f}, 1.0f);
        // Where its cube sits now, given: B's alone.
        change.moved[0].cube = raycache::CubeBounds{{20, 1, 5.5f}, 2.0f};
        CHECK(caches.scene_changed(change, Invalidation::all).cubes_moved == 1u);
        check_bounds(caches.object_bounds(a), {0.5f, 0.5f, 5.0f}, 0.5f);
        check_bounds(caches.object_bounds(b), {20.0f, 1.0f, 5.5f}, 2.0f);
        // A primitive outside every range (the backdrop's 6) moves no cube; the whole geometry moves both.
        change.moved[0] = {ObjectId{s.soup, RTC_INVALID_GEOMETRY_ID, 6}, BoundingSphere{{0, 0, 10}, 15.0f}, BoundingSphere{{0, 1, 10}, 15.0f}, std::nullopt};
        CHECK(caches.scene_changed(change, Invalidation::exact).cubes_moved == 0u);
        change.moved[0].id = ObjectId{s.soup};
        CHECK(caches.scene_changed(change, Invalidation::exact).cubes_moved == 2u);
        check_bounds(caches.object_bounds(a), {0.5f, 1.5f, 5.0f}, 0.5f);
        check_bounds(caches.object_bounds(b), {20.0f, 2.0f, 5.5f}, 2.0f);
        // A CDCT cache's own bounds (what its searches measure from) follow: the same centres.
        caches.for_each_cdct_cache([&](ObjectId id, const raycache::CdctCache* cache) {
            if (!cache) return;
            check_bounds(cache->bounds(), id.prim_id == 0 ? glm::vec3(0.5f, 1.5f, 5.0f) : glm::vec3(20.0f, 2.0f, 5.5f),
                         id.prim_id == 0 ? 0.5f : 2.0f);
        });
    }
}

namespace {
// Caches that keep path records from the start, with no origin test, no confidence test and no resting,
// so that each store and move does only what the transitive tests below derive; with cubes of 8-texel faces
// for mirrors A (id 10, at the origin) and B (id 11, at (4, 0, 0)), half-size 1 (attach_a_and_b).
raycache::embree::SceneCacheSettings transitive_test_settings(bool transitive_by_direction = true) {
    raycache::embree::SceneCacheSettings settings;
    settings.path_records = raycache::embree::PathRecords::always;
    settings.origin_drift = -1.0f;
    settings.edge_threshold = -1.0f;
    settings.min_hit_rate = 0.0f;
    settings.transitive_by_direction = transitive_by_direction;
    return settings;
}
void attach_a_and_b(SceneCache& caches) {
    caches.attach({10}, 8, raycache::CubeBounds{glm::vec3(0.0f), 1.0f});
    caches.attach({11}, 8, raycache::CubeBounds{glm::vec3(4, 0, 0), 1.0f});
}
// The move of the tests below: the uncached ball X (id 12, radius 0.5) straight up from (3.3, 5, 0) to
// (3.3, 30, 0), under exact invalidation.
raycache::embree::InvalidationStatistics move_x_up(SceneCache& caches) {
    SceneChange change;
    change.moved.push_back({ObjectId{12}, BoundingSphere{{3.3f, 5, 0}, 0.5f}, BoundingSphere{{3.3f, 30, 0}, 0.5f}, std::nullopt});
    return caches.scene_changed(change, Invalidation::exact);
}
} // namespace

TEST_CASE("exact invalidation re-tests a cube that lost texels once another cube it reads has changed") {
    // Mirrors A (id 10, at the origin) and B (id 11, at (4, 0, 0)) and an uncached ball X (id 12) at
    // (3.3, 5, 0), radius 0.5, which moves straight up to (3.3, 30, 0). B holds one texel whose path hit X;
    // A one whose path hit X (toward +y) and one whose path hit only B (toward +x: the ray that B's cube
    // answered, as the tracer records it). X's move empties A's first texel and B's by their paths, so both
    // cubes change; A's second texel read B, which changed, so it must go too, though A itself lost texels
    // in the same pass. (A review found it kept: transitive passes tested only cubes that had not changed.)
    SceneCache caches(Technique::cct, transitive_test_settings());
    attach_a_and_b(caches);
    const std::uint64_t a = raycache::embree::path_key({10}), b = raycache::embree::path_key({11}), x = raycache::embree::path_key({12});
    REQUIRE((raycache::object_bits(b) & raycache::object_bits(x)) == 0u); // B's hits never read as X's
    REQUIRE((raycache::object_bits(a) & raycache::object_bits(x)) == 0u);
    auto store = [&](unsigned id, glm::vec3 o, glm::vec3 d, std::uint64_t hit, glm::vec3 point) {
        caches.leaving_ray({id}, o, glm::normalize(d), [&](raycache::PathRecord& path) {
            path.hit(hit, point);
            return TracedRay{glm::vec3(0.5f), glm::length(point - o)};
        });
    };
    store(11, {4, 1, 0}, {-0.7f, 3.5f, 0}, x, {3.3f, 4.5f, 0});              // B sees X
    store(10, {0, 1, 0}, {3.3f, 3.5f, 0}, x, {3.0f, 4.6f, 0});               // A sees X
    store(10, {1, 0, 0}, {1, 0.05f, 0.05f}, b, {3.0f, 0.1f, 0.1f});          // A sees B (B's cube answered)
    caches.begin_frame();
    REQUIRE(caches.statistics().valid_texels == 3u);
    const raycache::embree::InvalidationStatistics s = move_x_up(caches);
    CHECK(s.dropped_by_path == 2u);
    CHECK(s.dropped_transitively == 1u);
    CHECK(s.dropped == 3u);
    CHECK(caches.statistics().valid_texels == 0u);
}

TEST_CASE("exact invalidation keeps a path that read a changed cube only where that cube kept its texels") {
    // Mirrors A (id 10, at the origin) and B (id 11, at (4, 0, 0)) and an uncached ball X (id 12) at
    // (3.3, 5, 0), radius 0.5, which moves straight up to (3.3, 30, 0). B holds two texels, whose paths hit
    // only a far uncached wall W (id 13): toward (-0.2, 1, 0) (face +Y, sc = x / y = -0.2, the centre cell;
    // X, at sc = -0.7 / 5 from B's centre, lies in its cone) and toward +z. A then stores two texels toward
    // +x, each traced by a path that hit B and whose bounce off B was answered by B's cube, one from each of
    // B's texels: the tracer passes A's record to that nested leaving ray (`enclosing`), so A's records hold
    // the cells B's cube was read in, and what the answering texels' paths saw (W). X's move empties B's
    // first texel by its cone, and A's first texel, which read it, transitively; A's second read B only
    // toward +z, where B kept its texel, so it stays. (Records that did not track their cached reads would
    // lose both: the test before this one; so do they with SceneCacheSettings::transitive_by_direction off.)
    for (const bool by_direction : {true, false}) {
        CAPTURE(by_direction);
        SceneCache caches(Technique::cct, transitive_test_settings(by_direction));
        attach_a_and_b(caches);
        const std::uint64_t b = raycache::embree::path_key({11}), x = raycache::embree::path_key({12}), w = raycache::embree::path_key({13});
        REQUIRE((raycache::object_bits(b) & raycache::object_bits(x)) == 0u);
        REQUIRE((raycache::object_bits(w) & raycache::object_bits(x)) == 0u);
        const glm::vec3 to_x = glm::normalize(glm::vec3(-0.2f, 1, 0)), to_wall = glm::normalize(glm::vec3(0.05f, 0.05f, 1));
        auto traced_b = [&](std::uint64_t hit, glm::vec3 point) {
            return [=](raycache::PathRecord& path) {
                path.track_cached_reads(); // (they read no cube)
                path.hit(hit, point);
                return TracedRay{glm::vec3(0.5f), 5.0f};
            };
        };
        caches.leaving_ray({11}, {4, 1, 0}, to_x, traced_b(w, {3.5f, 40.0f, 0}));
        caches.leaving_ray({11}, {4, 0, 1}, to_wall, traced_b(w, {4.2f, 0.2f, 40}));
        caches.begin_frame();
        REQUIRE(caches.statistics().valid_texels == 2u);
        int b_traced = 0;
        auto store_a = [&](glm::vec3 d, glm::vec3 b_point, glm::vec3 b_direction) {
            caches.leaving_ray({10}, {1, 0, 0}, glm::normalize(d), [&](raycache::PathRecord& path) {
                path.track_cached_reads();
                path.hit(b, b_point);
                // The bounce off B: B's cube answers it (the trace below must not run), noted in A's record.
                caches.leaving_ray({11}, b_point, b_direction, [&](raycache::PathRecord&) {
                    ++b_traced;
                    return TracedRay{glm::vec3(0.0f), 1.0f};
                }, &path);
                return TracedRay{glm::vec3(0.5f), glm::length(b_point - glm::vec3(1, 0, 0))};
            });
        };
        store_a({1, 0.05f, 0.05f}, {3.0f, 0.1f, 0.1f}, to_x);
        store_a({1, -0.05f, -0.2f}, {3.0f, -0.1f, -0.3f}, to_wall);
        CHECK(b_traced == 0);
        caches.begin_frame();
        REQUIRE(caches.statistics().valid_texels == 4u);
        const raycache::embree::InvalidationStatistics s = move_x_up(caches);
        CHECK(s.dropped_by_cone == 1u);      // B's texel toward X
        CHECK(s.dropped_by_path == 0u);
        CHECK(s.dropped_transitively == (by_direction ? 1u : 2u)); // A's texel that read it (and the other)
        CHECK(s.dropped == (by_direction ? 2u : 3u));
        CHECK(caches.statistics().valid_texels == (by_direction ? 2u : 1u));
        auto answered = [&](unsigned id, glm::vec3 o, glm::vec3 d) {
            bool traced = false;
            caches.leaving_ray({id}, o, glm::normalize(d), [&] {
                traced = true;
                return TracedRay{glm::vec3(0.0f), 1.0f};
            });
            return !traced;
        };
        CHECK(answered(11, {4, 0, 1}, to_wall));
        CHECK_FALSE(answered(11, {4, 1, 0}, to_x));
        CHECK(answered(10, {1, 0, 0}, {1, -0.05f, -0.2f}) == by_direction);
        CHECK_FALSE(answered(10, {1, 0, 0}, {1, 0.05f, 0.05f}));
    }
}

TEST_CASE("a path that read the cube of an instance attached alone goes transitively when that cube changes") {
    // As the test before, with mirror B attached as an instance alone (attach({11}): instance 11, whose
    // geometry 0 a hit reaches as {geom 0, inst 11}): A's path hit B through the instance (the tracer records
    // path_key({0, 11})) and B's cube answered the bounce. X's move empties B's texel toward it by its cone;
    // B's cube changed under its own key, path_key({11}), which none of A's hits carries: A's texel must go
    // all the same, since its path read that cube there. (It was kept: the transitive step matched cubes to
    // paths by their hits' keys alone.) For the CCT and the CDCT (whose secant search from the hit point
    // (3, 0.1, 0.1) toward X meets B's stored point, 5 along B's texel's ray).
    for (const Technique technique : {Technique::cct, Technique::cdct}) {
        CAPTURE(static_cast<int>(technique));
        SceneCache caches(technique, transitive_test_settings());
        attach_a_and_b(caches);
        const ObjectId b_hit{0, 11};
        const std::uint64_t x = raycache::embree::path_key({12}), w = raycache::embree::path_key({13});
        REQUIRE((raycache::object_bits(raycache::embree::path_key({11})) & raycache::object_bits(raycache::embree::path_key(b_hit))) !=
                raycache::object_bits(raycache::embree::path_key({11})));
        REQUIRE((raycache::object_bits(w) & raycache::object_bits(x)) == 0u);
        const glm::vec3 b_origin(4, 1, 0), to_x = glm::normalize(glm::vec3(-0.2f, 1, 0));
        caches.leaving_ray(b_hit, b_origin, to_x, [&](raycache::PathRecord& path) {
            path.track_cached_reads();
            path.hit(w, {3.5f, 40.0f, 0});
            return TracedRay{glm::vec3(0.5f), 5.0f};
        });
        caches.begin_frame();
        REQUIRE(caches.statistics().valid_texels == 1u);
        // The bounce off B, from a point on the ray B's texel was stored from (so the CDCT's search meets it).
        const glm::vec3 b_point = b_origin + 0.5f * to_x;
        int b_traced = 0;
        caches.leaving_ray({10}, {1, 0, 0}, glm::normalize(b_point - glm::vec3(1, 0, 0)), [&](raycache::PathRecord& path) {
            path.track_cached_reads();
            path.hit(raycache::embree::path_key(b_hit), b_point);
            caches.leaving_ray(b_hit, b_point, to_x, [&](raycache::PathRecord&) {
                ++b_traced;
                return TracedRay{glm::vec3(0.0f), 1.0f};
            }, &path);
            return TracedRay{glm::vec3(0.5f), glm::length(b_point - glm::vec3(1, 0, 0))};
        });
        REQUIRE(b_traced == 0); // B's cube answered
        caches.begin_frame();
        REQUIRE(caches.statistics().valid_texels == 2u);
        const raycache::embree::InvalidationStatistics s = move_x_up(caches);
        CHECK(s.dropped_by_cone == 1u); // B's texel toward X
        CHECK(s.dropped_transitively == 1u); // A's, which read it
        CHECK(caches.statistics().valid_texels == 0u);
    }
}

TEST_CASE("a cached answer nested in a traced path brings what the answering texel's path saw into that path's record") {
    // Mirror B (id 11, at (4, 0, 0)) holds a texel toward +z whose path hit the uncached ball X (id 12) at
    // (4, 3, 6) and cast a shadow ray (its ray, from (4, 0, 1), hit 5 further on: the CDCT stores the point
    // (4, 0, 6)); mirror A's (id 10) traced path hits B, whose cube answers the bounce: for the CCT a ray
    // toward +z from (3, 0, 0), for the CDCT one from (4, 0, 0.9), whose search meets the stored point. A's
    // record then holds B's texel's hits and shadow ray, as if A's trace had followed the bounce itself,
    // and the cell B's cube was read in (+Z's centre: for the CDCT, the cone from the centre through the
    // box exit (4, 0, 1) and on along +z). When X moves, A's texel goes with B's by their paths (and would
    // even if B's texel had since been replaced, which a test of B's cube alone at the move could not know).
    for (const Technique technique : {Technique::cct, Technique::cdct}) {
        CAPTURE(static_cast<int>(technique));
        const bool cdct = technique == Technique::cdct;
        SceneCache caches(technique, transitive_test_settings());
        attach_a_and_b(caches);
        const std::uint64_t b = raycache::embree::path_key({11}), x = raycache::embree::path_key({12});
        const glm::vec3 up_z(0, 0, 1);
        caches.leaving_ray({11}, {4, 0, 1}, up_z, [&](raycache::PathRecord& path) {
            path.track_cached_reads(); // (it read no cube)
            path.hit(x, {4, 3, 6});
            path.lit = true;
            return TracedRay{glm::vec3(0.5f), 5.0f};
        });
        caches.begin_frame();
        raycache::PathRecord seen;
        int b_traced = 0;
        const glm::vec3 b_point = cdct ? glm::vec3(4, 0, 0.9f) : glm::vec3(3, 0, 0);
        caches.leaving_ray({10}, {1, 0, 0}, glm::vec3(1, 0, 0), [&](raycache::PathRecord& path) {
            path.track_cached_reads();
            path.hit(b, b_point);
            caches.leaving_ray({11}, b_point, up_z, [&] { return ++b_traced, TracedRay{glm::vec3(0.0f), 1.0f}; }, &path);
            seen = path;
            return TracedRay{glm::vec3(0.5f), 2.0f};
        });
        REQUIRE(b_traced == 0); // B's cube answered
        CHECK(seen.objects == (raycache::object_bits(b) | raycache::object_bits(x)));
        CHECK(seen.lit);
        CHECK(seen.vertex_lo == glm::min(b_point, glm::vec3(4, 3, 6)));
        CHECK(seen.vertex_hi == glm::max(b_point, glm::vec3(4, 3, 6)));
        CHECK(seen.cached_reads == raycache::direction_cell_bit(RAYCACHE_FACE_POSITIVE_Z, 1, 1));
        caches.begin_frame();
        SceneChange change;
        change.lights = {glm::vec3(4, 20, 20)};
        change.moved.push_back({ObjectId{12}, BoundingSphere{{4, 3, 6}, 0.5f}, BoundingSphere{{4, 3.5f, 6}, 0.5f}, std::nullopt});
        const raycache::embree::InvalidationStatistics s = caches.scene_changed(change, Invalidation::exact);
        CHECK(s.dropped_by_path == 2u);
        CHECK(s.dropped == 2u);
    }
}

TEST_CASE("two objects in one triangle geometry get a cube each, and a hit's primID finds its object's cube") {
    Soup s;
    SceneCache caches(Technique::cct);
    caches.attach_primitives(s.scene, {s.soup}, 2, 4, 8); // B first: ranges need not come in order
    caches.attach_primitives(s.scene, {s.soup}, 0, 2, 16);
    CHECK(caches.object_count() == 2);
    const std::vector<ObjectId> objects = caches.objects();
    CHECK(objects[0].prim_id == 2u);
    CHECK(objects[1].prim_id == 0u);
    // Each cube sits around its own triangles.
    check_bounds(caches.object_bounds({s.soup, RTC_INVALID_GEOMETRY_ID, 1}), {0.5f, 0.5f, 5.0f}, 0.5f);
    check_bounds(caches.object_bounds({s.soup, RTC_INVALID_GEOMETRY_ID, 5}), {4.0f, 1.0f, 5.5f}, 1.0f);
    CHECK(caches.face_size({s.soup, RTC_INVALID_GEOMETRY_ID, 0}) == 16);
    CHECK(caches.face_size({s.soup, RTC_INVALID_GEOMETRY_ID, 3}) == 8);
    // The backdrop's triangles, and the geometry without a primitive, have none.
    CHECK_FALSE(caches.has_cache({s.soup, RTC_INVALID_GEOMETRY_ID, 6}));
    CHECK_FALSE(caches.has_cache({s.soup, RTC_INVALID_GEOMETRY_ID, 7}));
    CHECK_FALSE(caches.has_cache({s.soup, RTC_INVALID_GEOMETRY_ID, 8}));
    CHECK_FALSE(caches.has_cache({s.soup}));

    // Real hits, through object_of(hit), each on its object's cube.
    int traces = 0;
    auto leave = [&](glm::vec3 from) {
        const RTCHit hit = hit_in(s.scene, from, {0, 0, 1});
        REQUIRE(hit.geomID == s.soup);
        CHECK(hit.instID[0] == RTC_INVALID_GEOMETRY_ID); // Embree's own answer for a plain hit
        const ObjectId id = raycache::embree::object_of(hit);
        CHECK(id.geom_id == s.soup);
        CHECK(id.inst_id == RTC_INVALID_GEOMETRY_ID);
        CHECK(id.prim_id == hit.primID);
        caches.leaving_ray(id, from, {0, 0, -1}, [&] { ++traces; return TracedRay{glm::vec3(0.5f), 5.0f}; });
        return hit.primID;
    };
    CHECK(leave({0.25f, 0.75f, 0}) <= 1u);         // object A
    const unsigned on_b = leave({4.5f, 0.5f, 0}); // object B's front square
    CHECK((on_b == 2u || on_b == 3u));
    CHECK(leave({-5, -5, 0}) >= 6u);              // the backdrop: traced, no cube
    CHECK(traces == 3);
    CHECK(caches.object_statistics({s.soup, RTC_INVALID_GEOMETRY_ID, 0})->lookups == 1u);
    CHECK(caches.object_statistics({s.soup, RTC_INVALID_GEOMETRY_ID, 2})->lookups == 1u);
    CHECK_FALSE(caches.object_statistics({s.soup, RTC_INVALID_GEOMETRY_ID, 6}));
    const auto frame = caches.begin_frame();
    CHECK(frame.lookups == 2u);
    CHECK(frame.stores == 2u);
    // Next frame: both answered from their own cubes.
    leave({0.25f, 0.75f, 0});
    leave({4.5f, 0.5f, 0});
    CHECK(traces == 3);
    CHECK(caches.begin_frame().hits == 2u);
}

TEST_CASE("primitive ranges that overlap, run past the geometry, or clash with a whole-geometry cube are refused clearly") {
    Soup s;
    World w;
    SceneCache caches(Technique::cct);
    caches.attach_primitives(s.scene, {s.soup}, 2, 4, 8);
    using doctest::Contains;
    CHECK_THROWS_WITH_AS(caches.attach_primitives(s.scene, {s.soup}, 5, 2, 8),
                         Contains("primitives 5..6 of geometry 0 overlap primitives 2..5, which already have a cube"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(caches.attach_primitives(s.scene, {s.soup}, 0, 3, 8), Contains("overlap primitives 2..5"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(caches.attach_primitives(s.scene, {s.soup}, 3, 1, 8), Contains("overlap primitives 2..5"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(caches.attach_primitives(s.scene, {s.soup}, 0, 8, 8), Contains("overlap"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(caches.attach_primitives(s.scene, {s.soup}, 6, 3, 8),
                         Contains("primitives 6..8 are past the end of geometry 0, which has 8 primitives (0..7)"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(caches.attach_primitives(s.scene, {s.soup}, 4294967295u, 2, 8, raycache::CubeBounds{{0, 0, 0}, 1.0f}),
                         Contains("past the end"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(caches.attach_primitives(s.scene, {s.soup}, 0, 0, 8), Contains("empty primitive range"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(caches.attach_primitives(s.scene, {s.soup}, 0, 2, -1), Contains("face size"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(caches.attach(s.scene, {s.soup}, 8), Contains("split into primitive ranges"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(caches.attach(s.scene, raycache::embree::ObjectId{s.soup, RTC_INVALID_GEOMETRY_ID, 0}, 8),
                         Contains("attach_primitives()"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(caches.attach_primitives(s.scene, {s.soup, 3}, 0, 2, 8), Contains("pass their cube's bounds"),
                         std::invalid_argument);
    // A geometry with a cube as a whole cannot have ranges; one whose primitives Embree cannot count neither.
    SceneCache whole(Technique::cct);
    whole.attach(w.scene, {w.floor}, 8);
    CHECK_THROWS_WITH_AS(whole.attach_primitives(w.scene, {w.floor}, 0, 1, 8), Contains("already has a cube for all its primitives"),
                         std::invalid_argument);
    CHECK_THROWS_WITH_AS(whole.attach_primitives(w.scene, {w.mirror}, 0, 1, 8, raycache::CubeBounds{{1, 2, 3}, 0.5f}),
                         Contains("cannot count the primitives of geometry"), std::invalid_argument);
    // The refusals changed nothing: still one range, found as before, its neighbours free.
    CHECK(caches.object_count() == 1);
    CHECK(caches.has_cache({s.soup, RTC_INVALID_GEOMETRY_ID, 2}));
    CHECK_FALSE(caches.has_cache({s.soup, RTC_INVALID_GEOMETRY_ID, 1}));
    caches.attach_primitives(s.scene, {s.soup}, 0, 2, 8); // adjacent ranges are fine
    caches.attach_primitives(s.scene, {s.soup}, 6, 2, 8);
    CHECK(caches.object_count() == 3);
    check_bounds(caches.object_bounds({s.soup, RTC_INVALID_GEOMETRY_ID, 1}), {0.5f, 0.5f, 5.0f}, 0.5f);
    check_bounds(caches.object_bounds({s.soup, RTC_INVALID_GEOMETRY_ID, 4}), {4.0f, 1.0f, 5.5f}, 1.0f);
    check_bounds(caches.object_bounds({s.soup, RTC_INVALID_GEOMETRY_ID, 7}), {0.0f, 0.0f, 10.0f}, 10.0f);
    // A geometry detached from the scene has no primitives to give a cube.
    SceneCache later(Technique::cct);
    rtcDetachGeometry(s.scene, s.soup);
    rtcCommitScene(s.scene);
    CHECK_THROWS_WITH_AS(later.attach_primitives(s.scene, {s.soup}, 0, 2, 8), Contains("no geometry with id"), std::invalid_argument);
}

TEST_CASE("a primitive range inside an instance gets its cube from the caller's bounds and is found by hits through the instance") {
    Soup s;
    RTCScene top = rtcNewScene(s.device);
    const unsigned instance_id = add_instance(s.device, top, s.scene, {0, 0, 100});
    rtcCommitScene(top);
    {
        SceneCache caches(Technique::cct);
        // `scene` is the instanced scene, which holds the geometry; the bounds are in world space.
        caches.attach_primitives(s.scene, {s.soup, instance_id}, 0, 2, 16, raycache::CubeBounds{{0.5f, 0.5f, 105}, 0.5f});
        const RTCHit hit = hit_in(top, {0.5f, 0.25f, 0}, {0, 0, 1});
        REQUIRE(hit.geomID == s.soup);
        CHECK(hit.instID[0] == instance_id);
        const ObjectId id = raycache::embree::object_of(hit);
        CHECK(caches.has_cache(id));
        check_bounds(caches.object_bounds(id), {0.5f, 0.5f, 105}, 0.5f);
        CHECK_FALSE(caches.has_cache({s.soup, RTC_INVALID_GEOMETRY_ID, hit.primID})); // not outside the instance
        CHECK_FALSE(caches.has_cache(raycache::embree::object_of(hit_in(top, {4.5f, 0.5f, 0}, {0, 0, 1})))); // object B
        caches.leaving_ray(id, {0.5f, 0.25f, 105}, {0, 0, -1}, [] { return TracedRay{glm::vec3(0.5f), 2.0f}; });
        CHECK(caches.begin_frame().stores == 1u);
    }
    rtcReleaseScene(top);
}

TEST_CASE("object_of(hit) of real Embree hits finds the cubes the README attaches: a geometry, and an instance by its own id") {
    World w;
    RTCScene top = rtcNewScene(w.device);
    const unsigned plain = w.add_sphere(top, {0, 0, 10}, 1.0f);
    const unsigned instance_id = add_instance(w.device, top, w.scene, {20, 0, 0}); // the World: mirror, floor, ball
    rtcCommitScene(top);
    {
        SceneCache caches(Technique::cct);
        caches.attach(top, {plain});
        caches.attach(top, {instance_id});
        const RTCHit on_plain = hit_in(top, {0, 0, 0}, {0, 0, 1});
        REQUIRE(on_plain.geomID == plain);
        CHECK(on_plain.instID[0] == RTC_INVALID_GEOMETRY_ID);
        const RTCHit on_mirror = hit_in(top, {21, 2, 0}, {0, 0, 1}); // the instanced mirror sphere
        REQUIRE(on_mirror.geomID == w.mirror);
        CHECK(on_mirror.instID[0] == instance_id);
        const RTCHit on_floor = hit_in(top, {15, 5, 0}, {0, -1, 0}); // the instanced floor
        REQUIRE(on_floor.geomID == w.floor);
        for (const RTCHit& hit : {on_plain, on_mirror, on_floor})
            caches.leaving_ray(raycache::embree::object_of(hit), {0, 0, 0}, {0, 1, 0}, [] { return TracedRay{glm::vec3(0.5f), 1.0f}; });
        CHECK(caches.object_statistics({plain})->lookups == 1u);
        CHECK(caches.object_statistics({instance_id})->lookups == 2u); // both geometries reached through it
        CHECK(caches.begin_frame().lookups == 3u);
    }
    rtcReleaseScene(top);
}
