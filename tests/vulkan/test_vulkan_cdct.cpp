// The CDCT in GLSL (raycache/cdct.glsl, driven by shaders/cdct_cross.comp) against raycache::CdctCube
// and raycache::relief_search: texels written by C++ give the same relief searches in GLSL (hit, texels
// read, distance, point and colour, bit for bit), and texels stored by GLSL (store_hit, store_escape,
// store), after the end-frame pass, are word for word what C++ makes of the same stores.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include <raycache/raycache.hpp>

#include "vulkan_test.hpp"
#include "../cdct_scenes.hpp"
#include "../test_bits.hpp"

using namespace raycache;
namespace gpu = raycache::shared;

namespace {

// shaders/cdct_cross.comp's Query, Result and push constants, with their std430 layouts.
struct Query {
    glm::vec3 origin; // search: ray origin; store_hit: the hit point
    std::uint32_t cube;
    glm::vec3 direction; // search and store_escape: ray direction; store: key
    std::uint32_t mode;  // 0: relief search, 1: store_hit, 2: store_escape, 3: store(key, colour, distance),
                         // 4: secant search, 5: depth_search (the parameters' search)
    glm::vec3 color;
    float distance;
};
static_assert(sizeof(Query) == 48, "Query must match cdct_cross.comp");
struct Result {
    std::uint32_t hit;
    std::int32_t texels_read;
    float distance;
    std::uint32_t pad;
    glm::vec3 color;
    float pad1;
    glm::vec3 point;
    float pad2;
};
static_assert(sizeof(Result) == 48, "Result must match cdct_cross.comp");
// GLSL's raycache_relief_parameters is ReliefParameters field for field (cdct.hpp asserts the layout):
// the push constants hold its bytes as they are.
struct Push {
    ReliefParameters parameters;
    std::uint32_t count;
    Push(const ReliefParameters& p, std::size_t n) : parameters(p), count(static_cast<std::uint32_t>(n)) {}
};
static_assert(sizeof(Push) == 32, "raycache_relief_parameters is 7 4-byte fields, then the count");


using Scene = rcx_test::CdctScene;
using rcx_test::random_direction;

Scene make_scene(std::mt19937& rng, bool fill) { return rcx_test::make_analytic_scene(rng, fill); }

// rcx_test::search_rays as search queries (mode 0: relief; 4: secant; 5: the parameters' search).
std::vector<Query> search_queries(const Scene& s, std::mt19937& rng, int per_cube, std::uint32_t mode = 0) {
    std::vector<Query> queries;
    for (const rcx_test::CdctRay& ray : rcx_test::search_rays(s, rng, per_cube)) {
        Query q{};
        q.origin = ray.origin;
        q.cube = ray.cube;
        q.direction = ray.direction;
        q.mode = mode;
        queries.push_back(q);
    }
    return queries;
}

struct Comparison {
    std::size_t same = 0, hits = 0;
    long long texels = 0;
    std::uint64_t empty = 0; // GPU searches counted as misses on empty texels
};

// Compares GPU search results with the C++ search of each query's mode (0: relief_search, 4: secant_search,
// 5: depth_search) on the C++ cubes; prints the first differences.
Comparison compare_searches(Scene& s, const std::vector<Query>& queries, const Result* r, const ReliefParameters& p) {
    Comparison c;
    int printed = 0;
    for (std::size_t i = 0; i < queries.size(); ++i) {
        if (queries[i].mode != 0 && queries[i].mode != 4 && queries[i].mode != 5) continue;
        const Query& q = queries[i];
        CdctCube& cube = s.cubes[q.cube];
        const CubeBounds& b = s.bounds[q.cube];
        const ReliefResult e = q.mode == 0   ? relief_search(cube, b, q.origin, q.direction, p)
                               : q.mode == 4 ? secant_search(cube, b, q.origin, q.direction, p)
                                             : depth_search(cube, b, q.origin, q.direction, p);
        const bool ok = (r[i].hit != 0) == e.hit && r[i].texels_read == e.texels_read &&
                        glm::floatBitsToUint(r[i].distance) == glm::floatBitsToUint(e.distance) && same_bits(r[i].point, e.point) &&
                        same_bits(r[i].color, e.color);
        c.same += ok;
        c.hits += e.hit;
        c.texels += e.texels_read;
        if (!ok && printed++ < 8)
            std::printf("  differs: cube %u origin (%a, %a, %a) direction (%a, %a, %a): C++ hit %d read %d t %a, "
                        "GLSL hit %u read %d t %a\n",
                        q.cube, q.origin.x, q.origin.y, q.origin.z, q.direction.x, q.direction.y, q.direction.z, e.hit,
                        e.texels_read, e.distance, r[i].hit, r[i].texels_read, r[i].distance);
    }
    return c;
}

// shaders/cdct_cross.comp, on a device with the 64-bit atomics that the include's CDCT stores need.
rcx::vk::ComputePipeline cross_pipeline(rcx::vk::Context& vk) {
    REQUIRE_MESSAGE(vk.int64_atomics(), "RayCache's GLSL CDCT stores need shaderInt64 and shaderBufferInt64Atomics");
    return rcx::vk::ComputePipeline(vk, rcx_test::spirv("cdct_cross"), rcx_test::cross_bindings, sizeof(Push));
}

// A scene's cubes and a batch of search queries in the buffers of the cross-check shader (nothing pending),
// searched in GLSL with any parameters and compared with C++.
struct GpuSearches {
    rcx::vk::Context& vk;
    const rcx::vk::ComputePipeline& cross;
    Scene& s;
    std::vector<Query> queries;
    rcx::vk::Buffer texels, pending, cubes, query_buffer, results;
    rcx_test::Frame frame;

    GpuSearches(rcx::vk::Context& context, const rcx::vk::ComputePipeline& pipeline, Scene& scene, std::vector<Query> q)
        : vk(context), cross(pipeline), s(scene), queries(std::move(q)), texels(rcx_test::buffer_of(vk, s.words())),
          pending(vk, s.elements * 8), cubes(rcx_test::buffer_of(vk, s.descriptors)),
          query_buffer(rcx_test::buffer_of(vk, queries)), results(vk, queries.size() * sizeof(Result)),
          frame(vk, static_cast<std::uint32_t>(s.cubes.size()), 16) {
        pending.fill(RAYCACHE_GPU_CLEAR_WORD);
    }
    Comparison run(const ReliefParameters& p) {
        const Push push(p, queries.size());
        frame.start();
        vk.dispatch(cross, {texels, pending, cubes, query_buffer, results, frame.buffer}, &push, sizeof(push),
                    rcx::vk::group_count(queries.size(), 64));
        const auto empty = static_cast<std::size_t>(MissReason::empty);
        std::vector<std::uint64_t> empty_before(s.cubes.size());
        for (std::size_t k = 0; k < s.cubes.size(); ++k) empty_before[k] = s.cubes[k].statistics().misses_by[empty];
        Comparison c = compare_searches(s, queries, results.as<Result>(), p);
        // Every search is one lookup of its cube, a hit when it answered; a miss ended by a read of a texel
        // holding no value counts as empty, as the same C++ searches (just above) count it.
        const raycache::GpuFrameStatistics stats = frame.statistics();
        std::vector<std::uint64_t> lookups(s.cubes.size(), 0), hits(s.cubes.size(), 0);
        for (std::size_t i = 0; i < queries.size(); ++i) ++lookups[queries[i].cube], hits[queries[i].cube] += results.as<Result>()[i].hit != 0u;
        for (std::size_t k = 0; k < s.cubes.size(); ++k) {
            CHECK(stats.cubes[k].lookups == lookups[k]);
            CHECK(stats.cubes[k].hits == hits[k]);
            CHECK(stats.cubes[k].misses_by[empty] == s.cubes[k].statistics().misses_by[empty] - empty_before[k]);
            c.empty += stats.cubes[k].misses_by[empty];
        }
        return c;
    }
};

} // namespace

TEST_CASE("CDCT texels written by C++ give the same relief searches in GLSL as in C++, bit for bit") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    const rcx::vk::ComputePipeline cross = cross_pipeline(*vk);
    std::mt19937 rng(21);
    Scene s = make_scene(rng, true);
    GpuSearches gpu(*vk, cross, s, search_queries(s, rng, 1500));
    const std::vector<Query>& queries = gpu.queries;

    const float inf = std::numeric_limits<float>::infinity();
    const ReliefParameters sets[] = {
        {2.0f, 0.2f, 1024, 100.0f, inf},  {0.4f, 0.05f, 1024, 100.0f, inf}, {0.2f, 0.02f, 1024, 100.0f, inf},
        {0.05f, 0.002f, 300, 100.0f, inf}, {0.2f, 0.02f, 1024, 100.0f, 0.3f}, {0.25f, 0.02f, 10, 100.0f, inf},
    };
    for (const ReliefParameters& p : sets) {
        CAPTURE(p.step);
        CAPTURE(p.epsilon);
        CAPTURE(p.max_steps);
        CAPTURE(p.max_gap);
        const Comparison c = gpu.run(p);
        std::printf("CDCT relief search (step %g, epsilon %g, %d steps, max_gap %g), C++ texels read in GLSL: %zu of "
                    "%zu equal to C++ (%zu hits, %.1f texels read per search)\n",
                    p.step, p.epsilon, p.max_steps, p.max_gap, c.same, queries.size(), c.hits,
                    static_cast<double>(c.texels) / queries.size());
        CHECK(c.same == queries.size());
        CHECK(c.hits > queries.size() / 5);
        CHECK(c.hits < queries.size());
    }
}

TEST_CASE("GLSL and C++ relief searches end at once alike when the step cannot move the ray or max_steps is over the limit") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    const rcx::vk::ComputePipeline cross = cross_pipeline(*vk);
    std::mt19937 rng(23);
    Scene s = make_scene(rng, true);
    // Origins inside the boxes (and the bad ones): the walk starts at the box exit, t > 0.05, where
    // t + 1e-30 == t.
    std::vector<Query> queries = search_queries(s, rng, 300);
    queries.erase(std::remove_if(queries.begin(), queries.end(),
                                 [&](const Query& q) {
                                     const glm::vec3 local = glm::abs(q.origin - s.bounds[q.cube].centre);
                                     return std::max(local.x, std::max(local.y, local.z)) > 0.95f * s.bounds[q.cube].half_size;
                                 }),
                  queries.end());
    GpuSearches gpu(*vk, cross, s, queries);

    const float inf = std::numeric_limits<float>::infinity();
    const ReliefParameters sets[] = {{1e-30f, 0.02f, 100000, 100.0f, inf},
                                     {0.2f, 0.02f, std::numeric_limits<int>::max(), 100.0f, inf}};
    for (const ReliefParameters& p : sets) {
        CAPTURE(p.step);
        CAPTURE(p.max_steps);
        const Comparison c = gpu.run(p);
        CHECK(c.same == queries.size());
        if (p.max_steps > RAYCACHE_MAX_RELIEF_STEPS) { // parameters no search runs with: a miss, nothing read
            CHECK(c.hits == 0);
            CHECK(c.texels == 0);
        } else { // the box exit only (a hit where the cached surface lies inside the box)
            CHECK(c.texels <= static_cast<long long>(queries.size()));
        }
    }
}

TEST_CASE("CDCT stores made in GLSL are invisible that frame, the nearest then smallest word wins, and C++ reads the result") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    const rcx::vk::ComputePipeline cross = cross_pipeline(*vk);
    rcx::vk::ComputePipeline end_frame(*vk, rcx_test::spirv("end_frame_listed_cdct"), rcx_test::listed_end_frame_bindings, 0);
    std::mt19937 rng(22);
    // The scene filled, then 3 of every 4 texels emptied: stores into the rest are refused.
    Scene s = make_scene(rng, true);
    for (CdctCube& cube : s.cubes) {
        const int n = cube.face_size();
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column)
                    if ((face + row + column) % 4 != 0) cube.invalidate(TexelAddress{face, column, row});
    }
    const ReliefParameters p{0.2f, 0.02f, 1024, 100.0f, std::numeric_limits<float>::infinity()};

    // Stores of every kind, mixed with searches in one dispatch. Raw stores aim at a few keys with a
    // few distances and colours, so that many texels see several competing words, ties of distance
    // included; some distances are negative, NaN, infinite or -0.
    std::vector<Query> queries = search_queries(s, rng, 800);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::uniform_int_distribution<int> pick(0, 7);
    const float inf = std::numeric_limits<float>::infinity();
    const float odd_distances[] = {-1.0f, std::nanf(""), inf, -0.0f, 0.0f, 1e-40f};
    for (int i = 0; i < 24000; ++i) {
        Query q{};
        q.cube = static_cast<std::uint32_t>(i % s.cubes.size());
        const CubeBounds& b = s.bounds[q.cube];
        q.color = glm::vec3(pick(rng) / 4.0f, u(rng) < 0.5f ? 0.25f : 1.0f, 0.5f);
        switch (i % 3) {
        case 0: // store_hit at a point 0.5 to 150 from the centre (beyond 100: clamped to max_depth)
            q.mode = 1;
            q.origin = b.centre + glm::normalize(random_direction(rng)) * (0.5f + 150.0f * u(rng) * u(rng));
            break;
        case 1:
            q.mode = 2;
            q.direction = random_direction(rng);
            break;
        default:
            q.mode = 3;
            q.direction = glm::vec3(pick(rng) - 3.5f, pick(rng) % 3 - 1.0f, 1.0f + pick(rng) % 2);
            q.distance = i % 50 == 2 ? odd_distances[pick(rng) % 6] : 1.0f + pick(rng) % 3;
            break;
        }
        queries.push_back(q);
    }
    std::shuffle(queries.begin(), queries.end(), rng);

    // What C++ answers this frame, before the stores (a store is invisible in its frame anyway), and
    // which stores C++ must refuse whatever the order: bad key, bad distance, texel already visible.
    std::vector<ReliefResult> frame_searches(queries.size());
    std::vector<bool> refused_for_sure(queries.size());
    for (std::size_t i = 0; i < queries.size(); ++i) {
        const Query& q = queries[i];
        CdctCube& cube = s.cubes[q.cube];
        if (q.mode == 0) {
            frame_searches[i] = relief_search(cube, s.bounds[q.cube], q.origin, q.direction, p);
            continue;
        }
        const glm::vec3 key = q.mode == 1 ? q.origin - s.bounds[q.cube].centre : q.direction;
        const float d = q.mode == 3 ? q.distance : 0.0f;
        refused_for_sure[i] = !is_direction(key) || !(d >= 0.0f) || !std::isfinite(d) ||
                              (is_direction(key) && cube.peek(key).has_value());
    }

    rcx::vk::Buffer texels = rcx_test::buffer_of(*vk, s.words());
    rcx::vk::Buffer pending(*vk, s.elements * 8);
    pending.fill(RAYCACHE_GPU_CLEAR_WORD);
    rcx::vk::Buffer cubes = rcx_test::buffer_of(*vk, s.descriptors);
    rcx::vk::Buffer query_buffer = rcx_test::buffer_of(*vk, queries);
    std::vector<Query> next_queries = search_queries(s, rng, 1500);
    rcx::vk::Buffer next_buffer = rcx_test::buffer_of(*vk, next_queries);
    std::vector<Query> next_secant_queries = next_queries;
    for (Query& q : next_secant_queries) q.mode = 4;
    rcx::vk::Buffer next_secant_buffer = rcx_test::buffer_of(*vk, next_secant_queries);
    rcx::vk::Buffer frame_results(*vk, queries.size() * sizeof(Result));
    rcx::vk::Buffer next_results(*vk, next_queries.size() * sizeof(Result));
    rcx::vk::Buffer next_secant_results(*vk, next_queries.size() * sizeof(Result));
    const Push push(p, queries.size());
    const Push next_push(p, next_queries.size());
    rcx::vk::Buffer dummy(*vk, 16);
    rcx_test::Frame frame(*vk, static_cast<std::uint32_t>(s.cubes.size()), static_cast<std::uint32_t>(s.elements));
    vk->submit([&](rcx::vk::Commands& c) {
        c.dispatch(cross, {texels, pending, cubes, query_buffer, frame_results, frame.buffer}, &push, sizeof(push),
                   rcx::vk::group_count(queries.size(), 64));
        c.barrier();
        rcx_test::record_listed_end_frame(c, end_frame, dummy, dummy, texels, pending, frame);
    });
    const raycache::GpuFrameStatistics gpu_stats = frame.statistics();
    const std::vector<std::uint32_t> listed = frame.listed();
    frame.start();
    vk->submit([&](rcx::vk::Commands& c) {
        c.dispatch(cross, {texels, pending, cubes, next_buffer, next_results, frame.buffer}, &next_push, sizeof(next_push),
                   rcx::vk::group_count(next_queries.size(), 64));
        c.dispatch(cross, {texels, pending, cubes, next_secant_buffer, next_secant_results, frame.buffer}, &next_push,
                   sizeof(next_push), rcx::vk::group_count(next_queries.size(), 64));
    });

    // The same stores in C++, in order; count the texels that several different words competed for.
    std::map<std::pair<std::uint32_t, std::size_t>, std::set<std::uint64_t>> competing;
    for (const Query& q : queries) {
        CdctCube& cube = s.cubes[q.cube];
        const CubeBounds& b = s.bounds[q.cube];
        bool stored = false;
        glm::vec3 key(0.0f);
        DepthSample sample;
        if (q.mode == 1) {
            stored = store_hit(cube, b, q.origin, q.color, p);
            key = q.origin - b.centre;
            sample = DepthSample{q.color, std::min(glm::length(key), p.max_depth)};
        } else if (q.mode == 2) {
            stored = store_escape(cube, q.direction, q.color, p);
            key = q.direction;
            sample = DepthSample{q.color, p.max_depth};
        } else if (q.mode == 3) {
            stored = cube.store(q.direction, DepthSample{q.color, q.distance});
            key = q.direction;
            sample = DepthSample{q.color, q.distance};
        }
        if (stored)
            competing[{q.cube, texel_linear_index(*texel_of(key, cube.face_size()), cube.face_size())}].insert(
                CdctTexel::encode(sample));
    }
    // The store list holds the texels C++ wrote this frame, once each, tagged as CDCT entries; refusals
    // before the pending word are the certain ones, the other stores reached it.
    std::set<std::uint32_t> written;
    for (std::size_t k = 0; k < s.cubes.size(); ++k)
        s.cubes[k].for_each_written_texel([&](const TexelAddress& t) {
            written.insert((s.descriptors[k].first_texel + static_cast<std::uint32_t>(texel_linear_index(t, s.cubes[k].face_size()))) |
                           RAYCACHE_FRAME_CDCT_ENTRY);
        });
    CHECK(std::set<std::uint32_t>(listed.begin(), listed.end()) == written);
    CHECK(listed.size() == written.size());
    CHECK(gpu_stats.overflow == 0u);
    std::uint64_t certain = 0, store_calls = 0;
    for (std::size_t i = 0; i < queries.size(); ++i)
        if (queries[i].mode != 0) ++store_calls, certain += refused_for_sure[i];
    CHECK(gpu_stats.total.refused_stores == certain);
    CHECK(gpu_stats.total.stores + gpu_stats.total.refused_stores == store_calls);
    for (CdctCube& cube : s.cubes) cube.begin_frame();
    std::size_t contended = 0;
    for (const auto& texel : competing) contended += texel.second.size() > 1;

    // During the frame: searches answered from the frame's start; stores refused where C++ must refuse.
    const Result* r = frame_results.as<Result>();
    std::size_t searches_same = 0, searches = 0, refusals_kept = 0, refusals = 0;
    for (std::size_t i = 0; i < queries.size(); ++i) {
        if (queries[i].mode == 0) {
            ++searches;
            const ReliefResult& e = frame_searches[i];
            searches_same += (r[i].hit != 0) == e.hit && r[i].texels_read == e.texels_read &&
                             glm::floatBitsToUint(r[i].distance) == glm::floatBitsToUint(e.distance) && same_bits(r[i].color, e.color);
        } else if (refused_for_sure[i]) {
            ++refusals;
            refusals_kept += r[i].hit == 0u;
        }
    }
    CHECK(searches_same == searches);
    CHECK(refusals_kept == refusals);
    CHECK(refusals > 0);

    // After the end-frame pass: every valid word equals C++'s, every empty one is empty in C++, and
    // the pending buffer is empty again.
    const std::vector<std::uint64_t> expected = s.words();
    const std::uint64_t* words = texels.as<std::uint64_t>();
    std::size_t words_same = 0, valid = 0, pending_clear = 0;
    for (std::size_t i = 0; i < s.elements; ++i) {
        const bool gpu_valid = CdctTexel::is_valid(words[i]);
        words_same += gpu_valid ? words[i] == expected[i] : !CdctTexel::is_valid(expected[i]);
        valid += gpu_valid;
        pending_clear += pending.as<std::uint64_t>()[i] == ~std::uint64_t{0};
    }
    std::printf("CDCT stores in GLSL: %zu of %zu words equal to C++'s after the frame (%zu valid, %zu stored by "
                "several different stores); %zu of %zu searches during the frame equal to C++; %zu of %zu certain "
                "refusals refused\n",
                words_same, s.elements, valid, contended, searches_same, searches, refusals_kept, refusals);
    CHECK(words_same == s.elements);
    CHECK(pending_clear == s.elements);
    CHECK(contended > 50);

    // C++ reads the GPU's words: a fresh cube filled from them holds the same words, and the searches of
    // the next frame in GLSL equal those of C++.
    for (std::size_t c = 0; c < s.cubes.size(); ++c) {
        CdctCube copy(s.cubes[c].face_size());
        rcx_test::store_words(copy, words + s.descriptors[c].first_texel);
        copy.begin_frame();
        CHECK(rcx_test::words_of(copy) == rcx_test::words_of(s.cubes[c]));
    }
    const Comparison next = compare_searches(s, next_queries, next_results.as<Result>(), p);
    std::printf("CDCT relief search in the next frame: %zu of %zu equal to C++ (%zu hits)\n", next.same,
                next_queries.size(), next.hits);
    CHECK(next.same == next_queries.size());
    CHECK(next.hits > 0);
    const Comparison next_secant = compare_searches(s, next_secant_queries, next_secant_results.as<Result>(), p);
    std::printf("CDCT secant search in the next frame: %zu of %zu equal to C++ (%zu hits)\n", next_secant.same,
                next_queries.size(), next_secant.hits);
    CHECK(next_secant.same == next_queries.size());
    CHECK(next_secant.hits > 0);
}

TEST_CASE("the secant search in GLSL equals C++'s secant_search bit for bit, on analytic cubes and on cubes filled by stores") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    const rcx::vk::ComputePipeline cross = cross_pipeline(*vk);
    std::mt19937 rng(24);
    // Analytic cubes (every texel but the first cube's cap filled), and cubes filled by 7,500 traced rays
    // through cdct_cached_trace over three frames (holes where no ray went).
    std::vector<rcx_test::TracedSample> samples;
    Scene scenes[2] = {rcx_test::make_analytic_scene(rng, true), rcx_test::make_stored_scene(rng, 2500, 3, samples)};
    rcx_test::apply_samples(scenes[1], samples, ReliefParameters{});
    const char* names[2] = {"analytic cubes", "cubes filled by stores"};

    std::size_t compared = 0, all_same = 0;
    for (int k = 0; k < 2; ++k) {
        Scene& s = scenes[k];
        CAPTURE(names[k]);
        GpuSearches gpu(*vk, cross, s, search_queries(s, rng, 1000, 4));
        const std::vector<Query>& queries = gpu.queries;
        std::size_t hits = 0;
        std::uint64_t empty = 0;
        for (const ReliefParameters& p : rcx_test::secant_parameter_sets()) {
            CAPTURE(p.epsilon);
            CAPTURE(p.max_gap);
            CAPTURE(p.max_reads);
            const Comparison c = gpu.run(p);
            std::printf("CDCT secant search on %s (epsilon %g, max_gap %g, max_reads %d): %zu of %zu equal to C++ "
                        "(%zu hits, %.2f texels read per search)\n",
                        names[k], p.epsilon, p.max_gap, p.max_reads, c.same, queries.size(), c.hits,
                        static_cast<double>(c.texels) / queries.size());
            CHECK(c.same == queries.size());
            CHECK(c.hits < queries.size());
            CHECK(c.texels <= static_cast<long long>(queries.size()) * p.max_reads);
            compared += queries.size();
            all_same += c.same;
            hits += c.hits;
            empty += c.empty;
        }
        CHECK(hits > queries.size()); // both kinds of cube answer many searches over the sets
        CHECK(empty > 0u);            // and miss on empty texels, which the GPU counts as C++ does
    }
    std::printf("CDCT secant search: %zu of %zu GLSL searches equal to C++ bit for bit\n", all_same, compared);
    CHECK(compared >= 20000);
    CHECK(all_same == compared);
}

TEST_CASE("raycache_cdct_search makes the search the parameters name, as depth_search does") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    const rcx::vk::ComputePipeline cross = cross_pipeline(*vk);
    std::mt19937 rng(25);
    Scene s = make_scene(rng, true);
    GpuSearches gpu(*vk, cross, s, search_queries(s, rng, 500, 5));
    long long texels_read[2] = {0, 0};
    for (const DepthSearch search : {DepthSearch::secant, DepthSearch::relief}) {
        ReliefParameters p;
        p.search = search;
        const Comparison c = gpu.run(p);
        CHECK(c.same == gpu.queries.size());
        CHECK(c.hits > 0);
        texels_read[search == DepthSearch::relief] = c.texels;
    }
    CHECK(texels_read[0] < texels_read[1]); // the secant search did read fewer texels: it was the one made
}
