// The CCT in GLSL (raycache/cct.glsl, driven by shaders/cct_cross.comp) against raycache::CctCube:
// texels written by C++ read the same in GLSL, and texels stored by GLSL, after the end-frame pass,
// are word for word what C++ makes of the same stores, and read the same in C++; lookups mark the direction
// cells C++'s DirectionCoverage marks.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <vector>

#include <raycache/raycache.hpp>

#include "vulkan_test.hpp"

using raycache::CctCube;
using raycache::CctTexel;
namespace gpu = raycache::shared;

namespace {

// shaders/cct_cross.comp's Query and its std430 layout.
struct Query {
    glm::vec3 direction;
    std::uint32_t cube;
    glm::vec3 color;
    std::uint32_t store; // 0: lookup, 1: store
};
static_assert(sizeof(Query) == 32, "Query must match the std430 layout in cct_cross.comp");

// Directions of every kind: random, near axes, ties, signed zeros, and a few that are not directions.
glm::vec3 any_direction(std::mt19937& rng) {
    std::normal_distribution<float> g;
    std::uniform_int_distribution<int> kind(0, 19);
    const float inf = std::numeric_limits<float>::infinity();
    switch (kind(rng)) {
    case 0: return glm::vec3(1.0f, 1.0f, -1.0f) * std::abs(g(rng)); // tie xyz
    case 1: return glm::vec3(g(rng), -std::abs(g(rng)) * 0.0f, 0.0f);  // signed zeros
    case 2: return glm::vec3(-0.5f, 0.5f, g(rng) * 0.4f);               // tie xy
    case 3: return kind(rng) < 10 ? glm::vec3(0.0f) : glm::vec3(std::nanf(""), 1.0f, inf);
    default: return glm::vec3(g(rng), g(rng), g(rng)) * std::exp2(std::uniform_real_distribution<float>(-20, 20)(rng));
    }
}

// Colours of every kind, including ones that clamp (negative, NaN, huge, infinite) and tiny ones.
glm::vec3 any_color(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::uniform_int_distribution<int> kind(0, 9);
    switch (kind(rng)) {
    case 0: return glm::vec3(-1.0f, std::nanf(""), std::numeric_limits<float>::infinity());
    case 1: return glm::vec3(1e5f * u(rng), u(rng), 0.0f);
    case 2: return glm::vec3(1e-6f * u(rng), 1e-9f, 0.0f);
    default: return glm::vec3(u(rng), u(rng), u(rng)) * 4.0f;
    }
}

struct Setup {
    std::vector<CctCube> cubes;
    std::vector<gpu::raycache_gpu_cube> descriptors;
    std::size_t elements = 0;
};

// Cubes of 1, 4, 16 and 37 texels per edge, one after the other in one buffer, each given (visible)
// fill * 6 N^2 stores of random colours in random directions.
Setup make_cubes(std::mt19937& rng, double fill) {
    Setup s;
    for (int n : {1, 4, 16, 37}) {
        s.cubes.emplace_back(n);
        s.descriptors.push_back(gpu::raycache_make_gpu_cube(glm::vec3(0.0f), 1.0f, static_cast<std::uint32_t>(s.elements), n));
        s.descriptors.back().index = static_cast<std::uint32_t>(s.cubes.size() - 1); // its counters in the frame buffer
        s.elements += s.cubes.back().texel_count();
    }
    for (CctCube& cube : s.cubes) {
        for (double i = 0; i < fill * static_cast<double>(cube.texel_count()); ++i) cube.store(any_direction(rng), any_color(rng));
        cube.begin_frame();
    }
    return s;
}

std::vector<std::uint32_t> buffer_words(const Setup& s) {
    std::vector<std::uint32_t> words;
    for (const CctCube& cube : s.cubes) {
        const std::vector<std::uint32_t> w = rcx_test::words_of(cube);
        words.insert(words.end(), w.begin(), w.end());
    }
    return words;
}


} // namespace

TEST_CASE("CCT texels written by C++ give the same lookups in GLSL as in C++") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    rcx::vk::ComputePipeline cross(*vk, rcx_test::spirv("cct_cross"), rcx_test::cross_bindings, 4);
    std::mt19937 rng(11);
    Setup s = make_cubes(rng, 1.0);

    std::vector<Query> queries;
    for (int i = 0; i < 40000; ++i)
        queries.push_back({any_direction(rng), static_cast<std::uint32_t>(i % s.cubes.size()), glm::vec3(0.0f), 0u});
    rcx::vk::Buffer texels = rcx_test::buffer_of(*vk, buffer_words(s));
    rcx::vk::Buffer pending(*vk, s.elements * 4);
    pending.fill(RAYCACHE_GPU_CLEAR_WORD);
    rcx::vk::Buffer cubes = rcx_test::buffer_of(*vk, s.descriptors);
    rcx::vk::Buffer query_buffer = rcx_test::buffer_of(*vk, queries);
    rcx::vk::Buffer results(*vk, queries.size() * 16);
    rcx_test::Frame frame(*vk, static_cast<std::uint32_t>(s.cubes.size()), static_cast<std::uint32_t>(s.elements));
    const std::uint32_t count = static_cast<std::uint32_t>(queries.size());
    vk->dispatch(cross, {texels, pending, cubes, query_buffer, results, frame.buffer}, &count, 4, rcx::vk::group_count(count, 64));

    const std::uint32_t* r = results.as<std::uint32_t>();
    std::size_t same = 0, hits = 0;
    for (std::size_t i = 0; i < queries.size(); ++i) {
        const auto expected = s.cubes[queries[i].cube].lookup(queries[i].direction);
        const bool ok = expected ? r[4 * i] == 1u && r[4 * i + 1] == glm::floatBitsToUint(expected->x) && r[4 * i + 2] == glm::floatBitsToUint(expected->y) &&
                                       r[4 * i + 3] == glm::floatBitsToUint(expected->z)
                                 : r[4 * i] == 0u;
        same += ok;
        hits += expected.has_value();
    }
    std::printf("CCT lookups, C++ texels read in GLSL: %zu of %zu equal to C++ (%zu hits)\n", same, queries.size(), hits);
    CHECK(same == queries.size());
    CHECK(hits > queries.size() / 10);
    CHECK(hits < queries.size() * 9 / 10);

    // The GPU's counters, per cube, equal the C++ cubes' own for the same lookups (made just above).
    const raycache::GpuFrameStatistics gpu_stats = frame.statistics();
    std::uint64_t empties = 0;
    for (std::size_t k = 0; k < s.cubes.size(); ++k) {
        CAPTURE(k);
        const raycache::CubeStatistics cpu = s.cubes[k].statistics();
        CHECK(gpu_stats.cubes[k].lookups == cpu.lookups);
        CHECK(gpu_stats.cubes[k].hits == cpu.hits);
        CHECK(gpu_stats.cubes[k].misses == cpu.misses);
        // Misses on texels holding no value (the host's still-camera rule), as C++ counts them.
        CHECK(gpu_stats.cubes[k].misses_by[static_cast<std::size_t>(raycache::MissReason::empty)] ==
              cpu.misses_by[static_cast<std::size_t>(raycache::MissReason::empty)]);
        empties += cpu.misses_by[static_cast<std::size_t>(raycache::MissReason::empty)];
        CHECK(gpu_stats.cubes[k].stores == 0u);
        CHECK(gpu_stats.cubes[k].refused_stores == 0u);
    }
    CHECK(gpu_stats.total.lookups == queries.size());
    CHECK(empties > 0u); // some lookups met empty texels
    CHECK(gpu_stats.listed == 0u);

    // Each cube's coverage bits in the frame buffer are the cells C++'s DirectionCoverage marks for the
    // same lookups' directions (the cells adaptive face sizes go by), and their share is what it counts.
    const std::uint32_t* frame_words = frame.buffer.as<std::uint32_t>();
    std::size_t cells_marked = 0;
    for (std::size_t k = 0; k < s.cubes.size(); ++k) {
        CAPTURE(k);
        raycache::DirectionCoverage cpu;
        for (const Query& q : queries)
            if (q.cube == k) cpu.mark(q.direction);
        const auto bits = cpu.marked_cells();
        const std::uint32_t* gpu_bits = frame_words + gpu::raycache_frame_coverage_word(static_cast<std::uint32_t>(k), 0);
        bool same_bits = true;
        for (std::uint32_t w = 0; w < RAYCACHE_COVERAGE_WORDS; ++w)
            same_bits = same_bits && gpu_bits[w] == static_cast<std::uint32_t>(bits[w / 2] >> (32 * (w % 2)));
        CHECK(same_bits);
        CHECK(gpu_stats.coverage[k] == cpu.fraction());
        cells_marked += static_cast<std::size_t>(cpu.fraction() * RAYCACHE_COVERAGE_CELLS);
    }
    CHECK(cells_marked > 4 * RAYCACHE_COVERAGE_CELLS / 2); // the directions spread over most cells of every cube

    // Started without RAYCACHE_FRAME_MARK_COVERAGE (fixed face sizes), the same lookups mark no cell, count no
    // miss on an empty texel, and count hits and lookups as before.
    frame.start(false);
    vk->dispatch(cross, {texels, pending, cubes, query_buffer, results, frame.buffer}, &count, 4, rcx::vk::group_count(count, 64));
    const raycache::GpuFrameStatistics unmarked = frame.statistics();
    std::size_t words_set = 0;
    for (std::size_t k = 0; k < s.cubes.size(); ++k) {
        const std::uint32_t* gpu_bits = frame_words + gpu::raycache_frame_coverage_word(static_cast<std::uint32_t>(k), 0);
        for (std::uint32_t w = 0; w < RAYCACHE_COVERAGE_WORDS; ++w) words_set += gpu_bits[w] != 0u;
        CHECK(unmarked.coverage[k] == 0.0);
        CHECK(unmarked.cubes[k].lookups == gpu_stats.cubes[k].lookups);
        CHECK(unmarked.cubes[k].hits == gpu_stats.cubes[k].hits);
        CHECK(unmarked.cubes[k].misses_by[static_cast<std::size_t>(raycache::MissReason::empty)] == 0u); // adaptive frames alone
    }
    CHECK(words_set == 0u);
}

TEST_CASE("CCT stores made in GLSL are invisible that frame, the smallest word wins, and C++ reads the result") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    rcx::vk::ComputePipeline cross(*vk, rcx_test::spirv("cct_cross"), rcx_test::cross_bindings, 4);
    rcx::vk::ComputePipeline end_frame(*vk, rcx_test::spirv("end_frame_listed"), rcx_test::listed_end_frame_bindings, 0);
    std::mt19937 rng(12);
    Setup s = make_cubes(rng, 0.2); // some texels visible already: stores into them are refused

    // One dispatch of stores and lookups mixed: many stores per texel (the small cubes have 6 and 96
    // texels), lookups of the same directions in between.
    std::vector<Query> queries;
    for (int i = 0; i < 30000; ++i) {
        const glm::vec3 d = any_direction(rng);
        const std::uint32_t cube = static_cast<std::uint32_t>(i % s.cubes.size());
        queries.push_back({d, cube, any_color(rng), 1u});
        queries.push_back({d, cube, glm::vec3(0.0f), 0u});
    }
    // What C++ answers this frame (before its own stores: a store is invisible in its frame anyway).
    std::vector<std::optional<glm::vec3>> expected_lookups;
    std::vector<bool> refused_for_sure; // not a direction, or the texel already visible
    for (const Query& q : queries) {
        expected_lookups.push_back(s.cubes[q.cube].lookup(q.direction));
        refused_for_sure.push_back(!raycache::is_direction(q.direction) || s.cubes[q.cube].lookup(q.direction));
    }

    rcx::vk::Buffer texels = rcx_test::buffer_of(*vk, buffer_words(s));
    rcx::vk::Buffer pending(*vk, s.elements * 4);
    pending.fill(RAYCACHE_GPU_CLEAR_WORD);
    rcx::vk::Buffer cubes = rcx_test::buffer_of(*vk, s.descriptors);
    rcx::vk::Buffer query_buffer = rcx_test::buffer_of(*vk, queries);
    rcx::vk::Buffer frame_results(*vk, queries.size() * 16);
    rcx::vk::Buffer next_results(*vk, queries.size() * 16);
    std::vector<Query> lookups = queries;
    for (Query& q : lookups) q.store = 0u;
    rcx::vk::Buffer lookup_buffer = rcx_test::buffer_of(*vk, lookups);
    rcx::vk::Buffer dummy(*vk, 16);
    rcx_test::Frame frame(*vk, static_cast<std::uint32_t>(s.cubes.size()), static_cast<std::uint32_t>(s.elements));
    const std::uint32_t count = static_cast<std::uint32_t>(queries.size());
    vk->submit([&](rcx::vk::Commands& c) {
        c.dispatch(cross, {texels, pending, cubes, query_buffer, frame_results, frame.buffer}, &count, 4, rcx::vk::group_count(count, 64));
        c.barrier();
        rcx_test::record_listed_end_frame(c, end_frame, texels, pending, dummy, dummy, frame);
    });
    // The frame's statistics and store list, read back before the next frame starts the frame buffer again.
    const raycache::GpuFrameStatistics gpu_stats = frame.statistics();
    const std::vector<std::uint32_t> listed = frame.listed();
    const std::uint32_t dispatched = frame.buffer.as<std::uint32_t>()[RAYCACHE_FRAME_DISPATCH];
    frame.start();
    vk->dispatch(cross, {texels, pending, cubes, lookup_buffer, next_results, frame.buffer}, &count, 4, rcx::vk::group_count(count, 64));

    // The same stores in C++, in order, then the end of the frame; count the texels that several
    // different words competed for.
    std::map<std::pair<std::uint32_t, std::size_t>, std::set<std::uint32_t>> competing;
    std::vector<std::uint64_t> certain_refusals(s.cubes.size(), 0), store_calls(s.cubes.size(), 0);
    for (std::size_t i = 0; i < queries.size(); ++i) {
        const Query& q = queries[i];
        if (!q.store) continue;
        CctCube& cube = s.cubes[q.cube];
        ++store_calls[q.cube];
        certain_refusals[q.cube] += refused_for_sure[i];
        if (s.cubes[q.cube].store(q.direction, q.color))
            competing[{q.cube, raycache::texel_linear_index(*raycache::texel_of(q.direction, cube.face_size()), cube.face_size())}]
                .insert(CctTexel::encode(q.color));
    }
    std::size_t contended = 0;
    for (const auto& texel : competing) contended += texel.second.size() > 1;
    // The texels C++ wrote this frame, as buffer elements: what the store list must hold, once each.
    std::set<std::uint32_t> written;
    for (std::size_t k = 0; k < s.cubes.size(); ++k)
        s.cubes[k].for_each_written_texel([&](const raycache::TexelAddress& t) {
            written.insert(s.descriptors[k].first_texel +
                           static_cast<std::uint32_t>(raycache::texel_linear_index(t, s.cubes[k].face_size())));
        });
    // Counters: stores refused before the pending word are exactly the certain refusals (not a direction, or
    // a visible texel); the others reached it, whether or not they won (C++'s stores plus its same-frame losers).
    for (std::size_t k = 0; k < s.cubes.size(); ++k) {
        CAPTURE(k);
        const raycache::CubeStatistics cpu = s.cubes[k].statistics();
        CHECK(gpu_stats.cubes[k].refused_stores == certain_refusals[k]);
        CHECK(gpu_stats.cubes[k].stores + gpu_stats.cubes[k].refused_stores == store_calls[k]);
        CHECK(cpu.stores + cpu.refused_stores == store_calls[k]);
        CHECK(gpu_stats.cubes[k].stores >= cpu.stores);
        std::uint64_t lookups_made = 0, hits_made = 0; // C++'s answers to the frame's lookup queries
        for (std::size_t i = 0; i < queries.size(); ++i)
            if (!queries[i].store && queries[i].cube == k) ++lookups_made, hits_made += expected_lookups[i].has_value();
        CHECK(gpu_stats.cubes[k].lookups == lookups_made);
        CHECK(gpu_stats.cubes[k].hits == hits_made);
    }
    CHECK(gpu_stats.overflow == 0u);
    CHECK(std::set<std::uint32_t>(listed.begin(), listed.end()) == written);
    CHECK(listed.size() == written.size()); // each texel listed once
    CHECK(dispatched == raycache::gpu_end_frame_groups(listed.size()));
    for (CctCube& cube : s.cubes) cube.begin_frame();

    // During the frame: lookups answered from the frame's start, stores refused where C++ must refuse.
    const std::uint32_t* r = frame_results.as<std::uint32_t>();
    std::size_t lookups_same = 0, lookup_count = 0, refusals_kept = 0, refusal_count = 0;
    for (std::size_t i = 0; i < queries.size(); ++i) {
        if (queries[i].store) {
            if (refused_for_sure[i]) {
                ++refusal_count;
                refusals_kept += r[4 * i] == 0u;
            }
        } else {
            ++lookup_count;
            const auto& e = expected_lookups[i];
            lookups_same += e ? r[4 * i] == 1u && r[4 * i + 1] == glm::floatBitsToUint(e->x) : r[4 * i] == 0u;
        }
    }
    CHECK(lookups_same == lookup_count);
    CHECK(refusals_kept == refusal_count);
    CHECK(refusal_count > 0);

    // After the end-frame pass: every word equals C++'s, and the pending buffer is empty again.
    const std::vector<std::uint32_t> expected_words = buffer_words(s);
    const std::uint32_t* words = texels.as<std::uint32_t>();
    std::size_t words_same = 0, valid = 0, pending_clear = 0;
    for (std::size_t i = 0; i < s.elements; ++i) {
        words_same += words[i] == expected_words[i];
        valid += CctTexel::is_valid(words[i]);
        pending_clear += pending.as<std::uint32_t>()[i] == RAYCACHE_GPU_CLEAR_WORD;
    }
    std::printf("CCT stores in GLSL: %zu of %zu words equal to C++'s after the frame (%zu valid, %zu stored by "
                "several different stores); %zu of %zu lookups during the frame equal to C++; %zu of %zu certain "
                "refusals refused\n",
                words_same, s.elements, valid, contended, lookups_same, lookup_count, refusals_kept, refusal_count);
    CHECK(words_same == s.elements);
    CHECK(pending_clear == s.elements);
    CHECK(contended > 100);

    // C++ reads the GPU's words: a fresh cube filled from them equals the C++ cube, and the lookups of
    // the next frame in GLSL equal those of C++ on either cube.
    std::size_t cube_index = 0;
    for (const CctCube& cube : s.cubes) {
        CctCube copy(cube.face_size());
        rcx_test::store_words(copy, words + s.descriptors[cube_index++].first_texel);
        copy.begin_frame();
        CHECK(rcx_test::words_of(copy) == rcx_test::words_of(cube));
    }
    const std::uint32_t* next = next_results.as<std::uint32_t>();
    std::size_t next_same = 0, next_hits = 0;
    for (std::size_t i = 0; i < lookups.size(); ++i) {
        const auto e = s.cubes[lookups[i].cube].lookup(lookups[i].direction);
        next_hits += e.has_value();
        next_same += e ? next[4 * i] == 1u && next[4 * i + 1] == glm::floatBitsToUint(e->x) && next[4 * i + 2] == glm::floatBitsToUint(e->y) &&
                             next[4 * i + 3] == glm::floatBitsToUint(e->z)
                       : next[4 * i] == 0u;
    }
    CHECK(next_same == lookups.size());
    CHECK(next_hits > lookups.size() / 2);
}

TEST_CASE("the end-of-frame pass publishes the listed texels only, and a list that overflows is made good by the sweep") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    rcx::vk::ComputePipeline cross(*vk, rcx_test::spirv("cct_cross"), rcx_test::cross_bindings, 4);
    rcx::vk::ComputePipeline listed_pass(*vk, rcx_test::spirv("end_frame_listed"), rcx_test::listed_end_frame_bindings, 0);
    rcx::vk::ComputePipeline sweep(*vk, rcx_test::spirv("end_frame_cct"), rcx_test::end_frame_bindings, 0);
    for (const std::uint32_t capacity : {100000u, 40u}) {
        CAPTURE(capacity);
        std::mt19937 rng(13);
        Setup s = make_cubes(rng, 0.1);
        std::vector<Query> queries;
        for (int i = 0; i < 3000; ++i)
            queries.push_back({any_direction(rng), static_cast<std::uint32_t>(i % s.cubes.size()), any_color(rng), 1u});
        const std::vector<std::uint32_t> before = buffer_words(s); // visible words, before this frame's stores
        for (const Query& q : queries) s.cubes[q.cube].store(q.direction, q.color); // the oracle
        std::set<std::uint32_t> written;
        for (std::size_t k = 0; k < s.cubes.size(); ++k)
            s.cubes[k].for_each_written_texel([&](const raycache::TexelAddress& t) {
                written.insert(s.descriptors[k].first_texel + static_cast<std::uint32_t>(raycache::texel_linear_index(t, s.cubes[k].face_size())));
            });
        for (CctCube& cube : s.cubes) cube.begin_frame();
        const std::vector<std::uint32_t> after = buffer_words(s);

        rcx::vk::Buffer texels = rcx_test::buffer_of(*vk, before);
        rcx::vk::Buffer pending(*vk, s.elements * 4);
        pending.fill(RAYCACHE_GPU_CLEAR_WORD);
        rcx::vk::Buffer cubes = rcx_test::buffer_of(*vk, s.descriptors);
        rcx::vk::Buffer query_buffer = rcx_test::buffer_of(*vk, queries);
        rcx::vk::Buffer results(*vk, queries.size() * 16);
        rcx::vk::Buffer dummy(*vk, 16);
        rcx_test::Frame frame(*vk, static_cast<std::uint32_t>(s.cubes.size()), capacity);
        const std::uint32_t count = static_cast<std::uint32_t>(queries.size());
        vk->dispatch(cross, {texels, pending, cubes, query_buffer, results, frame.buffer}, &count, 4, rcx::vk::group_count(count, 64));

        // A planted pending word in an empty texel no store reached: the pass must not visit it.
        std::uint32_t planted = 0;
        while (planted < s.elements && (written.count(planted) || CctTexel::is_valid(before[planted]))) ++planted;
        REQUIRE(planted < s.elements);
        pending.as<std::uint32_t>()[planted] = 0x1234u;

        const raycache::GpuFrameStatistics stats = frame.statistics();
        vk->submit([&](rcx::vk::Commands& c) { rcx_test::record_listed_end_frame(c, listed_pass, texels, pending, dummy, dummy, frame); });
        const std::uint32_t* words = texels.as<std::uint32_t>();
        CHECK(stats.listed + stats.overflow == written.size());
        CHECK(words[planted] == RAYCACHE_GPU_CLEAR_WORD);
        CHECK(pending.as<std::uint32_t>()[planted] == 0x1234u);
        std::size_t published = 0, unchanged = 0;
        for (std::uint32_t i = 0; i < s.elements; ++i) {
            if (words[i] == after[i] && words[i] != before[i]) ++published;
            if (words[i] == before[i]) ++unchanged;
        }
        if (capacity >= written.size()) {
            CHECK(stats.overflow == 0u);
            CHECK(published == written.size());
            CHECK(unchanged == s.elements - written.size());
        } else {
            // Only `capacity` texels were listed and published; the sweep publishes the rest (and the planted word).
            CHECK(stats.listed == capacity);
            CHECK(stats.overflow == written.size() - capacity);
            CHECK(published == capacity);
            pending.as<std::uint32_t>()[planted] = RAYCACHE_GPU_CLEAR_WORD;
            vk->submit([&](rcx::vk::Commands& c) {
                const raycache::GpuGroups g = raycache::gpu_sweep_groups(s.elements);
                c.dispatch(sweep, {texels, pending}, nullptr, 0, g.x, g.y);
            });
        }
        std::size_t same = 0;
        for (std::uint32_t i = 0; i < s.elements; ++i) same += i == planted || words[i] == after[i];
        CHECK(same == s.elements);
        std::printf("end-of-frame pass, list of %u: %zu texels stored, %llu listed, %llu overflowed; %zu of %zu words "
                    "equal to C++'s after the frame\n",
                    capacity, written.size(), static_cast<unsigned long long>(stats.listed),
                    static_cast<unsigned long long>(stats.overflow), same, s.elements);
    }
}
