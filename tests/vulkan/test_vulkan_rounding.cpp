// raycache/shared/rounding.h as the device's shader compiler builds it (shaders/rounding_cross.comp) against
// the CPU's IEEE division and square root: the refinement from starts up to 3 ulps off, the same cases as
// the C++ test (rounding_cases.hpp), must give the correctly rounded result bit for bit, and so must
// raycache_divide and raycache_sqrt from the device's own operators. On lavapipe those operators are exact
// already, so this checks that the compiler keeps the refinement's exact arithmetic (no contraction, no
// reassociation, products and sums rounded as written); on a GPU whose division is looser it checks the
// correction itself.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <ios>
#include <random>
#include <vector>

#include "../rounding_cases.hpp"
#include "vulkan_test.hpp"

namespace {

// shaders/rounding_cross.comp's Query and its std430 layout.
struct Query {
    glm::vec4 operands;
    std::uint32_t kind;
    std::uint32_t pad[3];
};
static_assert(sizeof(Query) == 32, "Query must match the std430 layout in rounding_cross.comp");

std::uint32_t bits(float f) {
    std::uint32_t u = 0;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

} // namespace

TEST_CASE("GLSL's refined division and square root round to nearest from starts up to 3 ulps off, as IEEE does") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    std::mt19937 rng(28112026);
    std::vector<Query> queries;
    std::vector<float> expected;
    std::vector<rounding_cases::Division> divisions = rounding_cases::random_divisions(rng, 20000);
    for (const auto& more : {rounding_cases::near_midpoint_divisions(rng, 10000), rounding_cases::exact_divisions(rng, 5000)})
        divisions.insert(divisions.end(), more.begin(), more.end());
    for (const rounding_cases::Division& d : divisions) {
        const float q = d.first / d.second;
        for (int kq = -3; kq <= 3; ++kq)
            for (int ky = -2; ky <= 2; ky += 2) {
                queries.push_back({glm::vec4(d.first, d.second, rounding_cases::moved(q, kq), rounding_cases::moved(1.0f / d.second, ky)), 0u, {}});
                expected.push_back(q);
            }
    }
    const std::size_t division_queries = queries.size();
    std::vector<float> roots = rounding_cases::random_roots(rng, 20000);
    for (const auto& more : {rounding_cases::near_midpoint_roots(rng, 10000), rounding_cases::exact_roots(rng, 5000)})
        roots.insert(roots.end(), more.begin(), more.end());
    for (float x : roots) {
        const float s = std::sqrt(x);
        for (int ks = -3; ks <= 3; ++ks)
            for (int kh = -2; kh <= 2; kh += 2) {
                queries.push_back({glm::vec4(x, rounding_cases::moved(s, ks), rounding_cases::moved(0.5f / s, kh), 0.0f), 1u, {}});
                expected.push_back(s);
            }
    }

    rcx::vk::ComputePipeline pipeline(*vk, rcx_test::spirv("rounding_cross"),
                                      std::vector<VkDescriptorType>(2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER), 4);
    rcx::vk::Buffer query_buffer = rcx_test::buffer_of(*vk, queries);
    rcx::vk::Buffer results(*vk, queries.size() * 8);
    const std::uint32_t count = static_cast<std::uint32_t>(queries.size());
    vk->dispatch(pipeline, {query_buffer, results}, &count, 4, rcx::vk::group_count(count, 64));

    const std::uint32_t* r = results.as<std::uint32_t>();
    std::size_t refined_wrong[2] = {0, 0}, own_wrong[2] = {0, 0}, reported = 0;
    for (std::size_t i = 0; i < queries.size(); ++i) {
        const int kind = static_cast<int>(queries[i].kind);
        const bool refined_ok = r[2 * i] == bits(expected[i]), own_ok = r[2 * i + 1] == bits(expected[i]);
        refined_wrong[kind] += !refined_ok;
        own_wrong[kind] += !own_ok;
        if ((!refined_ok || !own_ok) && reported++ < 10)
            MESSAGE((kind == 0 ? "divide " : "sqrt ") << std::hexfloat << queries[i].operands.x << ", " << queries[i].operands.y
                                                      << " from " << queries[i].operands.z << ": refined " << r[2 * i]
                                                      << ", own " << r[2 * i + 1] << ", expected " << bits(expected[i]));
    }
    MESSAGE(vk->device_name() << ": " << division_queries << " divisions and " << queries.size() - division_queries
                              << " square roots; refined wrong " << refined_wrong[0] << " and " << refined_wrong[1]
                              << ", raycache_divide / raycache_sqrt wrong " << own_wrong[0] << " and " << own_wrong[1]);
    CHECK(division_queries > 20 * 35000);
    CHECK(refined_wrong[0] == 0);
    CHECK(refined_wrong[1] == 0);
    CHECK(own_wrong[0] == 0);
    CHECK(own_wrong[1] == 0);
}
