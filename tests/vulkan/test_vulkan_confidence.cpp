// The confidence test on the GPU (RAYCACHE_CONFIDENCE: doubtful-bit buffers, the mark pass of
// raycache/end_frame.glsl) against C++'s raycache::mark_doubtful_edges: the same stores give the same
// doubtful texels bit for bit on CCT and CDCT cubes (several cubes of different sizes per buffer, over two
// frames), hand-derived marks on a 2 x 2 face (strictly more than the threshold, never across a face's
// edge), lookups and searches that miss on doubtful texels as C++'s do, and a threshold < 0 or NaN that
// marks nothing. Shaders: confidence_queries.comp (stores, lookups, searches), confidence_end_frame.comp
// (both passes, and the sweep after a store-list overflow), each also compiled for the CCT alone, which runs
// on a device without shaderInt64.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <vector>

#include <raycache/raycache.hpp>

#include "vulkan_test.hpp"

using namespace raycache;

namespace {

// shaders/confidence_queries.comp's Query (std430).
struct Query {
    glm::vec3 direction;
    std::uint32_t mode; // 0: CCT store, 1: CCT lookup, 2: CDCT store, 3: secant search, 4: relief walk
    glm::vec3 color;
    float distance;
    glm::vec3 origin;
    std::uint32_t cube;
};
static_assert(sizeof(Query) == 48, "Query must match confidence_queries.comp");

struct EndFramePush {
    std::uint32_t pass; // 0: publish the listed texels, 1: mark them; 2: publish every element, 3: mark every one
    float threshold;
};

const std::vector<VkDescriptorType> query_bindings(11, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
const std::vector<VkDescriptorType> end_frame_bindings(9, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);

std::vector<GpuCubeShape> shapes_of(const std::vector<int>& sizes, float x) {
    std::vector<GpuCubeShape> shapes;
    for (int n : sizes) shapes.push_back({n, CubeBounds{glm::vec3(x, 0.0f, 0.0f), 1.0f}}), x += 3.0f;
    return shapes;
}

rcx::vk::Buffer words_buffer(rcx::vk::Context& vk, std::uint64_t bytes, std::uint32_t word) {
    rcx::vk::Buffer b(vk, std::max<std::uint64_t>(bytes, 16));
    b.fill(word);
    return b;
}

// A cube table: the descriptors, or one zero (no texels) when there are none.
rcx::vk::Buffer table_buffer(rcx::vk::Context& vk, const std::vector<shared::raycache_gpu_cube>& cubes) {
    if (!cubes.empty()) return rcx_test::buffer_of(vk, cubes);
    return words_buffer(vk, sizeof(shared::raycache_gpu_cube), 0u);
}

// CCT and CDCT cubes in GPU buffers with the confidence test, beside the same cubes in C++. Stores are
// queued for both (store_cct, store_cdct) and made by run(): on the GPU a frame of queries, the end-of-frame
// pass, a barrier and the mark pass; in C++ the stores, mark_doubtful_edges and begin_frame().
struct Rig {
    // list_capacity: the store list's entries (0: every texel, so it never overflows).
    Rig(rcx::vk::Context& context, const std::vector<int>& cct_sizes, const std::vector<int>& cdct_sizes, bool cct_only,
        std::uint32_t list_capacity = 0)
        : vk(context),
          queries_pipeline(vk, rcx_test::spirv(cct_only ? "confidence_queries_cct" : "confidence_queries"), query_bindings,
                           sizeof(std::uint32_t)),
          end_frame(vk, rcx_test::spirv(cct_only ? "confidence_end_frame" : "confidence_cdct"), end_frame_bindings,
                    sizeof(EndFramePush)),
          cct_layout(gpu_buffer_layout<CctTexel>(shapes_of(cct_sizes, 0.0f), 0)),
          cdct_layout(gpu_buffer_layout<CdctTexel>(shapes_of(cdct_sizes, 0.0f), static_cast<std::uint32_t>(cct_sizes.size()))),
          cct_texels(words_buffer(vk, cct_layout.bytes, gpu_clear_word)),
          cct_pending(words_buffer(vk, cct_layout.bytes, gpu_clear_word)),
          cdct_texels(words_buffer(vk, cdct_layout.bytes, gpu_clear_word)),
          cdct_pending(words_buffer(vk, cdct_layout.bytes, gpu_clear_word)),
          cct_doubtful(words_buffer(vk, cct_layout.doubtful_bytes, gpu_doubtful_clear_word)),
          cdct_doubtful(words_buffer(vk, cdct_layout.doubtful_bytes, gpu_doubtful_clear_word)),
          cct_table(table_buffer(vk, cct_layout.cubes)),
          cdct_table(table_buffer(vk, cdct_layout.cubes)),
          frame(vk, static_cast<std::uint32_t>(cct_sizes.size() + cdct_sizes.size()),
                list_capacity ? list_capacity
                              : static_cast<std::uint32_t>(std::max<std::uint64_t>(cct_layout.texels + cdct_layout.texels, 1))) {
        for (int n : cct_sizes) cct.push_back(std::make_unique<CctCube>(n));
        for (int n : cdct_sizes) cdct.push_back(std::make_unique<CdctCube>(n));
    }

    void store_cct(std::uint32_t k, const TexelAddress& t, const glm::vec3& colour) {
        const glm::vec3 d = texel_direction(t, cct[k]->face_size());
        queries.push_back(Query{d, 0u, colour, 0.0f, glm::vec3(0.0f), k});
        cct[k]->store(d, colour);
    }
    void store_cdct(std::uint32_t k, const TexelAddress& t, const glm::vec3& colour, float distance) {
        const glm::vec3 d = texel_direction(t, cdct[k]->face_size());
        queries.push_back(Query{d, 2u, colour, distance, glm::vec3(0.0f), k});
        cdct[k]->store(d, DepthSample{colour, distance});
    }

    // Runs the queued queries as one GPU frame and the same frame in C++; returns the GPU's results. sweep:
    // end the frame as after a store-list overflow, with the sweep and the confidence test over every element.
    std::vector<glm::uvec4> run(float threshold, bool sweep = false) {
        if (queries.empty()) queries.push_back(Query{glm::vec3(0.0f), 1u, glm::vec3(0.0f), 0.0f, glm::vec3(0.0f), 0u});
        rcx::vk::Buffer query_buffer = rcx_test::buffer_of(vk, queries);
        rcx::vk::Buffer results(vk, queries.size() * sizeof(glm::uvec4));
        const std::uint32_t count = static_cast<std::uint32_t>(queries.size());
        const EndFramePush publish{sweep ? 2u : 0u, threshold}, mark{sweep ? 3u : 1u, threshold};
        const std::uint32_t sweep_groups =
            rcx::vk::group_count(std::max(cct_layout.texels, cdct_layout.texels), RAYCACHE_END_FRAME_GROUP_SIZE);
        frame.start();
        vk.submit([&](rcx::vk::Commands& c) {
            c.dispatch(queries_pipeline,
                       {cct_texels, cct_pending, cdct_texels, cdct_pending, frame.buffer, cct_doubtful, cdct_doubtful, cct_table,
                        cdct_table, query_buffer, results},
                       &count, sizeof count, rcx::vk::group_count(queries.size(), 64));
            c.barrier();
            for (const EndFramePush* push : {&publish, &mark}) {
                const std::initializer_list<rcx::vk::Resource> buffers = {cct_texels,  cct_pending,   cdct_texels,
                                                                          cdct_pending, frame.buffer,  cct_doubtful,
                                                                          cdct_doubtful, cct_table,    cdct_table};
                if (sweep) c.dispatch(end_frame, buffers, push, sizeof *push, sweep_groups);
                else c.dispatch_indirect(end_frame, buffers, push, sizeof *push, frame.buffer, gpu_end_frame_dispatch_offset);
                c.barrier(); // the published texels, visible to the mark pass
            }
        });
        for (auto& cube : cct) mark_doubtful_edges(*cube, threshold), cube->begin_frame();
        for (auto& cube : cdct) mark_doubtful_edges(*cube, threshold), cube->begin_frame();
        listed_last_frame = frame.statistics().listed;
        overflow_last_frame = frame.statistics().overflow;
        const glm::uvec4* r = results.as<glm::uvec4>();
        std::vector<glm::uvec4> out(r, r + queries.size());
        queries.clear();
        return out;
    }

    static std::uint32_t element(const GpuBufferLayout& layout, std::uint32_t k, const TexelAddress& t) {
        const shared::raycache_gpu_cube& at = layout.cubes[k];
        return at.first_texel +
               shared::raycache_texel_linear_index(shared::raycache_texel_address{t.face, t.column, t.row}, at.face_size);
    }
    // Set bits of both doubtful-bit buffers.
    std::uint64_t gpu_marks() const {
        std::uint64_t bits = 0;
        for (std::uint64_t i = 0; i < cct_layout.doubtful_words; ++i) bits += popcount(cct_doubtful.as<std::uint32_t>()[i]);
        for (std::uint64_t i = 0; i < cdct_layout.doubtful_words; ++i) bits += popcount(cdct_doubtful.as<std::uint32_t>()[i]);
        return bits;
    }
    static int popcount(std::uint32_t w) {
        int n = 0;
        for (; w; w &= w - 1) ++n;
        return n;
    }

    // Every texel of every cube: the GPU's doubtful bit equals C++'s is_doubtful, and the texel words agree.
    // Returns the marks counted.
    std::size_t check_same_marks() const {
        const std::size_t marks = check_cubes(cct, cct_layout, cct_texels, cct_doubtful) +
                                  check_cubes(cdct, cdct_layout, cdct_texels, cdct_doubtful);
        CHECK(gpu_marks() == marks);
        return marks;
    }
    template <class Texel>
    static std::size_t check_cubes(const std::vector<std::unique_ptr<CacheCube<Texel>>>& cubes, const GpuBufferLayout& layout,
                                   const rcx::vk::Buffer& texels, const rcx::vk::Buffer& doubtful) {
        using Word = typename Texel::Word;
        std::size_t marks = 0;
        for (std::uint32_t k = 0; k < cubes.size(); ++k) {
            CAPTURE(k);
            const std::vector<Word> words = rcx_test::words_of(*cubes[k]);
            const int n = cubes[k]->face_size();
            for (int face = 0; face < 6; ++face)
                for (int row = 0; row < n; ++row)
                    for (int column = 0; column < n; ++column) {
                        const TexelAddress t{face, column, row};
                        const std::uint32_t e = element(layout, k, t);
                        CAPTURE(e);
                        const Word gpu = texels.as<Word>()[e], cpu = words[e - layout.cubes[k].first_texel];
                        REQUIRE(Texel::is_valid(gpu) == Texel::is_valid(cpu)); // (C++'s empty CDCT word is not the GPU's)
                        if (Texel::is_valid(gpu)) REQUIRE(gpu == cpu);
                        const bool expected = cubes[k]->is_doubtful(t);
                        CHECK(gpu_doubtful(doubtful.as<std::uint32_t>(), layout.doubtful_words, e) == expected);
                        marks += expected;
                    }
        }
        return marks;
    }

    rcx::vk::Context& vk;
    rcx::vk::ComputePipeline queries_pipeline, end_frame;
    GpuBufferLayout cct_layout, cdct_layout;
    rcx::vk::Buffer cct_texels, cct_pending, cdct_texels, cdct_pending, cct_doubtful, cdct_doubtful, cct_table, cdct_table;
    rcx_test::Frame frame;
    std::vector<std::unique_ptr<CctCube>> cct;
    std::vector<std::unique_ptr<CdctCube>> cdct;
    std::vector<Query> queries;
    std::uint64_t listed_last_frame = 0, overflow_last_frame = 0;
};

// A hand-made pattern with edges: 2 x 2 checker blocks of 0.25 / 0.75 in red, plus noise of up to 0.15 in
// blue (so some neighbours inside a block differ by more than 0.1 and some by less); texels where `skip`
// holds are left for the second frame; one texel in four gets a second, competing store.
struct Pattern {
    explicit Pattern(unsigned seed) : rng(seed) {}
    static bool skip(const TexelAddress& t) { return (t.face * 3 + t.row * 5 + t.column * 7) % 6 == 0; }
    glm::vec3 colour(const TexelAddress& t) {
        const bool dark = (t.row / 2 + t.column / 2 + t.face) % 2 == 0;
        return glm::vec3(dark ? 0.25f : 0.75f, 0.5f, 0.15f * u(rng));
    }
    template <class Store>
    void frame(int n, bool second, Store&& store) {
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column) {
                    const TexelAddress t{face, column, row};
                    // Frame 2 also stores into a third of the texels already visible: refused, on both sides.
                    if (skip(t) != second && !(second && (row + column) % 3 == 0)) continue;
                    store(t, colour(t), 0.5f + 0.1f * u(rng));
                    if ((row + 2 * column + face) % 4 == 0) store(t, colour(t), 0.5f + 0.1f * u(rng));
                }
    }
    std::mt19937 rng;
    std::uniform_real_distribution<float> u{0.0f, 1.0f};
};

// Rig with the pattern's first frame stored in every cube (threshold as given).
void store_pattern(Rig& rig, Pattern& pattern, bool second) {
    for (std::uint32_t k = 0; k < rig.cct.size(); ++k)
        pattern.frame(rig.cct[k]->face_size(), second,
                      [&](const TexelAddress& t, const glm::vec3& c, float) { rig.store_cct(k, t, c); });
    for (std::uint32_t k = 0; k < rig.cdct.size(); ++k)
        pattern.frame(rig.cdct[k]->face_size(), second,
                      [&](const TexelAddress& t, const glm::vec3& c, float d) { rig.store_cdct(k, t, c, d); });
}

// The elements whose doubtful bit is set, in a rig's CCT (cdct false) or CDCT buffer.
std::set<std::uint32_t> marked(const Rig& rig, bool cdct) {
    const GpuBufferLayout& layout = cdct ? rig.cdct_layout : rig.cct_layout;
    const std::uint32_t* words = (cdct ? rig.cdct_doubtful : rig.cct_doubtful).as<std::uint32_t>();
    std::set<std::uint32_t> out;
    for (std::uint32_t e = 0; e < layout.texels; ++e)
        if (gpu_doubtful(words, layout.doubtful_words, e)) out.insert(e);
    return out;
}

} // namespace

TEST_CASE("the GPU's mark pass marks what mark_doubtful_edges marks in C++, bit for bit, in CCT and CDCT cubes") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    // Cubes of different sizes in each buffer, so that the mark pass finds each texel's cube in the table.
    Rig rig(*vk, {8, 5, 6}, {6, 8}, false);
    Pattern pattern(7);
    store_pattern(rig, pattern, false);
    rig.run(0.1f);
    const std::size_t first = rig.check_same_marks();
    std::size_t valid = 0;
    for (auto& c : rig.cct) valid += c->valid_texels();
    for (auto& c : rig.cdct) valid += c->valid_texels();
    CHECK(first > valid / 10); // the pattern has edges ...
    CHECK(first < valid);      // ... and texels that match their neighbours
    // The second frame fills the gaps beside texels made visible (and marked) in the first.
    store_pattern(rig, pattern, true);
    rig.run(0.1f);
    CHECK(rig.check_same_marks() > first);
}

TEST_CASE("after a store-list overflow, the sweep and the confidence test over every element mark what C++ marks") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    Rig rig(*vk, {8, 5}, {6, 8}, false, 64); // a list of 64 entries: each frame stores hundreds of texels
    Pattern pattern(5);
    store_pattern(rig, pattern, false);
    rig.run(0.1f, true);
    CHECK(rig.overflow_last_frame > 0u);
    const std::size_t first = rig.check_same_marks();
    CHECK(first > 0u);
    // The second frame: the sweep compares the older texels again, at the same threshold: no other marks.
    store_pattern(rig, pattern, true);
    rig.run(0.1f, true);
    CHECK(rig.overflow_last_frame > 0u);
    CHECK(rig.check_same_marks() > first);
}

TEST_CASE("hand-derived marks on a 2 x 2 face: more than the threshold, never across a face's edge, and the CCT alone "
          "needs no 64-bit feature") {
    if (!rcx_test::context()) return; // no Vulkan device: skipped
    for (const char* name : {"confidence_queries_cct", "confidence_end_frame"}) {
        CAPTURE(name);
        const std::set<std::uint32_t> caps = rcx_test::capabilities_of(rcx_test::spirv(name));
        CHECK(caps.count(rcx_test::capability_int64) == 0);
        CHECK(caps.count(rcx_test::capability_int64_atomics) == 0);
    }
    rcx::vk::ContextOptions options;
    options.enable_int64 = false;
    rcx::vk::Context cct_vk(options);
    REQUIRE_MESSAGE(cct_vk.validation_enabled(), "this test needs VK_LAYER_KHRONOS_validation to mean anything");
    const std::uint64_t errors_before = cct_vk.validation_errors();

    // Face 0 (elements 0..3 = (column, row) (0,0), (1,0), (0,1), (1,1)): red 0, 0.5, 0.25, 0.25; face 1's
    // first texel (element 4, right after element 3 in the buffer but on another face) white x 2.
    // Pairs on a face: 0-1 differ by 0.5, 0-2 and 1-3 by 0.25, 2-3 by 0. Thresholds and what they mark:
    struct Case {
        float threshold;
        std::set<std::uint32_t> expected;
    };
    const Case cases[] = {{0.25f, {0, 1}}, {0.24f, {0, 1, 2, 3}}, {0.5f, {}}, {0.0f, {0, 1, 2, 3}}};
    const TexelAddress texels[] = {{0, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 1, 1}, {1, 0, 0}};
    const glm::vec3 colours[] = {glm::vec3(0.0f), glm::vec3(0.5f, 0.0f, 0.0f), glm::vec3(0.25f, 0.0f, 0.0f),
                                 glm::vec3(0.25f, 0.0f, 0.0f), glm::vec3(2.0f)};
    for (const bool cdct : {false, true}) {
        for (const Case& c : cases) {
            CAPTURE(cdct);
            CAPTURE(c.threshold);
            Rig rig(cdct ? *rcx_test::context() : cct_vk, cdct ? std::vector<int>{} : std::vector<int>{2},
                    cdct ? std::vector<int>{2} : std::vector<int>{}, !cdct);
            for (int i = 0; i < 5; ++i) {
                if (cdct) rig.store_cdct(0, texels[i], colours[i], 1.0f);
                else rig.store_cct(0, texels[i], colours[i]);
            }
            rig.run(c.threshold);
            CHECK(rig.listed_last_frame == 5u);
            CHECK(marked(rig, cdct) == c.expected);
            CHECK(marked(rig, !cdct).empty());
            rig.check_same_marks(); // and C++ agrees
        }
    }
    CHECK(cct_vk.validation_errors() == errors_before);
}

TEST_CASE("GPU lookups and CDCT searches miss on doubtful texels, as C++'s do, and stores into them are refused") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    Rig rig(*vk, {8, 5}, {6, 8}, false);
    // The same stores into C++ cubes with the test off: what the searches answer without marks.
    Rig unmarked_stores(*vk, {}, {6, 8}, false);
    Pattern pattern(11), same(11);
    store_pattern(rig, pattern, false);
    for (std::uint32_t k = 0; k < 2; ++k)
        same.frame(unmarked_stores.cdct[k]->face_size(), false, [&](const TexelAddress& t, const glm::vec3& c, float d) {
            unmarked_stores.cdct[k]->store(texel_direction(t, unmarked_stores.cdct[k]->face_size()), DepthSample{c, d});
        });
    rig.run(0.1f);
    for (auto& cube : unmarked_stores.cdct) cube->begin_frame();
    REQUIRE(rig.check_same_marks() > 0);

    // Lookups of every CCT texel; secant searches and relief walks from each CDCT cube's centre through
    // every texel; and a store into every CCT texel (refused wherever a value is visible, doubtful or not).
    struct Expect {
        bool hit;
        glm::vec3 colour;
        bool doubtful;
        bool hit_unmarked;
    };
    std::vector<Expect> expected;
    const ReliefParameters p{};
    for (std::uint32_t k = 0; k < rig.cct.size(); ++k) {
        CctCube& cube = *rig.cct[k];
        const int n = cube.face_size();
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column) {
                    const TexelAddress t{face, column, row};
                    const glm::vec3 d = texel_direction(t, n);
                    const std::optional<glm::vec3> c = cube.peek(d);
                    rig.queries.push_back(Query{d, 1u, glm::vec3(0.0f), 0.0f, glm::vec3(0.0f), k});
                    expected.push_back({c.has_value(), c.value_or(glm::vec3(0.0f)), cube.is_doubtful(t), cube.load(t).has_value()});
                }
    }
    const std::size_t lookups = expected.size();
    for (std::uint32_t k = 0; k < rig.cdct.size(); ++k) {
        CdctCube& cube = *rig.cdct[k];
        const CubeBounds b{rig.cdct_layout.cubes[k].centre, rig.cdct_layout.cubes[k].half_size};
        const int n = cube.face_size();
        for (std::uint32_t mode : {3u, 4u})
            for (int face = 0; face < 6; ++face)
                for (int row = 0; row < n; ++row)
                    for (int column = 0; column < n; ++column) {
                        const TexelAddress t{face, column, row};
                        const glm::vec3 d = texel_direction(t, n);
                        const ReliefResult r = mode == 3u ? secant_search(cube, b, b.centre, d, p) : relief_search(cube, b, b.centre, d, p);
                        const ReliefResult u = mode == 3u ? secant_search(*unmarked_stores.cdct[k], b, b.centre, d, p)
                                                          : relief_search(*unmarked_stores.cdct[k], b, b.centre, d, p);
                        rig.queries.push_back(Query{d, mode, glm::vec3(0.0f), 0.0f, b.centre, k});
                        expected.push_back({r.hit, r.color, cube.is_doubtful(t), u.hit});
                    }
    }
    const std::size_t before_stores = expected.size();
    std::vector<bool> store_refused;
    for (std::uint32_t k = 0; k < rig.cct.size(); ++k) {
        const int n = rig.cct[k]->face_size();
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column) {
                    const TexelAddress t{face, column, row};
                    store_refused.push_back(rig.cct[k]->load(t).has_value());
                    rig.store_cct(k, t, glm::vec3(1.0f, 0.0f, 0.0f));
                }
    }
    const std::vector<glm::uvec4> results = rig.run(0.1f);
    REQUIRE(results.size() == before_stores + store_refused.size());

    std::size_t missed_doubtful_lookups = 0, missed_doubtful_searches = 0, refused_doubtful = 0;
    for (std::size_t i = 0; i < before_stores; ++i) {
        CAPTURE(i);
        const Expect& e = expected[i];
        CHECK((results[i].x != 0u) == e.hit);
        if (e.hit) {
            glm::vec3 gpu;
            std::memcpy(&gpu, &results[i].y, sizeof gpu);
            CHECK(gpu == e.colour);
        }
        if (e.doubtful && e.hit_unmarked && results[i].x == 0u) ++(i < lookups ? missed_doubtful_lookups : missed_doubtful_searches);
    }
    for (std::size_t i = 0; i < store_refused.size(); ++i) {
        CAPTURE(i);
        CHECK((results[before_stores + i].x == 0u) == store_refused[i]);
        refused_doubtful += store_refused[i] && results[before_stores + i].x == 0u;
    }
    CHECK(missed_doubtful_lookups > 0);
    CHECK(missed_doubtful_searches > 0);
    CHECK(refused_doubtful > 0);
    rig.check_same_marks(); // the refused stores changed nothing; the new ones were compared
}

TEST_CASE("a threshold below 0 or NaN marks nothing on the GPU, and every stored texel answers") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    for (const float threshold : {-1.0f, -0.0001f, std::numeric_limits<float>::quiet_NaN()}) {
        CAPTURE(threshold);
        Rig rig(*vk, {6}, {6}, false);
        Pattern pattern(3);
        store_pattern(rig, pattern, false);
        rig.run(threshold);
        CHECK(rig.gpu_marks() == 0u);
        CHECK(rig.check_same_marks() == 0u);
        // Lookups of every CCT texel hit exactly where one was stored.
        std::vector<bool> stored;
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < 6; ++row)
                for (int column = 0; column < 6; ++column) {
                    const TexelAddress t{face, column, row};
                    stored.push_back(rig.cct[0]->load(t).has_value());
                    rig.queries.push_back(Query{texel_direction(t, 6), 1u, glm::vec3(0.0f), 0.0f, glm::vec3(0.0f), 0u});
                }
        const std::vector<glm::uvec4> results = rig.run(threshold);
        for (std::size_t i = 0; i < stored.size(); ++i) CHECK((results[i].x != 0u) == stored[i]);
    }
}
