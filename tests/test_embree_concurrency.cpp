// SceneCache::scene_changed with its passes spread over threads: a ring of cached mirror balls, each
// reflecting the others, filled through leaving_ray's recording callback; one ball moves. The parallel
// invalidation must empty exactly the texels the serial one empties, in every cube (labelled concurrency:
// run under TSan).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>
#include <thread>
#include <vector>

#include <glm/glm.hpp>

#include "raycache/embree/scene_cache.hpp"

namespace {

using raycache::PathRecord;
using raycache::TracedRay;
using raycache::embree::Invalidation;
using raycache::embree::InvalidationStatistics;
using raycache::embree::ObjectId;
using raycache::embree::SceneCache;
using raycache::embree::Technique;

constexpr int balls = 8;
constexpr float ring = 3.0f, radius = 0.5f;

glm::vec3 centre_of(int i) {
    const float a = 6.2831853f * static_cast<float>(i) / balls;
    return glm::vec3(ring * std::cos(a), 0.0f, ring * std::sin(a));
}

// The nearest ball a ray meets (distance in *t), or -1; the ray leaves ball `from`, which it skips.
int nearest(const glm::vec3& o, const glm::vec3& d, int from, float* t) {
    int best = -1;
    *t = std::numeric_limits<float>::infinity();
    for (int i = 0; i < balls; ++i) {
        if (i == from) continue;
        const glm::vec3 oc = o - centre_of(i);
        const float b = glm::dot(oc, d), c = glm::dot(oc, oc) - radius * radius, h = b * b - c;
        if (h < 0.0f) continue;
        const float s = -b - std::sqrt(h);
        if (s > 1e-4f && s < *t) *t = s, best = i;
    }
    return best;
}

// A leaving ray of ball `from`: its first hit's colour, with a shadow ray toward a light above and one
// mirror bounce from the hit, all recorded as the Embree tracer records them.
TracedRay trace(const glm::vec3& o, const glm::vec3& d, int from, PathRecord& path) {
    float t = 0.0f;
    const int i = nearest(o, d, from, &t);
    if (i < 0) return {glm::vec3(0.1f, 0.2f, 0.4f) + 0.2f * d, std::numeric_limits<float>::infinity()};
    const glm::vec3 p = o + t * d;
    path.hit(raycache::embree::path_key(ObjectId{static_cast<unsigned>(i)}), p);
    const glm::vec3 n = glm::normalize(p - centre_of(i));
    path.lit = true;
    const glm::vec3 r = glm::reflect(d, n);
    float t2 = 0.0f;
    const int j = nearest(p + 1e-3f * n, r, i, &t2);
    if (j < 0) path.escaped(r);
    else path.hit(raycache::embree::path_key(ObjectId{static_cast<unsigned>(j)}), p + t2 * r), path.chained = true;
    const float shade = 0.3f + 0.7f * std::max(0.0f, n.y);
    return {glm::vec3(0.2f + 0.1f * static_cast<float>(i), shade, j < 0 ? 0.5f : 0.1f * static_cast<float>(j)), t};
}

// The caches after two frames of leaving rays from every ball, at `face_size` (adaptive_face_size: the
// cubes shrink after the first frame), each frame ended through `end_frame(caches)`.
template <class EndFrame>
void fill(SceneCache& caches, int face_size, EndFrame&& end_frame) {
    for (int i = 0; i < balls; ++i) caches.attach(ObjectId{static_cast<unsigned>(i)}, face_size, raycache::CubeBounds{centre_of(i), radius});
    for (int frame = 0; frame < 2; ++frame) {
        for (int i = 0; i < balls; ++i)
            for (int k = 0; k < 4000; ++k) {
                // Points spread over the ball (a spiral), rays leaving along their normals, tilted.
                const float z = 1.0f - 2.0f * (static_cast<float>(k) + 0.5f) / 4000.0f, phi = 2.39996f * static_cast<float>(k);
                const float s = std::sqrt(1.0f - z * z);
                const glm::vec3 n(s * std::cos(phi), z, s * std::sin(phi));
                const glm::vec3 d = glm::normalize(n + 0.3f * glm::vec3(std::sin(1.7f * phi), 0.0f, std::cos(1.3f * phi)));
                const glm::vec3 o = centre_of(i) + (radius + 1e-3f) * n;
                caches.leaving_ray(ObjectId{static_cast<unsigned>(i)}, o, d, [&](PathRecord& path) { return trace(o, d, i, path); });
            }
        end_frame(caches);
    }
}
void fill(SceneCache& caches) {
    fill(caches, 32, [](SceneCache& c) { c.begin_frame(); });
}

// Every cube's valid texels, by cube, as loaded values.
std::vector<std::vector<float>> contents(const SceneCache& caches) {
    std::vector<std::vector<float>> all;
    caches.for_each_cct_cube([&](ObjectId, const raycache::CubeBounds&, const raycache::CctCube* cube) {
        if (!cube) return;
        std::vector<float>& v = all.emplace_back();
        cube->for_each_valid_texel([&](const raycache::TexelAddress& a) {
            const glm::vec3 c = *cube->load(a);
            v.insert(v.end(), {static_cast<float>(a.face), static_cast<float>(a.column), static_cast<float>(a.row), c.x, c.y, c.z});
        });
    });
    caches.for_each_cdct_cache([&](ObjectId, const raycache::CdctCache* cache) {
        if (!cache) return;
        std::vector<float>& v = all.emplace_back();
        cache->cube().for_each_valid_texel([&](const raycache::TexelAddress& a) {
            const raycache::DepthSample s = *cache->cube().load(a);
            v.insert(v.end(), {static_cast<float>(a.face), static_cast<float>(a.column), static_cast<float>(a.row), s.distance});
        });
    });
    return all;
}

// Every cube's face size and the path records of its blocks (objects, boxes, flags, unrecorded texels).
std::vector<std::vector<float>> records(const SceneCache& caches) {
    std::vector<std::vector<float>> all;
    auto add = [&](const auto& cube) {
        std::vector<float>& v = all.emplace_back(1, static_cast<float>(cube.face_size()));
        cube.for_each_block_state([&](const auto& b) {
            v.insert(v.end(), {static_cast<float>(b.tile), static_cast<float>(b.block), static_cast<float>(b.objects & 0xFFFFu),
                               static_cast<float>(b.objects >> 16 & 0xFFFFu), static_cast<float>(b.objects >> 32 & 0xFFFFu),
                               static_cast<float>(b.objects >> 48), static_cast<float>(b.path_flags),
                               static_cast<float>(b.unrecorded_texels)});
            for (const glm::vec3* box : {&b.vertex_lo, &b.vertex_hi, &b.escape_lo, &b.escape_hi}) v.insert(v.end(), {box->x, box->y, box->z});
        });
    };
    caches.for_each_cct_cube([&](ObjectId, const raycache::CubeBounds&, const raycache::CctCube* cube) {
        if (cube) add(*cube);
    });
    caches.for_each_cdct_cache([&](ObjectId, const raycache::CdctCache* cache) {
        if (cache) add(cache->cube());
    });
    return all;
}

// A parallel_for over `threads` std::threads, each taking every threads-th index.
auto threads_for(int threads) {
    return [threads](std::size_t count, const std::function<void(std::size_t)>& f) {
        std::vector<std::thread> pool;
        for (int t = 0; t < threads; ++t)
            pool.emplace_back([&, t] {
                for (std::size_t i = static_cast<std::size_t>(t); i < count; i += static_cast<std::size_t>(threads)) f(i);
            });
        for (std::thread& th : pool) th.join();
    };
}

} // namespace

TEST_CASE("scene_changed over 4 threads empties exactly the texels the serial pass empties, CCT and CDCT") {
    for (const Technique technique : {Technique::cct, Technique::cdct}) {
        CAPTURE(technique == Technique::cct ? "CCT" : "CDCT");
        raycache::embree::SceneCacheSettings moving; // a scene that moves: path records from the first store
        moving.path_records = raycache::embree::PathRecords::always;
        SceneCache serial(technique, moving), parallel(technique, moving);
        fill(serial);
        fill(parallel);
        REQUIRE(contents(serial) == contents(parallel));
        raycache::embree::SceneChange change;
        change.moved.push_back({ObjectId{3}, {centre_of(3), radius}, {centre_of(3) + glm::vec3(0.0f, 0.4f, 0.0f), radius}, std::nullopt});
        change.lights = {glm::vec3(0.0f, 10.0f, 0.0f)};
        const InvalidationStatistics one = serial.scene_changed(change, Invalidation::exact);
        const InvalidationStatistics four = parallel.scene_changed(change, Invalidation::exact, threads_for(4));
        MESSAGE(one.dropped << " of " << one.valid_before << " texels dropped, " << one.cubes_changed << " cubes changed");
        CHECK(one.dropped > 0);
        CHECK(one.dropped < one.valid_before);
        CHECK(one.cubes_changed > 2); // the mover's cube, and others by their rays' cones or paths
        // Every emptied texel has one reason: the mover's own cube, its rays' cone, its block's paths, or a
        // changed mirror's cube (every store here brought a record). The ball moves up past its neighbours'
        // reflections of it, so their cones meet it.
        MESSAGE("moved cube " << one.dropped_with_moved_cubes << ", cone " << one.dropped_by_cone << ", path " << one.dropped_by_path
                              << ", transitively " << one.dropped_transitively);
        CHECK(one.dropped_with_moved_cubes > 0);
        CHECK(one.dropped_by_cone > 0);
        CHECK(one.dropped_unrecorded == 0);
        CHECK(one.dropped_with_moved_cubes + one.dropped_by_cone + one.dropped_by_path + one.dropped_transitively +
                  one.dropped_unrecorded == one.dropped);
        CHECK(four.dropped_by_cone == one.dropped_by_cone);
        CHECK(four.dropped_by_path == one.dropped_by_path);
        CHECK(four.dropped_transitively == one.dropped_transitively);
        CHECK(four.valid_before == one.valid_before);
        CHECK(four.dropped == one.dropped);
        CHECK(four.cubes_changed == one.cubes_changed);
        CHECK(contents(parallel) == contents(serial));
    }
}

TEST_CASE("adaptive cubes resized over 4 threads hold what resizing them one by one gives, CCT and CDCT") {
    // With room in the budget for every resized cube, begin_frame() resizes them on the caller's threads;
    // with little room (here the first frame fills most of it), one by one. Either way every cube must end
    // with the serial resize's face size, texels, doubtful marks (as what loads) and path records.
    for (const Technique technique : {Technique::cct, Technique::cdct}) {
        // The tight budgets leave less room after the first frame than the 8 resized cubes could take.
        const std::size_t tight = technique == Technique::cct ? std::size_t{2} << 20 : std::size_t{3} << 20;
        for (const std::size_t budget : {std::size_t{256} << 20, tight}) {
            CAPTURE(technique == Technique::cct ? "CCT" : "CDCT");
            CAPTURE(budget);
            raycache::embree::SceneCacheSettings settings;
            settings.budget_bytes = budget;
            SceneCache serial(technique, settings), parallel(technique, settings);
            std::vector<std::size_t> resized_serial, resized_parallel, doubtful_serial, doubtful_parallel;
            fill(serial, raycache::embree::adaptive_face_size, [&](SceneCache& c) {
                const auto s = c.begin_frame();
                resized_serial.push_back(s.resized_cubes);
                doubtful_serial.push_back(s.doubtful_texels);
            });
            fill(parallel, raycache::embree::adaptive_face_size, [&](SceneCache& c) {
                const auto s = c.begin_frame(threads_for(4));
                resized_parallel.push_back(s.resized_cubes);
                doubtful_parallel.push_back(s.doubtful_texels);
            });
            CHECK(resized_serial == std::vector<std::size_t>{balls, 0});
            CHECK(resized_parallel == resized_serial);
            CHECK(doubtful_serial.back() > 0);
            CHECK(doubtful_parallel == doubtful_serial);
            const std::vector<std::vector<float>> r = records(serial);
            REQUIRE(r.size() == static_cast<std::size_t>(balls));
            for (const std::vector<float>& cube : r) CHECK(cube.front() < 64.0f); // shrunk from the first size
            CHECK(records(parallel) == r);
            CHECK(contents(parallel) == contents(serial));
            CHECK(serial.statistics().allocated_bytes == parallel.statistics().allocated_bytes);
            CHECK(serial.statistics().allocated_bytes <= budget);
        }
    }
}

TEST_CASE("scene_changed refuses a sphere, light or cube that is not finite, before any cube moves or loses a texel") {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    SceneCache caches(Technique::cct);
    fill(caches);
    const std::vector<std::vector<float>> before = contents(caches);
    const raycache::CubeBounds bounds = *caches.object_bounds(ObjectId{3});
    for (const Invalidation policy : {Invalidation::none, Invalidation::all, Invalidation::exact}) {
        for (int k = 0; k < 5; ++k) {
            CAPTURE(k);
            raycache::embree::SceneChange change;
            change.moved.push_back({ObjectId{3}, {centre_of(3), radius}, {centre_of(3) + glm::vec3(0.0f, 0.4f, 0.0f), radius}, std::nullopt});
            change.lights = {glm::vec3(0.0f, 10.0f, 0.0f)};
            if (k == 0) change.moved[0].after.centre.z = nan;
            if (k == 1) change.moved[0].before.radius = -1.0f;
            if (k == 2) change.moved[0].after.radius = inf;
            if (k == 3) change.lights[0].x = nan;
            if (k == 4) change.moved[0].cube = raycache::CubeBounds{centre_of(3), nan};
            CHECK_THROWS_AS(caches.scene_changed(change, policy), std::invalid_argument);
            CHECK(contents(caches) == before);
            const raycache::CubeBounds now = *caches.object_bounds(ObjectId{3});
            CHECK(now.centre == bounds.centre);
            CHECK(now.half_size == bounds.half_size);
        }
    }
}

TEST_CASE("how far out a cube's rays left is the furthest origin of any thread's rays: the same on 4 threads as on one") {
    // SceneCache keeps it per cube as an atomic maximum of the rays' distances from the centre; after an
    // exact move the cube answers rays from within it (2% more) alone.
    auto reach_after = [&](int threads) {
        raycache::embree::SceneCacheSettings settings;
        settings.origin_drift = -1.0f;
        settings.path_records = raycache::embree::PathRecords::always;
        SceneCache caches(Technique::cct, settings);
        caches.attach(ObjectId{0}, 64, raycache::CubeBounds{glm::vec3(0.0f), 1.5f});
        std::vector<std::thread> pool;
        for (int t = 0; t < threads; ++t)
            pool.emplace_back([&, t] {
                for (int k = t; k < 4000; k += threads) {
                    // Origins 1.0 .. 1.3999 from the centre, in many directions; the furthest is k = 3999.
                    const float distance = 1.0f + 0.0001f * static_cast<float>(k);
                    const float a = 0.01f * static_cast<float>(k);
                    const glm::vec3 origin = distance * glm::vec3(std::cos(a), 0.0f, std::sin(a));
                    caches.leaving_ray(ObjectId{0}, origin, glm::normalize(origin), [&](PathRecord&) {
                        return raycache::TracedRay{glm::vec3(0.5f), std::numeric_limits<float>::infinity()};
                    });
                }
            });
        for (std::thread& t : pool) t.join();
        caches.begin_frame();
        raycache::embree::SceneChange far;
        far.moved.push_back({ObjectId{9}, {glm::vec3(-30, 0, 0), 0.5f}, {glm::vec3(-30, 0, 1), 0.5f}, std::nullopt});
        caches.scene_changed(far, Invalidation::exact);
        return *caches.answered_origin_radius(ObjectId{0});
    };
    const float one = reach_after(1);
    CHECK(one == doctest::Approx(1.3999f * 1.02f));
    CHECK(reach_after(4) == one);
}
