// raycache_micro_bench: the cost of one cache operation against one rtcIntersect1, on the same reflected
// rays of behind-32 (rays leaving the main mirror sphere towards the spheres behind the camera).
// Google Benchmark; each benchmark cycles through the same 4096 rays.
#include <benchmark/benchmark.h>

#include <memory>
#include <random>
#include <vector>

#include "tracer.hpp"

namespace {

struct LeavingRay {
    glm::vec3 origin, direction;
    unsigned geom_id;
};

// behind-32, its Embree scene, and 4096 rays leaving cached objects, found by tracing primary rays.
struct Fixture {
    rcx::Scene scene = rcx::make_scene("behind-32");
    rcx::embree::Tracer tracer{scene};
    std::vector<LeavingRay> rays;
    raycache::embree::ObjectId main_sphere;

    RTCRayHit intersect(glm::vec3 o, glm::vec3 d) const {
        RTCRayHit rh{};
        rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
        rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
        rh.ray.tnear = 1e-3f;
        rh.ray.tfar = 1e30f;
        rh.ray.mask = 0xFFFFFFFFu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        rtcIntersect1(tracer.rtc_scene(), &context, &rh);
        return rh;
    }

    Fixture() {
        const std::vector<unsigned> cached = tracer.cached_geometries();
        std::mt19937 rng(1);
        std::uniform_int_distribution<int> pixel(0, 1023);
        const rcx::CameraBasis camera = rcx::camera_basis(scene.camera, 1024, 1024);
        while (rays.size() < 4096) {
            const glm::vec3 eye = scene.camera.eye;
            const glm::vec3 d = rcx::primary_direction(camera, pixel(rng), pixel(rng));
            const RTCRayHit rh = intersect(eye, d);
            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
            if (std::find(cached.begin(), cached.end(), rh.hit.geomID) == cached.end()) continue;
            const glm::vec3 p = eye + rh.ray.tfar * d;
            const glm::vec3 n = glm::normalize(glm::vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
            rays.push_back({p + 1e-3f * n, glm::reflect(d, n), rh.hit.geomID});
        }
        main_sphere = {rays.front().geom_id};
    }
};

Fixture& fixture() {
    static Fixture f;
    return f;
}

void rtc_intersect1(benchmark::State& state) {
    Fixture& f = fixture();
    std::size_t i = 0;
    for (auto _ : state) {
        const LeavingRay& r = f.rays[i++ & 4095];
        benchmark::DoNotOptimize(f.intersect(r.origin, r.direction));
    }
}
BENCHMARK(rtc_intersect1);

// A CCT cube of 512-texel faces, filled with every ray's traced colour (all lookups hit).
void cct_lookup(benchmark::State& state) {
    Fixture& f = fixture();
    raycache::CctCube cube(512);
    for (const LeavingRay& r : f.rays) cube.store(r.direction, glm::vec3(0.5f));
    cube.begin_frame();
    std::size_t i = 0;
    for (auto _ : state) benchmark::DoNotOptimize(cube.lookup(f.rays[i++ & 4095].direction));
}
BENCHMARK(cct_lookup);

void cct_store(benchmark::State& state) {
    Fixture& f = fixture();
    raycache::CctCube cube(512);
    std::size_t i = 0;
    for (auto _ : state) {
        if ((i & 4095) == 0) {
            state.PauseTiming();
            cube.clear();
            state.ResumeTiming();
        }
        benchmark::DoNotOptimize(cube.store(f.rays[i++ & 4095].direction, glm::vec3(0.5f)));
    }
}
BENCHMARK(cct_store);

// A CDCT cube filled by tracing 512 x 512 x 6 rays from the main sphere's centre (so every texel is
// valid), then searched along the leaving rays of the main sphere: linear (thesis), over the pyramid, or
// the secant search (the default: a few reads and a consistency test, max_gap 0.5).
void cdct_search(benchmark::State& state, raycache::DepthSearch search, bool pyramid, float step, float epsilon) {
    Fixture& f = fixture();
    static std::unique_ptr<raycache::CdctCube> cube;
    static std::unique_ptr<raycache::DepthPyramid> levels;
    static raycache::CubeBounds bounds;
    raycache::ReliefParameters relief{step, epsilon, 2048, 100.0f};
    relief.search = search;
    if (search == raycache::DepthSearch::secant) relief.max_gap = 0.5f;
    if (!cube) {
        bounds = raycache::embree::bounds_of(f.tracer.rtc_scene(), f.main_sphere);
        cube = std::make_unique<raycache::CdctCube>(512);
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < 512; ++row)
                for (int column = 0; column < 512; ++column) {
                    const glm::vec3 d = glm::normalize(raycache::texel_direction({face, column, row}, 512));
                    const glm::vec3 o = bounds.centre + bounds.half_size * 1.01f * d;
                    const RTCRayHit rh = f.intersect(o, d);
                    const float t = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? 1e30f : rh.ray.tfar;
                    if (t < 1e29f)
                        raycache::store_hit(*cube, bounds, o + t * d, glm::vec3(0.5f), relief);
                    else
                        raycache::store_escape(*cube, d, glm::vec3(0.5f), relief);
                }
        levels = std::make_unique<raycache::DepthPyramid>(512);
        levels->update(*cube);
        cube->begin_frame();
    }
    std::vector<LeavingRay> main_rays;
    for (const LeavingRay& r : f.rays)
        if (r.geom_id == f.main_sphere.geom_id) main_rays.push_back(r);
    std::size_t i = 0;
    long reads = 0, hits = 0;
    for (auto _ : state) {
        const LeavingRay& r = main_rays[i++ % main_rays.size()];
        const raycache::ReliefResult result =
            raycache::depth_search(*cube, bounds, r.origin, r.direction, relief, pyramid ? levels.get() : nullptr);
        reads += result.texels_read;
        hits += result.hit;
        benchmark::DoNotOptimize(result);
    }
    state.counters["texels_per_search"] = benchmark::Counter(static_cast<double>(reads), benchmark::Counter::kAvgIterations);
    state.counters["hit_rate"] = benchmark::Counter(static_cast<double>(hits), benchmark::Counter::kAvgIterations);
}
BENCHMARK_CAPTURE(cdct_search, linear_thesis_0_2, raycache::DepthSearch::relief, false, 0.2f, 0.02f);
BENCHMARK_CAPTURE(cdct_search, pyramid, raycache::DepthSearch::relief, true, 0.2f, 0.02f);
BENCHMARK_CAPTURE(cdct_search, secant, raycache::DepthSearch::secant, false, 0.2f, 0.02f);

} // namespace

BENCHMARK_MAIN();
