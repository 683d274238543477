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

#include "vulkan_test.hpp"

namespace {

struct Direction {
    glm::vec3 v;
    const char* kind;
};

float next_up(float x, int steps) {
    for (int i = 0; i < steps; ++i) x = std::nextafter(x, std::numeric_limits<float>::infinity());
    for (int i = 0; i > steps; --i) x = std::nextafter(x, -std::numeric_limits<float>::infinity());
    return x;
}

// The direction with magnitude m along face f's major axis and face coordinates (sc, tc) (the face
// table read backwards).
glm::vec3 on_face(int f, float m, float sc, float tc) {
    switch (f) {
    case 0: return {m, -tc, -sc};
    case 1: return {-m, -tc, sc};
    case 2: return {sc, m, tc};
    case 3: return {sc, -m, -tc};
    case 4: return {sc, -tc, m};
    default: return {-sc, -tc, -m};
    }
}

std::vector<Direction> directions_for(int n, std::uint32_t seed) {
    std::vector<Direction> out;
    std::mt19937 rng(seed);
    std::normal_distribution<float> gauss;
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::uniform_int_distribution<int> exponent(-40, 40);

    // Random directions, of every size between 2^-40 and 2^40, some close to an axis.
    for (int i = 0; i < 100000; ++i) {
        glm::vec3 v(gauss(rng), gauss(rng), gauss(rng));
        if (i % 4 == 1) v[i % 3] *= 64.0f;
        v *= std::ldexp(1.0f, exponent(rng));
        out.push_back({v, "random"});
    }

    // Ties: |x| = |y| = |z|, and each pair equal with the third smaller or zero, in every sign.
    for (int i = 0; i < 150; ++i) {
        const float a = i < 5 ? std::ldexp(1.0f, i - 2) : std::ldexp(0.5f + unit(rng), exponent(rng));
        const float small[] = {a * unit(rng), 0.0f, -0.0f};
        for (int signs = 0; signs < 8; ++signs) {
            const float sx = signs & 1 ? -1.0f : 1.0f, sy = signs & 2 ? -1.0f : 1.0f, sz = signs & 4 ? -1.0f : 1.0f;
            out.push_back({{sx * a, sy * a, sz * a}, "tie xyz"});
            for (float b : small) {
                out.push_back({{sx * a, sy * a, sz * b}, "tie xy"});
                out.push_back({{sx * a, sy * b, sz * a}, "tie xz"});
                out.push_back({{sx * b, sy * a, sz * a}, "tie yz"});
            }
        }
    }

    // Signed zeros in the minor components, alone and with a non-zero third component.
    for (int i = 0; i < 200; ++i) {
        const float a = std::ldexp(0.5f + unit(rng), exponent(rng));
        const float c = a * (2.0f * unit(rng) - 1.0f);
        for (int axis = 0; axis < 3; ++axis)
            for (int signs = 0; signs < 8; ++signs) {
                glm::vec3 v(signs & 2 ? -0.0f : 0.0f, signs & 4 ? -0.0f : 0.0f, 0.0f);
                glm::vec3 w(v.x, c, 0.0f);
                const float major = signs & 1 ? -a : a;
                v = glm::vec3(v.x, v.y, major);
                w = glm::vec3(w.x, w.y, major);
                // rotate the components so the major one is `axis`
                for (int r = 0; r < axis + 1; ++r) {
                    v = glm::vec3(v.z, v.x, v.y);
                    w = glm::vec3(w.z, w.x, w.y);
                }
                out.push_back({v, "signed zeros"});
                out.push_back({w, "signed zero + minor"});
            }
    }

    // Texel edges: sc = (2k/N - 1) m, so that t = sc * (0.5/m) + 0.5 is k/N as nearly as floats allow,
    // and its neighbours 1 and 2 floats away, on every face, along columns and rows, for several m.
    std::vector<int> ks;
    if (n <= 64) {
        for (int k = 0; k <= n; ++k) ks.push_back(k);
    } else {
        std::uniform_int_distribution<int> any_k(0, n);
        ks = {0, 1, n / 2, n - 1, n};
        while (ks.size() < 180) ks.push_back(any_k(rng));
    }
    for (int f = 0; f < 6; ++f)
        for (int k : ks)
            for (int mi = 0; mi < 4; ++mi) {
                const float m = mi == 0 ? 1.0f : mi == 1 ? 0.75f : mi == 2 ? 0.3f + 3.0f * unit(rng)
                                                                           : std::ldexp(0.5f + unit(rng), exponent(rng));
                const float edge = static_cast<float>((2.0 * k / n - 1.0) * m);
                for (int step = -2; step <= 2; ++step) {
                    const float sc = next_up(edge, step);
                    const float other = m * (2.0f * unit(rng) - 1.0f) * 0.999f;
                    out.push_back({on_face(f, m, sc, other), "texel edge (column)"});
                    out.push_back({on_face(f, m, other, sc), "texel edge (row)"});
                }
            }

    // The limits of a direction: major magnitude 2^-126 and 2^125 (directions) and one float beyond
    // (not directions); zero, infinite and NaN vectors (not directions).
    const float lowest = std::ldexp(1.0f, -126), highest = std::ldexp(1.0f, 125);
    for (int i = 0; i < 100; ++i) {
        const float u = 2.0f * unit(rng) - 1.0f, w = 2.0f * unit(rng) - 1.0f;
        for (float m : {lowest, next_up(lowest, 1), next_up(lowest, -1), highest, next_up(highest, -1), next_up(highest, 1)})
            for (int f = 0; f < 6; ++f) out.push_back({on_face(f, m, u * m, w * m), "limits"});
    }
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    for (glm::vec3 v : {glm::vec3(0.0f), glm::vec3(-0.0f), glm::vec3(inf, 0, 0), glm::vec3(1, -inf, 0),
                        glm::vec3(nan, 1, 1), glm::vec3(1, 1, nan), glm::vec3(inf, inf, inf), glm::vec3(1e-40f, 0, 0)})
        out.push_back({v, "not a direction"});
    return out;
}

void check_face_size(rcx::vk::Context& vk, rcx::vk::ComputePipeline& pipeline, int n) {
    const std::vector<Direction> directions = directions_for(n, 1234u + static_cast<std::uint32_t>(n));
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
    std::size_t include_agrees = 0, cube_texel_agrees = 0, sampler_agrees = 0, sampled = 0, reported = 0;
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
                "(the other %zu are not directions)\n",
                n, count, include_agrees, cube_texel_agrees, vk.device_name().c_str(), sampler_agrees, sampled,
                count - sampled);
    std::fflush(stdout);
    CHECK(count >= 100000);
    CHECK(include_agrees == count);
    CHECK(cube_texel_agrees == count);
    CHECK(sampler_agrees == sampled);
}

void check_face_sizes(std::initializer_list<int> sizes) {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    rcx::vk::ComputePipeline pipeline(*vk, rcx_test::spirv("face_map"),
                                      {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                       VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
                                      8);
    for (int n : sizes) {
        CAPTURE(n);
        check_face_size(*vk, pipeline, n);
    }
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
