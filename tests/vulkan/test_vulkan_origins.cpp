// The CCT's origin test on the GPU (RAYCACHE_ORIGINS: origin records per tile, the publish and drop passes
// of raycache/end_frame.glsl) against C++'s CacheCube::lookup and store with an OriginTolerance:
// - a hand-made case: a tile stored from the origin (0, 0, 0) at distance 10 answers origins within the
//   allowed drift (min(drift, parallax x 10)), misses beyond it, refuses a store that would widen its box
//   past the drift, and is emptied between frames after such a miss while another face's tile is kept;
// - random frames of stores and lookups from origins that drift, in cubes of 8, 20 and 33 texels a face
//   (partial tiles), with the confidence test on: the GPU's texels, doubtful bits, lookups, counters and
//   visible origin records equal C++'s after every frame, with the store list and after an overflow with
//   the sweep.
// Shaders: origin_queries.comp (stores and lookups), origin_end_frame.comp (the three passes and the sweep).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include <raycache/raycache.hpp>

#include "vulkan_test.hpp"

using namespace raycache;

namespace {

// shaders/origin_queries.comp's Query and push constants (std430).
struct Query {
    glm::vec3 direction;
    std::uint32_t mode; // 0: store_from, 1: lookup_from
    glm::vec3 color;
    float hit_distance;
    glm::vec3 origin;
    std::uint32_t cube;
};
static_assert(sizeof(Query) == 48, "Query must match origin_queries.comp");
struct QueryPush {
    std::uint32_t count;
    float drift, parallax;
};
struct EndFramePush {
    std::uint32_t pass;
    float threshold;
};

const std::vector<VkDescriptorType> query_bindings(12, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
const std::vector<VkDescriptorType> end_frame_bindings(10, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);

rcx::vk::Buffer words_buffer(rcx::vk::Context& vk, std::uint64_t bytes, std::uint32_t word) {
    rcx::vk::Buffer b(vk, std::max<std::uint64_t>(bytes, 16));
    b.fill(word);
    return b;
}

// CCT cubes in GPU buffers with origin records and doubtful bits, beside the same cubes in C++. Queries are
// queued for both and run by run(): on the GPU a frame of queries and the three end-of-frame passes (or the
// sweep); in C++ the same calls, mark_doubtful_edges and begin_frame().
struct Rig {
    Rig(rcx::vk::Context& context, const std::vector<int>& sizes, OriginTolerance tolerance, float threshold,
        std::uint32_t list_capacity = 0)
        : vk(context),
          tolerance(tolerance),
          threshold(threshold),
          queries_pipeline(vk, rcx_test::spirv("origin_queries"), query_bindings, sizeof(QueryPush)),
          end_frame(vk, rcx_test::spirv("origin_end_frame"), end_frame_bindings, sizeof(EndFramePush)),
          layout(gpu_buffer_layout<CctTexel>(shapes_of(sizes))),
          texels(words_buffer(vk, layout.bytes, gpu_clear_word)),
          pending(words_buffer(vk, layout.bytes, gpu_clear_word)),
          doubtful(words_buffer(vk, layout.doubtful_bytes, gpu_doubtful_clear_word)),
          origins(words_buffer(vk, layout.origin_bytes, gpu_clear_word)),
          table(rcx_test::buffer_of(vk, layout.cubes)),
          dummy(words_buffer(vk, 16, 0u)),
          frame(vk, static_cast<std::uint32_t>(sizes.size()),
                list_capacity ? list_capacity : static_cast<std::uint32_t>(layout.texels + layout.origin_tiles)) {
        for (int n : sizes) cubes.push_back(std::make_unique<CctCube>(n));
    }
    static std::vector<GpuCubeShape> shapes_of(const std::vector<int>& sizes) {
        std::vector<GpuCubeShape> shapes;
        for (int n : sizes) shapes.push_back({n, CubeBounds{}});
        return shapes;
    }

    void store(std::uint32_t k, const glm::vec3& d, const glm::vec3& colour, const glm::vec3& origin, float hit) {
        queries.push_back(Query{d, 0u, colour, hit, origin, k});
        cpu_results.push_back(glm::uvec4(cubes[k]->store(d, colour, origin, hit, tolerance) ? 1u : 0u, 0u, 0u, 0u));
    }
    void lookup(std::uint32_t k, const glm::vec3& d, const glm::vec3& origin) {
        queries.push_back(Query{d, 1u, glm::vec3(0.0f), 0.0f, origin, k});
        const std::optional<glm::vec3> c = cubes[k]->lookup(d, origin, tolerance);
        cpu_results.push_back(c ? glm::uvec4(1u, glm::floatBitsToUint(*c)) : glm::uvec4(0u));
    }

    // Runs the queued queries as one GPU frame and ends it; ends the same frame in C++. Checks that every
    // lookup answered as C++'s did and the counters agree; returns the GPU's results.
    std::vector<glm::uvec4> run(bool sweep = false) {
        if (queries.empty()) lookup(0, glm::vec3(1.0f, 0.0f, 0.0f), glm::vec3(0.0f));
        rcx::vk::Buffer query_buffer = rcx_test::buffer_of(vk, queries);
        rcx::vk::Buffer results(vk, queries.size() * sizeof(glm::uvec4));
        const QueryPush push{static_cast<std::uint32_t>(queries.size()), tolerance.drift, tolerance.parallax};
        const std::uint32_t sweep_groups = rcx::vk::group_count(std::max(layout.texels, layout.origin_tiles), RAYCACHE_END_FRAME_GROUP_SIZE);
        frame.start();
        vk.submit([&](rcx::vk::Commands& c) {
            c.dispatch(queries_pipeline, {texels, pending, dummy, dummy, frame.buffer, doubtful, dummy, table, dummy, origins, query_buffer, results},
                       &push, sizeof push, rcx::vk::group_count(queries.size(), 64));
            c.barrier();
            for (std::uint32_t pass = 0; pass < 3; ++pass) {
                const EndFramePush p{sweep ? pass + 3 : pass, threshold};
                const std::initializer_list<rcx::vk::Resource> buffers = {texels, pending, dummy, dummy, frame.buffer,
                                                                          doubtful, dummy, table, dummy, origins};
                if (sweep) c.dispatch(end_frame, buffers, &p, sizeof p, sweep_groups);
                else c.dispatch_indirect(end_frame, buffers, &p, sizeof p, frame.buffer, gpu_end_frame_dispatch_offset);
                c.barrier();
            }
        });
        const GpuFrameStatistics gpu = frame.statistics();
        overflow_last_frame = gpu.overflow;
        for (std::size_t k = 0; k < cubes.size(); ++k) {
            CAPTURE(k);
            const CubeStatistics& g = gpu.cubes[k];
            const CubeStatistics cpu = cubes[k]->statistics();
            CHECK(g.hits == cpu.hits);
            CHECK(g.misses == cpu.misses);
            // A texel stored earlier in the frame is not published yet: the GPU counts its misses as on an
            // empty texel, C++ as fresh.
            CHECK(g.misses_by[static_cast<std::size_t>(MissReason::empty)] ==
                  cpu.misses_by[static_cast<std::size_t>(MissReason::empty)] + cpu.misses_by[static_cast<std::size_t>(MissReason::fresh)]);
            CHECK(g.stores + g.refused_stores == cpu.stores + cpu.refused_stores); // same-frame losers count apart
            total_hits += cpu.hits, total_misses += cpu.misses;
            mark_doubtful_edges(*cubes[k], threshold);
            cubes[k]->begin_frame();
        }
        const glm::uvec4* r = results.as<glm::uvec4>();
        std::vector<glm::uvec4> out(r, r + queries.size());
        for (std::size_t i = 0; i < queries.size(); ++i)
            if (queries[i].mode == 1u) {
                CAPTURE(i);
                CHECK(out[i] == cpu_results[i]);
            }
        queries.clear();
        cpu_results.clear();
        return out;
    }

    // After a frame: every texel word and doubtful bit equals C++'s, every visible record equals what
    // write_gpu_origins makes of C++'s tiles, and the frame's words of every record are clear again.
    void check_same() const {
        std::vector<std::uint32_t> expected(static_cast<std::size_t>(layout.origin_words), gpu_clear_word);
        for (std::uint32_t k = 0; k < cubes.size(); ++k) {
            CAPTURE(k);
            const std::vector<std::uint32_t> words = rcx_test::words_of(*cubes[k]);
            const int n = cubes[k]->face_size();
            for (int face = 0; face < 6; ++face)
                for (int row = 0; row < n; ++row)
                    for (int column = 0; column < n; ++column) {
                        const TexelAddress t{face, column, row};
                        const std::uint32_t e = gpu_element(layout.cubes[k], t);
                        CAPTURE(e);
                        const std::uint32_t cpu = words[e - layout.cubes[k].first_texel];
                        const std::uint32_t gpu = texels.as<std::uint32_t>()[e];
                        REQUIRE(CctTexel::is_valid(gpu) == CctTexel::is_valid(cpu));
                        if (CctTexel::is_valid(gpu)) REQUIRE(gpu == cpu);
                        CHECK(gpu_doubtful(doubtful.as<std::uint32_t>(), layout.doubtful_words, e) == cubes[k]->is_doubtful(t));
                    }
            write_gpu_origins(*cubes[k], layout.cubes[k], expected.data(), expected.size());
        }
        const std::uint32_t* records = origins.as<std::uint32_t>();
        for (std::size_t w = 0; w < expected.size(); ++w) {
            CAPTURE(w);
            REQUIRE(records[w] == expected[w]);
        }
    }
    std::size_t gpu_boxes() const {
        std::size_t boxes = 0;
        for (std::uint64_t t = 0; t < layout.origin_tiles; ++t)
            boxes += origins.as<std::uint32_t>()[t * RAYCACHE_ORIGIN_RECORD_WORDS + RAYCACHE_ORIGIN_LO] != gpu_clear_word;
        return boxes;
    }

    rcx::vk::Context& vk;
    OriginTolerance tolerance;
    float threshold;
    rcx::vk::ComputePipeline queries_pipeline, end_frame;
    GpuBufferLayout layout;
    rcx::vk::Buffer texels, pending, doubtful, origins, table, dummy;
    rcx_test::Frame frame;
    std::vector<std::unique_ptr<CctCube>> cubes;
    std::vector<Query> queries;
    std::vector<glm::uvec4> cpu_results;
    std::uint64_t overflow_last_frame = 0;
    std::uint64_t total_hits = 0, total_misses = 0;
};

// Random frames: a camera drifting along x, stores and lookups from origins scattered around it; stores
// of random colours (some alike, so the confidence test marks some texels and leaves others).
void random_frames(Rig& rig, unsigned seed, int frames, bool sweep) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), unit(0.0f, 1.0f);
    std::size_t dropped_tiles = 0;
    for (int f = 0; f < frames; ++f) {
        CAPTURE(f);
        const glm::vec3 camera(0.04f * static_cast<float>(f), 0.0f, 0.0f);
        for (std::uint32_t k = 0; k < rig.cubes.size(); ++k)
            for (int q = 0; q < 600; ++q) {
                const glm::vec3 d(u(rng), u(rng), u(rng));
                const glm::vec3 origin = camera + glm::vec3(u(rng), u(rng), u(rng)) * (unit(rng) < 0.8f ? 0.03f : 0.3f);
                if (unit(rng) < 0.5f) {
                    const float hit = unit(rng) < 0.1f ? std::numeric_limits<float>::infinity() : 1.0f + 20.0f * unit(rng);
                    rig.store(k, d, glm::vec3(unit(rng) < 0.5f ? 0.25f : 0.75f, 0.5f, 0.1f * unit(rng)), origin, hit);
                } else {
                    rig.lookup(k, d, origin);
                }
            }
        std::size_t tiles_before = 0;
        for (const auto& cube : rig.cubes) tiles_before += cube->dropped_tiles();
        rig.run(sweep);
        for (const auto& cube : rig.cubes) dropped_tiles += cube->dropped_tiles();
        dropped_tiles -= tiles_before;
        rig.check_same();
    }
    // The frames exercised every path: answers, misses, dropped tiles and boxes left.
    CHECK(rig.total_hits > 100);
    CHECK(rig.total_misses > 100);
    CHECK(dropped_tiles > 0);
    CHECK(rig.gpu_boxes() > 0);
}

} // namespace

TEST_CASE("a GPU tile answers origins within the allowed drift of its box, refuses stores that widen it too far, and is emptied after a miss") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    // drift 1.0, parallax 0.01: a tile whose nearest hit lies at 10 allows min(1.0, 0.1) = 0.1.
    Rig rig(*vk, {16}, OriginTolerance{1.0f, 0.01f}, -1.0f);
    const glm::vec3 a = texel_direction(TexelAddress{0, 3, 3}, 16), b = texel_direction(TexelAddress{0, 5, 4}, 16);
    const glm::vec3 c = texel_direction(TexelAddress{0, 9, 9}, 16), other = texel_direction(TexelAddress{2, 3, 3}, 16);
    rig.store(0, a, glm::vec3(1.0f, 0.0f, 0.0f), glm::vec3(0.0f), 10.0f);
    rig.store(0, other, glm::vec3(0.0f, 1.0f, 0.0f), glm::vec3(0.0f), 10.0f);
    rig.run();
    rig.check_same();
    const std::uint32_t* record = rig.origins.as<std::uint32_t>(); // face 0's tile is record 0
    CHECK(record[RAYCACHE_ORIGIN_LO] == 0x80000000u);              // +0: sign bit set
    CHECK(record[RAYCACHE_ORIGIN_NEAREST] == 0xC1200000u);         // 10.0 = 0x41200000 with its sign bit set

    rig.lookup(0, a, glm::vec3(0.09f, 0.0f, 0.0f));               // within 0.1: answered
    rig.lookup(0, other, glm::vec3(0.5f, 0.0f, 0.0f));            // face 2's tile, stored from 0 too: 0.5 away
    rig.store(0, b, glm::vec3(0.5f), glm::vec3(0.3f, 0.0f, 0.0f), 10.0f);   // a box 0.3 wide: refused
    rig.store(0, c, glm::vec3(0.5f), glm::vec3(0.05f, 0.0f, 0.0f), 10.0f);  // 0.05 wide: kept
    std::vector<glm::uvec4> r = rig.run();
    CHECK(r[0].x == 1u);
    CHECK(r[1].x == 0u); // 0.5 from face 2's box: a miss, and face 2's tile is dropped
    CHECK(r[2].x == 0u);
    CHECK(r[3].x == 1u);
    rig.check_same();
    CHECK(rig.texels.as<std::uint32_t>()[gpu_element(rig.layout.cubes[0], TexelAddress{2, 3, 3})] == gpu_clear_word);
    CHECK(rig.texels.as<std::uint32_t>()[gpu_element(rig.layout.cubes[0], TexelAddress{0, 9, 9})] != gpu_clear_word);
    CHECK(rig.origins.as<std::uint32_t>()[RAYCACHE_ORIGIN_HI] == ~0xBD4CCCCDu); // 0.05f = 0x3D4CCCCD: box now [0, 0.05]

    rig.lookup(0, a, glm::vec3(0.2f, 0.0f, 0.0f)); // 0.15 beyond [0, 0.05]: a miss, and face 0's tile goes
    rig.lookup(0, other, glm::vec3(0.0f));         // emptied last frame: a miss
    r = rig.run();
    CHECK(r[0].x == 0u);
    CHECK(r[1].x == 0u);
    rig.check_same();
    CHECK(rig.texels.as<std::uint32_t>()[gpu_element(rig.layout.cubes[0], TexelAddress{0, 3, 3})] == gpu_clear_word);
    CHECK(rig.gpu_boxes() == 0u);

    // With no bound by distance (parallax infinity) the drift alone decides: 0.5 of 1.0 is answered.
    Rig far(*vk, {16}, OriginTolerance{1.0f, std::numeric_limits<float>::infinity()}, -1.0f);
    far.store(0, a, glm::vec3(1.0f, 0.0f, 0.0f), glm::vec3(0.0f), 10.0f);
    far.run();
    far.lookup(0, a, glm::vec3(0.5f, 0.0f, 0.0f));
    far.lookup(0, a, glm::vec3(0.0f, 0.0f, -1.01f));
    r = far.run();
    CHECK(r[0].x == 1u);
    CHECK(r[1].x == 0u);
    far.check_same();
}

TEST_CASE("the GPU's origin test keeps, answers and drops what C++'s does, frame by frame, in cubes of 8, 20 and 33 texels") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    Rig rig(*vk, {8, 20, 33}, OriginTolerance{0.1f, 0.01f}, 0.1f);
    random_frames(rig, 11, 6, false);
    CHECK(rig.overflow_last_frame == 0u);
}

TEST_CASE("after a store-list overflow, the sweep publishes and drops what the listed passes would") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    Rig rig(*vk, {8, 20}, OriginTolerance{0.1f, 0.01f}, 0.1f, 64);
    random_frames(rig, 12, 4, true);
    CHECK(rig.overflow_last_frame > 0u);
}

TEST_CASE("the origin test's boundaries, by hand: within the allowed drift is inclusive, and a store's hit distance tightens it") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    const glm::vec3 a = texel_direction(TexelAddress{0, 3, 3}, 16), b = texel_direction(TexelAddress{1, 3, 3}, 16);
    const glm::vec3 c = texel_direction(TexelAddress{0, 5, 5}, 16), d = texel_direction(TexelAddress{0, 7, 7}, 16);
    const glm::vec3 e = texel_direction(TexelAddress{0, 9, 9}, 16);
    auto x = [](float v) { return glm::vec3(v, 0.0f, 0.0f); };
    {
        // Drift 0.25, no bound by distance: a box [0, 0] answers x = 0.25 and -0.25, not the next float up.
        Rig rig(*vk, {16}, OriginTolerance{0.25f, std::numeric_limits<float>::infinity()}, -1.0f);
        rig.store(0, a, glm::vec3(1.0f, 0.0f, 0.0f), x(0.0f), 10.0f);
        rig.store(0, b, glm::vec3(0.0f, 1.0f, 0.0f), x(0.0f), 10.0f);
        rig.run();
        rig.lookup(0, a, x(0.25f));
        rig.lookup(0, a, x(-0.25f));
        rig.lookup(0, b, x(std::nextafter(0.25f, 1.0f)));
        const std::vector<glm::uvec4> r = rig.run();
        CHECK(r[0].x == 1u);
        CHECK(r[1].x == 1u);
        CHECK(r[2].x == 0u);
        rig.check_same();
    }
    // Drift 1, parallax 0.125: stored from 0 at distance 2, lookups allow min(1, 0.125 x 2) = 0.25. A store
    // whose ray hit at 1 allows min(1, 0.125 x min(2, 1)) = 0.125: a box 0.125 wide is kept, 0.25 refused;
    // one that hit at 4 allows 0.25 (the tile's nearest, 2, decides). Then the box is [0, 0.25] and its
    // nearest 1: lookups allow 0.125, up to x = 0.375 exactly.
    Rig rig(*vk, {16}, OriginTolerance{1.0f, 0.125f}, -1.0f);
    rig.store(0, a, glm::vec3(1.0f, 0.0f, 0.0f), x(0.0f), 2.0f);
    rig.run();
    rig.lookup(0, a, x(0.25f));
    rig.lookup(0, a, x(-0.25f));
    rig.store(0, c, glm::vec3(0.5f), x(0.125f), 1.0f);
    rig.store(0, d, glm::vec3(0.5f), x(0.25f), 1.0f);
    rig.store(0, e, glm::vec3(0.5f), x(0.25f), 4.0f);
    std::vector<glm::uvec4> r = rig.run();
    CHECK(r[0].x == 1u);
    CHECK(r[1].x == 1u);
    CHECK(r[2].x == 1u);
    CHECK(r[3].x == 0u);
    CHECK(r[4].x == 1u);
    rig.check_same();
    CHECK(rig.origins.as<std::uint32_t>()[RAYCACHE_ORIGIN_NEAREST] == 0xBF800000u); // 1.0 = 0x3F800000, sign bit set
    rig.lookup(0, c, x(0.375f));
    rig.lookup(0, e, x(-0.125f));
    r = rig.run();
    CHECK(r[0].x == 1u);
    CHECK(r[1].x == 1u);
    rig.lookup(0, c, x(std::nextafter(0.375f, 1.0f))); // beyond by one float: a miss, and the tile goes
    rig.lookup(0, e, x(0.0f));                         // same tile, same frame: still answered (marks drop between frames)
    r = rig.run();
    CHECK(r[0].x == 0u);
    CHECK(r[1].x == 1u);
    rig.check_same();
    CHECK(rig.gpu_boxes() == 0u);
}
