// The face table three ways on a Vulkan device: RayCache's GLSL include (raycache_texel_of and
// raycache_cube_texel, in shaders/face_map.comp), the C++ raycache::texel_of, and the device's own cube
// sampler (usamplerCube, NEAREST, CLAMP_TO_EDGE, an R32_UINT cube whose texels hold their own index).
// Directions: random ones of every size, every kind of tie between magnitudes, signed zeros, directions
// on texel edges (t = k/N as exactly as floats allow) and their float neighbours, and the limits of
// what counts as a direction. All three must agree on every one.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <raycache/cube_face.hpp>

#include "test_directions.hpp"
#include "vulkan_test.hpp"

namespace {

using rcx_test::Direction;

// True when a direction's position on its face, (c / |m| + 1) / 2 * N in texels along either face axis,
// lies within eps texels of a texel edge (the face's own edges, where two majors nearly tie, included),
// worked out in double precision.
bool near_texel_edge(glm::vec3 v, int n, double eps) {
    const double a[3] = {std::abs(static_cast<double>(v.x)), std::abs(static_cast<double>(v.y)), std::abs(static_cast<double>(v.z))};
    const int major = a[2] >= a[1] && a[2] >= a[0] ? 2 : (a[1] >= a[0] ? 1 : 0);
    for (int k = 0; k < 3; ++k) {
        if (k == major) continue;
        const double u = (a[k] / a[major] + 1.0) / 2.0 * n; // the sign of c mirrors u about n / 2: same distance
        if (std::abs(u - std::round(u)) < eps) return true;
    }
    return false;
}

void check_face_size(rcx::vk::Context& vk, rcx::vk::ComputePipeline& pipeline, int n) {
    const std::vector<Direction> directions = rcx_test::directions_for(n, 1234u + static_cast<std::uint32_t>(n));
    const std::size_t count = directions.size();

    std::vector<float> xyz;
    xyz.reserve(3 * count);
    for (const Direction& d : directions) xyz.insert(xyz.end(), {d.v.x, d.v.y, d.v.z});
    rcx::vk::Buffer input(vk, xyz.size() * sizeof(float));
    input.upload(xyz.data(), xyz.size() * sizeof(float));
    rcx::vk::Buffer texels(vk, count * 4 * sizeof(std::int32_t));
    rcx::vk::Buffer linear(vk, count * 2 * sizeof(std::uint32_t));

    // The cube image: each texel holds its own linear index (face * N + row) * N + column.
    rcx::vk::SampledCubeImage image(vk, static_cast<std::uint32_t>(n));
    {
        std::vector<std::uint32_t> addresses(std::size_t{6} * n * n);
        std::iota(addresses.begin(), addresses.end(), 0u);
        image.upload(addresses.data(), addresses.size() * sizeof(std::uint32_t));
    }

    struct {
        std::int32_t face_size;
        std::uint32_t count;
    } push{n, static_cast<std::uint32_t>(count)};
    vk.dispatch(pipeline, {input, texels, linear, image}, &push, sizeof(push), rcx::vk::group_count(count, 64));

    const std::int32_t* glsl = texels.as<std::int32_t>();
    const std::uint32_t* index = linear.as<std::uint32_t>();
    std::size_t include_agrees = 0, cube_texel_agrees = 0, sampler_agrees = 0, sampled = 0, reported = 0, excused = 0;
    const int fraction_bits = rcx_test::sampler_fraction_bits(vk);
    for (std::size_t i = 0; i < count; ++i) {
        const glm::vec3 v = directions[i].v;
        const std::optional<raycache::TexelAddress> cpu = raycache::texel_of(v, n);
        const raycache::TexelAddress gpu{glsl[4 * i], glsl[4 * i + 1], glsl[4 * i + 2]};
        const bool include_ok = cpu ? gpu == *cpu : gpu.face == RAYCACHE_NO_FACE;
        const std::uint32_t expected_index =
            cpu ? static_cast<std::uint32_t>(raycache::texel_linear_index(*cpu, n)) : 0xFFFFFFFFu;
        const bool cube_texel_ok = index[2 * i] == expected_index;
        bool sampler_ok = true;
        if (raycache::is_direction(v)) {
            ++sampled;
            sampler_ok = index[2 * i + 1] == expected_index;
            // A fixed-point sampler may pick the neighbour of a direction this close to a texel edge.
            if (!sampler_ok && fraction_bits > 0 && near_texel_edge(v, n, std::ldexp(1.0, -fraction_bits))) {
                sampler_ok = true;
                ++excused;
            }
            sampler_agrees += sampler_ok;
        }
        include_agrees += include_ok;
        cube_texel_agrees += cube_texel_ok;
        if ((!include_ok || !cube_texel_ok || !sampler_ok) && reported++ < 12) {
            std::printf("  N=%d %s (%a, %a, %a): C++ %d %d %d (%u), GLSL %d %d %d (%u), sampler %u\n", n,
                        directions[i].kind, v.x, v.y, v.z, cpu ? cpu->face : -1, cpu ? cpu->column : 0,
                        cpu ? cpu->row : 0, expected_index, gpu.face, gpu.column, gpu.row, index[2 * i],
                        index[2 * i + 1]);
        }
    }
    std::printf("face size %4d: %zu directions: GLSL raycache_texel_of = C++ texel_of for %zu, "
                "raycache_cube_texel = C++ for %zu; %s sampler = C++ for %zu of %zu directions "
                "(the other %zu are not directions)",
                n, count, include_agrees, cube_texel_agrees, vk.device_name().c_str(), sampler_agrees, sampled,
                count - sampled);
    if (fraction_bits > 0)
        std::printf("; its fixed-point coordinates picked a neighbour for %zu of them, all within 2^-%d texel of an edge",
                    excused, fraction_bits);
    std::printf("\n");
    std::fflush(stdout);
    CHECK(count >= 100000);
    CHECK(include_agrees == count);
    CHECK(cube_texel_agrees == count);
    CHECK(sampler_agrees == sampled);
}

void check_face_sizes(std::initializer_list<int> sizes) {
    rcx_test::for_face_sizes("face_map",
                             {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                              VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
                             sizes, check_face_size);
}

} // namespace

TEST_CASE("GLSL, C++ and the device's cube sampler pick the same texel at face sizes 1, 2, 3 and 16") {
    check_face_sizes({1, 2, 3, 16});
}

TEST_CASE("GLSL, C++ and the device's cube sampler pick the same texel at face sizes 255 and 512") {
    check_face_sizes({255, 512});
}

TEST_CASE("GLSL, C++ and the device's cube sampler pick the same texel at face size 4096") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    // 6 * 4096^2 texels of 4 bytes: a 384 MiB image, as much again to upload it.
    if (vk->properties().limits.maxImageDimensionCube < 4096) {
        MESSAGE("face size 4096 skipped: maxImageDimensionCube is " << vk->properties().limits.maxImageDimensionCube);
        return;
    }
    try {
        check_face_sizes({4096});
    } catch (const rcx::vk::Error& e) {
        if (std::string(e.what()).find("OUT_OF_") == std::string::npos) throw;
        MESSAGE("face size 4096 skipped, not enough memory: " << e.what());
    }
}
