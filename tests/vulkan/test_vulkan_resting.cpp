// Resting cubes in GLSL (raycache_cube_rests in raycache/cube.glsl, driven by shaders/resting_queries.comp)
// against C++: a cube the frame started resting lets through exactly the directions C++'s
// raycache_is_probe_direction_of does not probe at the bits of its resting word (1, read as 4, and 7), over the cross-checks' adversarial directions (ties, signed
// zeros, texel edges, every magnitude, and vectors that are not directions), and counts them in its
// `rested` counter; a working cube, and a resting cube without texels, let nothing through; no lookup is
// counted.
#include <doctest/doctest.h>

#include <cstdint>
#include <vector>

#include <raycache/resting.hpp>

#include "test_directions.hpp"
#include "vulkan_test.hpp"

namespace gpu = raycache::shared;

namespace {

// shaders/resting_queries.comp's Query and its std430 layout.
struct Query {
    glm::vec3 direction;
    std::uint32_t cube;
};
static_assert(sizeof(Query) == 16, "Query must match the std430 layout in resting_queries.comp");

} // namespace

TEST_CASE("a resting cube lets through, in GLSL, exactly the directions C++ does not probe, and counts them") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    rcx::vk::ComputePipeline pipeline(*vk, rcx_test::spirv("resting_queries"), std::vector<VkDescriptorType>(4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER), 4);
    // Cube 0 rests (resting word 1: a first rest's probes, one direction in 16), cube 1 works, cube 2 rests
    // but has no texels (face size 0), cube 3 rests probing one direction in 2^7.
    std::vector<gpu::raycache_gpu_cube> descriptors = {gpu::raycache_make_gpu_cube(glm::vec3(0.0f), 1.0f, 0u, 16),
                                                       gpu::raycache_make_gpu_cube(glm::vec3(0.0f), 1.0f, 1536u, 16),
                                                       gpu::raycache_make_gpu_cube(glm::vec3(0.0f), 1.0f, 3072u, 0),
                                                       gpu::raycache_make_gpu_cube(glm::vec3(0.0f), 1.0f, 3072u, 16)};
    for (std::uint32_t k = 0; k < 4; ++k) descriptors[k].index = k;
    std::vector<Query> queries;
    for (const rcx_test::Direction& d : rcx_test::directions_for(16, 5))
        for (std::uint32_t k = 0; k < 4; ++k) queries.push_back({d.v, k});
    rcx::vk::Buffer cubes = rcx_test::buffer_of(*vk, descriptors);
    rcx::vk::Buffer query_buffer = rcx_test::buffer_of(*vk, queries);
    rcx::vk::Buffer results(*vk, queries.size() * 4);
    rcx_test::Frame frame(*vk, 4, 16);
    frame.start(true, {1u, 0u, 4u, 7u});
    const std::uint32_t count = static_cast<std::uint32_t>(queries.size());
    vk->dispatch(pipeline, {cubes, query_buffer, frame.buffer, results}, &count, 4, rcx::vk::group_count(count, 64));

    const std::uint32_t* r = results.as<std::uint32_t>();
    std::size_t same = 0, let_through = 0, let_through_sparse = 0;
    for (std::size_t i = 0; i < queries.size(); ++i) {
        const glm::vec3 d = queries[i].direction;
        const bool expected = (queries[i].cube == 0 && !raycache::is_probe_direction(d)) ||
                              (queries[i].cube == 3 && !raycache::shared::raycache_is_probe_direction_of(d, 7u));
        same += (r[i] != 0u) == expected;
        let_through += expected && queries[i].cube == 0;
        let_through_sparse += expected && queries[i].cube == 3;
        // Probes at 7 bits are among those at 4: what a first rest lets through, a thinned one does too.
        if (queries[i].cube == 0 && (r[i] != 0u)) CHECK(r[i + 3] != 0u);
        if ((r[i] != 0u) != expected && same + 20 > i) // the first few differences, for the failure message
            MESSAGE("cube " << queries[i].cube << " direction (" << queries[i].direction.x << ", " << queries[i].direction.y << ", "
                            << queries[i].direction.z << "): GLSL " << r[i] << ", C++ " << expected);
    }
    CHECK(same == queries.size());
    const double share = static_cast<double>(let_through) / static_cast<double>(queries.size() / 4);
    CHECK(share > 0.85); // about 15 in 16 of the directions are not probes
    CHECK(share < 1.0);
    CHECK(let_through_sparse > let_through); // the probes at 7 bits are among those at 4
    CHECK(let_through_sparse < queries.size() / 4);
    const raycache::GpuFrameStatistics s = frame.statistics();
    CHECK(s.resting == std::vector<bool>{true, false, true, true});
    CHECK(s.cubes[0].misses_by[static_cast<std::size_t>(raycache::MissReason::resting)] == let_through);
    CHECK(s.cubes[3].misses_by[static_cast<std::size_t>(raycache::MissReason::resting)] == let_through_sparse);
    CHECK(s.cubes[0].looked_up() == 0u);
    CHECK(s.cubes[1].lookups == 0u);
    CHECK(s.cubes[2].lookups == 0u);
}
