// raycache_micro_bench: the cost of one cache operation against one rtcIntersect1, on the same reflected
// rays of behind-32 (rays leaving the main mirror sphere towards the spheres behind the camera), and of
// exact invalidation after one object of behind-32 moved.
// Google Benchmark; each benchmark cycles through the same 4096 rays.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include "bench_common.hpp"
#include "bench_embree.hpp"
#include "rcx/scene_hash.hpp"
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

// behind-32 with one sphere circling (the dynamic benchmark's scene), CCT and CDCT caches warmed along its
// walkthrough for `warm_frames` frames at 512 x 512 with exact invalidation of each move, then saved: every
// iteration loads that state (untimed) and times the exact invalidation of the next move, so each one
// starts from the same texels. A loaded cube's tiles are allocated in order, a warmed one's as rays came.
// With RAYCACHE_MICRO_BENCH_STATE=DIR the saved caches are kept in DIR and, when they are there already,
// loaded instead of warmed (the load checks they are this scene's): so that a profiler run, under
// callgrind say, spends its time on the invalidation and not on 40 frames of warming.
struct MovedSphere {
    static constexpr int warm_frames = 20;
    rcx::Scene scene = rcx::bench::behind_with_one_mover();
    rcx::embree::Tracer tracer{scene};
    raycache::SceneIdentity identity{rcx::scene_hash(scene), scene.name};
    rcx::bench::Variant variants[2]; // the CCT's and the CDCT's caches
    std::string files[2];
    bool keep_files = false;
    raycache::embree::SceneChange next_move;
    raycache::embree::SceneChange move_back; // puts the moved sphere's cube back where the files expect it

    MovedSphere() {
        const raycache::embree::Technique techniques[2] = {raycache::embree::Technique::cct, raycache::embree::Technique::cdct};
        const rcx::CacheMode modes[2] = {rcx::CacheMode::cct, rcx::CacheMode::cdct};
        for (int k = 0; k < 2; ++k) {
            variants[k].mode = modes[k];
            variants[k].caches = rcx::bench::dynamic_scene_cache(techniques[k]);
            tracer.attach_caches(*variants[k].caches, 0);
        }
        const char* kept_in = std::getenv("RAYCACHE_MICRO_BENCH_STATE");
        for (int k = 0; k < 2; ++k)
            files[k] = kept_in ? (std::filesystem::path(kept_in) / ("exact_invalidation_" + std::to_string(k) + ".rcache")).string()
                               // Named by the process, so that two benchmarks at once do not overwrite each other's.
                               : (std::filesystem::temp_directory_path() /
                                  ("raycache_micro_bench_" + std::to_string(::getpid()) + "_" + std::to_string(k) + ".rcache"))
                                     .string();
        keep_files = kept_in != nullptr;
        if (keep_files && std::filesystem::exists(files[0]) && std::filesystem::exists(files[1])) {
            for (int f = 1; f < warm_frames; ++f) { // the caches' cubes follow as when warmed (none is filled)
                const raycache::embree::SceneChange change = tracer.move_to(scene.at_frame(f));
                for (auto& v : variants) v.caches->scene_changed(change, raycache::embree::Invalidation::none);
            }
            next_move = tracer.move_to(scene.at_frame(warm_frames));
            move_back = tracer.move_to(scene.at_frame(warm_frames - 1));
            return;
        }
        for (int f = 0; f < warm_frames; ++f) {
            if (f > 0) {
                const raycache::embree::SceneChange change = tracer.move_to(scene.at_frame(f));
                for (auto& v : variants) rcx::embree::scene_changed(*v.caches, change, raycache::embree::Invalidation::exact);
            }
            for (auto& v : variants) rcx::bench::render(tracer, v, scene.camera_at(f), 512, 512);
        }
        next_move = tracer.move_to(scene.at_frame(warm_frames));
        move_back = tracer.move_to(scene.at_frame(warm_frames - 1));
        for (int k = 0; k < 2; ++k) variants[k].caches->save(files[k], identity);
    }
    ~MovedSphere() {
        if (!keep_files)
            for (const std::string& f : files) std::filesystem::remove(f);
    }
};

MovedSphere& moved_sphere() {
    static MovedSphere m;
    return m;
}

// technique: 0 CCT, 1 CDCT; state.range(0): invalidation threads (0: every core).
void exact_invalidation(benchmark::State& state, int technique) {
    MovedSphere& m = moved_sphere();
    raycache::embree::SceneCache& caches = *m.variants[technique].caches;
    // Written between the load and the timed pass, so that the cubes are not all in the cores' caches, as
    // after a frame's rendering.
    std::vector<char> evict(32u << 20);
    double kept = 0.0;
    for (auto _ : state) {
        state.PauseTiming();
        caches.load(m.files[technique], m.identity);
        std::fill(evict.begin(), evict.end(), static_cast<char>(evict[0] + 1));
        benchmark::ClobberMemory();
        state.ResumeTiming();
        const raycache::embree::InvalidationStatistics s =
            rcx::embree::scene_changed(caches, m.next_move, raycache::embree::Invalidation::exact, static_cast<int>(state.range(0)));
        kept += s.kept_fraction();
        state.PauseTiming();
        caches.scene_changed(m.move_back, raycache::embree::Invalidation::none);
        state.ResumeTiming();
    }
    state.counters["kept"] = benchmark::Counter(kept, benchmark::Counter::kAvgIterations);
}
// Each iteration first reloads the saved caches, untimed (about 40 ms): 0.05 s of timed moves (some 50 of
// them, whatever --benchmark_min_time says) keeps these four cases to seconds where 0.5 s took minutes.
BENCHMARK_CAPTURE(exact_invalidation, behind_32_cct, 0)->Arg(1)->Arg(0)->MinTime(0.05)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(exact_invalidation, behind_32_cdct, 1)->Arg(1)->Arg(0)->MinTime(0.05)->Unit(benchmark::kMillisecond);

} // namespace

// BENCHMARK_MAIN(), with the processor's name in the JSON's context: Google Benchmark records cores and caches
// but not the model, and docs/RESULTS.md names the machine of every table.
int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::AddCustomContext("machine", rcx::bench::machine_name());
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
