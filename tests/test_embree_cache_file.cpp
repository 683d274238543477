// SceneCache::save and load: a whole scene's cubes go to one file and come back into a fresh SceneCache bit
// for bit, answering the next frame's rays exactly as the saved cache would (tile origin boxes and CCT edge
// marks saved, pyramids rebuilt); a file that does not fit the
// cache (scene, objects, placements, fixed face sizes, technique) is refused and the cache keeps its cubes.
// No Embree scene is needed: cubes are attached with explicit bounds and rays traced against an analytic world.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <raycache/embree/scene_cache.hpp>

#include "test_bits.hpp"
#include "test_cache_files.hpp"
#include "test_random.hpp"

namespace {

using raycache::CubeBounds;
using raycache::SceneIdentity;
using raycache::TracedRay;
using raycache::embree::ObjectId;
using raycache::embree::SceneCache;
using raycache::embree::SceneCacheSettings;
using raycache::embree::Technique;

const SceneIdentity scene{42, "three balls"};

// Three cached objects: two plain geometries and one reached through an instance.
const ObjectId objects[] = {{0}, {3}, {1, 5}};
const CubeBounds placements[] = {{glm::vec3(0.0f), 1.0f}, {glm::vec3(4.0f, 0.5f, -2.0f), 0.5f}, {glm::vec3(-3.0f, 1.0f, 6.0f), 2.0f}};

// The analytic world: a sphere of radius 20 around the origin, coloured by where a ray meets it, with a
// checker pattern whose edges the CCT's confidence test marks doubtful.
TracedRay trace_world(const glm::vec3& origin, const glm::vec3& direction) {
    const glm::vec3 d = glm::normalize(direction);
    const float b = glm::dot(origin, d), c = glm::dot(origin, origin) - 400.0f;
    const float t = -b + std::sqrt(b * b - c);
    const glm::vec3 hit = origin + t * d;
    const glm::ivec3 square = glm::ivec3(glm::floor(hit / 6.0f));
    const float checker = (square.x + square.y + square.z) % 2 ? 1.0f : 0.3f;
    return TracedRay{checker * (0.5f + 0.5f * glm::normalize(hit)), t};
}

// One leaving ray of object k: from a point on its box's surface sphere, in a random direction.
struct Ray {
    int object;
    glm::vec3 origin, direction;
};
std::vector<Ray> rays_of_frame(std::uint64_t seed, int count) {
    Lcg rng{seed};
    std::vector<Ray> rays;
    for (int i = 0; i < count; ++i) {
        const int k = static_cast<int>(rng.next() % 3);
        const glm::vec3 out = glm::normalize(glm::vec3(rng.signed_uniform(), rng.signed_uniform(), rng.signed_uniform()) + 1e-3f);
        const glm::vec3 direction = glm::normalize(out + 0.7f * glm::vec3(rng.signed_uniform(), rng.signed_uniform(), rng.signed_uniform()));
        rays.push_back({k, placements[k].centre + placements[k].half_size * out, direction});
    }
    return rays;
}

// Renders one frame of rays through the cache; returns the colours and ends the frame.
std::vector<glm::vec3> frame(SceneCache& caches, const std::vector<Ray>& rays, raycache::embree::SceneCacheStatistics* stats = nullptr) {
    std::vector<glm::vec3> colours;
    for (const Ray& r : rays)
        colours.push_back(caches.leaving_ray(objects[r.object], r.origin, r.direction, [&] { return trace_world(r.origin, r.direction); }));
    const raycache::embree::SceneCacheStatistics s = caches.begin_frame();
    if (stats) *stats = s;
    return colours;
}

SceneCacheSettings settings_with_first_size(int first_face_size) {
    SceneCacheSettings s;
    s.adaptive.first_face_size = first_face_size;
    return s;
}

// A cache with a cube on each object: face_size texels, or adaptive (0) starting at 64; the CDCT searches
// with the relief walk over a depth pyramid when `relief`, else with the default search.
std::unique_ptr<SceneCache> make_cache(Technique technique, int face_size, bool relief = false) {
    SceneCacheSettings settings = settings_with_first_size(64);
    if (relief) settings.relief.search = raycache::DepthSearch::relief;
    // Files hold texels, not whether a cube rests (a loaded cache starts working and its frames decide):
    // cubes that never rest answer the frame after a load as the saved cache would.
    settings.min_hit_rate = 0.0f;
    auto caches = std::make_unique<SceneCache>(technique, settings);
    for (int k = 0; k < 3; ++k) caches->attach(objects[k], face_size, placements[k]);
    return caches;
}

std::vector<std::uint8_t> saved_bytes(const SceneCache& caches, const ScratchFolder& folder, const std::string& name) {
    caches.save(folder.file(name), scene);
    return raycache::read_whole_file(folder.file(name));
}

void check_round_trip(Technique technique, int face_size, bool relief = false) {
    ScratchFolder folder("scene-cache");
    std::unique_ptr<SceneCache> warm_cache = make_cache(technique, face_size, relief), loaded_cache = make_cache(technique, face_size, relief);
    SceneCache &warm = *warm_cache, &loaded = *loaded_cache;
    // Pre-filled (so CDCT searches find full cubes), then two frames of rays.
    for (const ObjectId& id : objects)
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < face_size; ++row) warm.prefill_row(id, face, row, trace_world);
    warm.begin_frame();
    for (std::uint64_t f = 0; f < 2; ++f) frame(warm, rays_of_frame(100 + f, 3000));
    const std::vector<std::uint8_t> bytes = saved_bytes(warm, folder, "warm.rcc");

    loaded.load(folder.file("warm.rcc"), scene);
    for (int k = 0; k < 3; ++k) CHECK(loaded.face_size(objects[k]) == warm.face_size(objects[k]));
    // Saved again, the loaded cache writes the same bytes: every texel of every cube, bit for bit.
    CHECK(saved_bytes(loaded, folder, "again.rcc") == bytes);
    const raycache::embree::SceneCacheStatistics before = loaded.statistics();
    CHECK(before.valid_texels == warm.statistics().valid_texels);
    CHECK(before.lookups == 0u);

    // The next frame: the loaded cache answers every ray as the saved one does, with the same texels read
    // (so the CDCT's depth pyramid was rebuilt to what the saved cache kept up to date).
    raycache::embree::SceneCacheStatistics a, b;
    const std::vector<Ray> next = rays_of_frame(999, 3000);
    const std::vector<glm::vec3> from_warm = frame(warm, next, &a), from_loaded = frame(loaded, next, &b);
    CHECK(a.hits > a.lookups / 20); // rays leaving from all over the box: the CCT's origin test traces many
    CHECK(b.hits == a.hits);
    CHECK(b.texels_read == a.texels_read);
    CHECK(b.doubtful_texels == a.doubtful_texels); // the CCT's edge marks came back
    if (technique == Technique::cct) CHECK(a.doubtful_texels > 0u);
    int same = 0;
    for (std::size_t i = 0; i < next.size(); ++i) same += same_bits(from_warm[i], from_loaded[i]);
    CHECK(same == static_cast<int>(next.size()));
}

} // namespace

TEST_CASE("a CCT SceneCache loaded from its file holds every texel bit for bit and answers the next frame as the saved one") {
    check_round_trip(Technique::cct, 48);
}

TEST_CASE("a CDCT SceneCache loaded from its file holds every texel bit for bit and searches as the saved one") {
    check_round_trip(Technique::cdct, 40);
}

TEST_CASE("a CDCT SceneCache searching over depth pyramids searches after a load exactly as before: its pyramids are rebuilt") {
    check_round_trip(Technique::cdct, 40, true);
}

TEST_CASE("adaptive cubes load at the face size they were saved with") {
    ScratchFolder folder("adaptive");
    for (Technique technique : {Technique::cct, Technique::cdct}) {
        std::unique_ptr<SceneCache> warm_cache = make_cache(technique, raycache::embree::adaptive_face_size);
        std::unique_ptr<SceneCache> loaded_cache = make_cache(technique, raycache::embree::adaptive_face_size);
        SceneCache &warm = *warm_cache, &loaded = *loaded_cache;
        for (std::uint64_t f = 0; f < 3; ++f) frame(warm, rays_of_frame(7 + f, 400)); // few rays: the cubes shrink
        int changed = 0;
        for (const ObjectId& id : objects) changed += warm.face_size(id) != 64;
        REQUIRE(changed > 0);
        warm.save(folder.file("warm.rcc"), scene);
        loaded.load(folder.file("warm.rcc"), scene);
        for (const ObjectId& id : objects) CHECK(loaded.face_size(id) == warm.face_size(id));
        CHECK(saved_bytes(loaded, folder, "again.rcc") == raycache::read_whole_file(folder.file("warm.rcc")));
    }
}

TEST_CASE("loaded adaptive cubes move with the saved cache's hysteresis, not as a first guess") {
    // The saved cubes were sized from counted rays; a frame whose rays call for a size one half-octave
    // step away (twice the rays: sqrt(2) the texels per edge) must not move them, in the loaded cache as in
    // the saved one (hysteresis of 2 steps). A cube still at its first guess would jump to the new size.
    ScratchFolder folder("adaptive-hysteresis");
    for (Technique technique : {Technique::cct, Technique::cdct}) {
        CAPTURE(static_cast<int>(technique));
        std::unique_ptr<SceneCache> warm_cache = make_cache(technique, raycache::embree::adaptive_face_size);
        std::unique_ptr<SceneCache> loaded_cache = make_cache(technique, raycache::embree::adaptive_face_size);
        SceneCache &warm = *warm_cache, &loaded = *loaded_cache;
        for (std::uint64_t f = 0; f < 3; ++f) frame(warm, rays_of_frame(7 + f, 20000));
        warm.save(folder.file("warm.rcc"), scene);
        loaded.load(folder.file("warm.rcc"), scene);
        std::vector<int> saved_sizes;
        for (const ObjectId& id : objects) saved_sizes.push_back(warm.face_size(id));
        const std::vector<Ray> more = rays_of_frame(20, 40000);
        frame(warm, more);
        frame(loaded, more);
        for (std::size_t k = 0; k < saved_sizes.size(); ++k) {
            CHECK(warm.face_size(objects[k]) == saved_sizes[k]);
            CHECK(loaded.face_size(objects[k]) == saved_sizes[k]);
        }
    }
}

TEST_CASE("a SceneCache refuses a file that does not fit it, says why, and keeps its cubes") {
    ScratchFolder folder("scene-refused");
    std::unique_ptr<SceneCache> warm = make_cache(Technique::cct, 32), target_cache = make_cache(Technique::cct, 32);
    frame(*warm, rays_of_frame(1, 2000));
    warm->save(folder.file("warm.rcc"), scene);

    SceneCache& target = *target_cache;
    frame(target, rays_of_frame(2, 500));
    const std::vector<std::uint8_t> before = saved_bytes(target, folder, "before.rcc");
    const std::string file = folder.file("warm.rcc");
    auto refusal = [&](SceneCache& caches, const SceneIdentity& identity) {
        return cache_file_error([&] { caches.load(file, identity); });
    };

    CHECK(contains(refusal(target, SceneIdentity{43, scene.name}), "saved for scene 'three balls' (hash 0x000000000000002a)"));

    SceneCache fewer(Technique::cct, settings_with_first_size(64));
    fewer.attach(objects[0], 32, placements[0]);
    fewer.attach(objects[1], 32, placements[1]);
    CHECK(contains(refusal(fewer, scene), "the file has a cube for geometry 1 of instance 5, which has none here"));

    std::unique_ptr<SceneCache> more = make_cache(Technique::cct, 32);
    more->attach(ObjectId{9}, 32, placements[0]);
    CHECK(contains(refusal(*more, scene), "geometry 9 has a cube here but none in the file"));

    SceneCache moved(Technique::cct, settings_with_first_size(64));
    moved.attach(objects[0], 32, placements[0]);
    moved.attach(objects[1], 32, CubeBounds{placements[1].centre, 0.5001f});
    moved.attach(objects[2], 32, placements[2]);
    CHECK(contains(refusal(moved, scene), "geometry 3's cube sits at centre (4, 0.5, -2), half-size 0.500100017, in the file at"));

    CHECK(contains(refusal(*make_cache(Technique::cct, 64), scene), "geometry 0's cube has 64-texel faces (fixed), in the file 32"));

    CHECK(contains(refusal(*make_cache(Technique::cdct, 32), scene), "holds CCT cubes, this cache is CDCT"));

    std::vector<std::uint8_t> cut = raycache::read_whole_file(file);
    cut.resize(cut.size() - 9);
    raycache::write_file_atomically(folder.file("cut.rcc"), cut);
    CHECK(contains(cache_file_error([&] { target.load(folder.file("cut.rcc"), scene); }), "truncated"));

    // After all of that the target still holds what it held, bit for bit.
    CHECK(saved_bytes(target, folder, "after.rcc") == before);
}

TEST_CASE("primitive ranges of one geometry are saved as cubes of their own and loaded only into the same ranges") {
    // One triangle geometry holding two quads (triangles 0-1 at x in [0, 1], 2-3 at x in [5, 6]).
    RTCDevice device = rtcNewDevice(nullptr);
    RTCScene embree_scene = rtcNewScene(device);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 8));
    const float corners[24] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 5, 0, 0, 6, 0, 0, 6, 1, 0, 5, 1, 0};
    for (int i = 0; i < 24; ++i) v[i] = corners[i];
    auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), 4));
    const unsigned triangles[12] = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
    for (int i = 0; i < 12; ++i) t[i] = triangles[i];
    rtcCommitGeometry(g);
    const unsigned geometry = rtcAttachGeometry(embree_scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(embree_scene);

    // Ranges 0..split-1 and split..3, each with a 16-texel cube.
    auto make = [&](unsigned split) {
        auto caches = std::make_unique<SceneCache>(Technique::cct, SceneCacheSettings{});
        caches->attach_primitives(embree_scene, ObjectId{geometry}, 0, split, 16);
        caches->attach_primitives(embree_scene, ObjectId{geometry}, split, 4 - split, 16);
        return caches;
    };
    ScratchFolder folder("ranges");
    std::unique_ptr<SceneCache> warm = make(2), loaded = make(2), other = make(1);
    Lcg rng{31};
    for (int i = 0; i < 4000; ++i) {
        const unsigned prim = rng.next() % 4;
        const glm::vec3 origin(prim < 2 ? 0.5f : 5.5f, 0.5f, 0.0f);
        const glm::vec3 direction(rng.signed_uniform(), rng.signed_uniform(), 1.0f);
        warm->leaving_ray(ObjectId{geometry, RTC_INVALID_GEOMETRY_ID, prim}, origin, direction, [&] { return trace_world(origin, direction); });
    }
    warm->begin_frame();
    const std::vector<std::uint8_t> bytes = saved_bytes(*warm, folder, "warm.rcc");
    loaded->load(folder.file("warm.rcc"), scene);
    CHECK(saved_bytes(*loaded, folder, "again.rcc") == bytes);
    CHECK(loaded->statistics().valid_texels == warm->statistics().valid_texels);
    CHECK(contains(cache_file_error([&] { other->load(folder.file("warm.rcc"), scene); }),
                   "primitives 0..0 of geometry " + std::to_string(geometry) + " has a cube here but none in the file"));
    CHECK(other->statistics().valid_texels == 0u);

    warm.reset();
    loaded.reset();
    other.reset();
    rtcReleaseScene(embree_scene);
    rtcReleaseDevice(device);
}
