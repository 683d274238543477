// Filtered (bilinear) lookups three ways on a Vulkan device: RayCache's GLSL footprint and filtered value
// (raycache_filter_taps_of, raycache_filtered_value over a fetch from a buffer, in shaders/filter_cross.comp),
// the C++ raycache::filter_footprint and raycache::filtered_value over the same texels, and the device's own
// seamless LINEAR samplerCube over an R32_SFLOAT cube holding the texels' red channel.
//
// GLSL and C++ must agree bit for bit: taps, weights and filtered colours, with every texel present and
// with a third of them empty. The sampler is the independent oracle for the footprint (which texels
// across edges, the corner rule, the weights): it must agree within 2^-20 (9.5e-7). Why that much: the
// texels are float32 values in [0, 1], so format precision adds nothing; the sampler computes the
// position u = t * N - 0.5 as the library does (Mesa's order, which the face test pins down), so the
// weights agree, but it blends with lerps (a + w (b - a), twice, plus the corner share) where the library
// takes a weighted sum, a different order of about 8 roundings of at most 2^-24 each: 2^-21, doubled
// for margin. (A driver that rounded the position differently would move weights by up to 2^-24 N
// and need a tolerance growing with N.) A GPU's sampler rounds the position to a few fractional bits of a
// texel (subTexelPrecisionBits, 8 on NVIDIA's): there the tolerance is 2^-bits. A wrong tap or corner rule errs by the difference between random
// texels, about 0.3 on average; dropping the corner tap and renormalising instead errs by up to 0.02.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <raycache/filtered_lookup.hpp>

#include "test_directions.hpp"
#include "vulkan_test.hpp"

namespace {

using rcx_test::Direction;
using rcx_test::next_up;
using rcx_test::on_face;

// The face test's directions, plus where filtering changes its taps: texel centres (t * N = k + 1/2, where
// a weight becomes 0 and its tap drops out) and their float neighbours, the faces' edges (t = 0 or 1,
// half a texel past the last centre, taps across the edge) and their neighbours, cube corners exactly and
// nudged, and directions anywhere in the corner half-texels (the three-tap footprints).
std::vector<Direction> filter_directions(int n, std::uint32_t seed) {
    std::vector<Direction> out = rcx_test::directions_for(n, seed);
    std::mt19937 rng(seed + 1);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::uniform_int_distribution<int> any_k(0, n - 1);
    std::vector<int> ks;
    for (int k = 0; k < std::min(n, 48); ++k) ks.push_back(n <= 48 ? k : any_k(rng));
    for (int f = 0; f < 6; ++f)
        for (int k : ks)
            for (float m : {1.0f, 0.3f + 3.0f * unit(rng)}) {
                const float centre = static_cast<float>((2.0 * k + 1.0) / n - 1.0) * m;
                for (int step = -2; step <= 2; ++step) {
                    const float sc = next_up(centre, step);
                    const float other = m * (2.0f * unit(rng) - 1.0f);
                    out.push_back({on_face(f, m, sc, other), "texel centre (column)"});
                    out.push_back({on_face(f, m, other, sc), "texel centre (row)"});
                }
            }
    for (int f = 0; f < 6; ++f)
        for (int i = 0; i < 40; ++i) {
            const float m = i < 10 ? 1.0f : 0.25f + 4.0f * unit(rng);
            const float other = m * (2.0f * unit(rng) - 1.0f);
            for (float edge : {m, -m})
                for (int step = -3; step <= 0; ++step) {
                    const float sc = edge > 0 ? next_up(edge, step) : next_up(edge, -step);
                    out.push_back({on_face(f, m, sc, other), "face edge"});
                    out.push_back({on_face(f, m, other, sc), "face edge"});
                    for (float edge2 : {m, -m}) {
                        const float tc = edge2 > 0 ? next_up(edge2, step - i % 3) : next_up(edge2, i % 3 - step);
                        out.push_back({on_face(f, m, sc, tc), "cube corner"});
                    }
                }
            // Anywhere within half a texel of a corner, in both coordinates.
            for (int corner = 0; corner < 4; ++corner) {
                const float sc = (corner & 1 ? -m : m) * (1.0f - unit(rng) / n);
                const float tc = (corner & 2 ? -m : m) * (1.0f - unit(rng) / n);
                out.push_back({on_face(f, m, sc, tc), "corner half-texel"});
            }
        }
    return out;
}

struct Totals {
    std::size_t taps_agree = 0, values_agree = 0, holes_agree = 0, sampled = 0, sampler_agrees = 0;
    std::size_t across_edges = 0, at_corners = 0; // footprints with taps on two faces, on three
    double worst_sampler = 0.0;
};

void check_face_size(rcx::vk::Context& vk, rcx::vk::ComputePipeline& pipeline, int n) {
    if (!rcx::vk::SampledCubeImage::supports_linear_filter(vk, VK_FORMAT_R32_SFLOAT)) {
        MESSAGE("skipped: " << vk.device_name() << " cannot filter R32_SFLOAT linearly");
        return;
    }
    const std::vector<Direction> directions = filter_directions(n, 777u + static_cast<std::uint32_t>(n));
    const std::size_t count = directions.size();
    const std::size_t texel_count = std::size_t{6} * n * n;

    // Random texel colours; a second set with about a third of them empty.
    std::mt19937 rng(99u + static_cast<std::uint32_t>(n));
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<glm::vec4> full(texel_count), holes(texel_count);
    std::vector<float> red(texel_count);
    for (std::size_t i = 0; i < texel_count; ++i) {
        full[i] = glm::vec4(unit(rng), unit(rng), unit(rng), 1.0f);
        holes[i] = glm::vec4(glm::vec3(full[i]), unit(rng) < 1.0f / 3.0f ? 0.0f : 1.0f);
        red[i] = full[i].r;
    }

    std::vector<float> xyz;
    xyz.reserve(3 * count);
    for (const Direction& d : directions) xyz.insert(xyz.end(), {d.v.x, d.v.y, d.v.z});
    const rcx::vk::Buffer input = rcx_test::buffer_of(vk, xyz);
    const rcx::vk::Buffer full_buffer = rcx_test::buffer_of(vk, full), holes_buffer = rcx_test::buffer_of(vk, holes);
    rcx::vk::Buffer taps(vk, count * 5 * sizeof(glm::uvec4));
    rcx::vk::Buffer full_values(vk, count * 2 * sizeof(glm::vec4)), holes_values(vk, count * 2 * sizeof(glm::vec4));
    rcx::vk::SampledCubeImage image(vk, static_cast<std::uint32_t>(n), VK_FORMAT_R32_SFLOAT, VK_FILTER_LINEAR);
    image.upload(red.data(), red.size() * sizeof(float));

    struct {
        std::int32_t face_size;
        std::uint32_t count;
    } push{n, static_cast<std::uint32_t>(count)};
    vk.dispatch(pipeline, {input, full_buffer, taps, full_values, image}, &push, sizeof(push),
                rcx::vk::group_count(count, 64));
    vk.dispatch(pipeline, {input, holes_buffer, taps, holes_values, image}, &push, sizeof(push),
                rcx::vk::group_count(count, 64));

    auto fetch_from = [n](const std::vector<glm::vec4>& texels) {
        return [n, &texels](const raycache::TexelAddress& t) -> std::optional<glm::vec3> {
            const glm::vec4 c = texels[raycache::texel_linear_index(t, n)];
            if (!(c.a > 0.0f)) return std::nullopt;
            return glm::vec3(c);
        };
    };
    // The GLSL value (colour, hit) equals C++'s optional bit for bit (a miss: hit 0, colour 0).
    auto same_value = [](const glm::vec4& gpu, const std::optional<glm::vec3>& cpu) {
        if (!cpu) return gpu.w == 0.0f && glm::floatBitsToUint(glm::vec3(gpu)) == glm::uvec3(0u);
        return gpu.w == 1.0f && glm::floatBitsToUint(glm::vec3(gpu)) == glm::floatBitsToUint(*cpu);
    };

    // A fixed-point sampler (rcx_test::sampler_fraction_bits) rounds each weight to within 2^-(bits+1),
    // which moves a blend of values in [0, 1] by up to 2^-bits.
    const int fraction_bits = rcx_test::sampler_fraction_bits(vk);
    const double tolerance = fraction_bits > 0 ? std::ldexp(1.0, -fraction_bits) + 0x1p-20 : 0x1p-20;
    const glm::uvec4* gpu_taps = taps.as<glm::uvec4>();
    const glm::vec4* gpu_full = full_values.as<glm::vec4>();
    const glm::vec4* gpu_holes = holes_values.as<glm::vec4>();
    Totals t;
    std::size_t reported = 0;
    for (std::size_t i = 0; i < count; ++i) {
        const glm::vec3 v = directions[i].v;
        const raycache::FilterFootprint cpu = raycache::filter_footprint(v, n);
        int faces = 0;
        for (int k = 0; k < cpu.count; ++k) {
            bool seen = false;
            for (int j = 0; j < k; ++j) seen = seen || cpu.taps[static_cast<std::size_t>(j)].texel.face == cpu.taps[static_cast<std::size_t>(k)].texel.face;
            faces += !seen;
        }
        t.across_edges += faces == 2;
        t.at_corners += faces == 3;
        bool taps_ok = gpu_taps[5 * i].x == static_cast<std::uint32_t>(cpu.count);
        for (int k = 0; taps_ok && k < cpu.count; ++k) {
            const raycache::FilterTap& c = cpu.taps[static_cast<std::size_t>(k)];
            taps_ok = gpu_taps[5 * i + 1 + k] == glm::uvec4(c.texel.face, c.texel.column, c.texel.row,
                                                             glm::floatBitsToUint(c.weight));
        }
        const std::optional<glm::vec3> cpu_full = raycache::filtered_value(v, n, fetch_from(full));
        const std::optional<glm::vec3> cpu_holes = raycache::filtered_value(v, n, fetch_from(holes));
        const bool full_ok = same_value(gpu_full[2 * i], cpu_full);
        const bool holes_ok = same_value(gpu_holes[2 * i], cpu_holes);
        bool sampler_ok = true;
        double difference = 0.0;
        if (raycache::is_direction(v)) {
            ++t.sampled;
            difference = std::abs(static_cast<double>(gpu_full[2 * i + 1].x) - gpu_full[2 * i].x);
            sampler_ok = gpu_full[2 * i].w == 1.0f && difference <= tolerance;
            t.sampler_agrees += sampler_ok;
            t.worst_sampler = std::max(t.worst_sampler, difference);
        }
        t.taps_agree += taps_ok;
        t.values_agree += full_ok;
        t.holes_agree += holes_ok;
        if ((!taps_ok || !full_ok || !holes_ok || !sampler_ok) && reported++ < 12) {
            std::printf("  N=%d %s (%a, %a, %a): taps %s, value %s, with holes %s; GLSL red %.9g, sampler %.9g\n", n,
                        directions[i].kind, v.x, v.y, v.z, taps_ok ? "agree" : "DIFFER", full_ok ? "agrees" : "DIFFERS",
                        holes_ok ? "agrees" : "DIFFERS", gpu_full[2 * i].x, gpu_full[2 * i + 1].x);
            for (int k = 0; k < cpu.count; ++k) {
                const raycache::FilterTap& c = cpu.taps[static_cast<std::size_t>(k)];
                std::printf("    C++ tap %d %d %d %.9g\n", c.texel.face, c.texel.column, c.texel.row, c.weight);
            }
        }
    }
    std::printf("face size %4d: %zu directions (%zu footprints across an edge, %zu at a corner): GLSL footprint = "
                "C++ for %zu, filtered value = C++ for %zu (with a third of the texels empty: %zu); %s LINEAR "
                "sampler = filtered value within %.2g for %zu of %zu directions (largest difference %.3g; the "
                "other %zu are not directions)\n",
                n, count, t.across_edges, t.at_corners, t.taps_agree, t.values_agree, t.holes_agree,
                vk.device_name().c_str(), tolerance, t.sampler_agrees, t.sampled, t.worst_sampler, count - t.sampled);
    std::fflush(stdout);
    CHECK(count >= 100000);
    CHECK(t.taps_agree == count);
    CHECK(t.values_agree == count);
    CHECK(t.holes_agree == count);
    CHECK(t.sampler_agrees == t.sampled);
}

void check_face_sizes(std::initializer_list<int> sizes) {
    rcx_test::for_face_sizes("filter_cross",
                             {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                              VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                              VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
                             sizes, check_face_size);
}

} // namespace

TEST_CASE("GLSL and C++ filter alike, and as the device's LINEAR cube sampler, at face sizes 1, 2, 3 and 16") {
    check_face_sizes({1, 2, 3, 16});
}

TEST_CASE("GLSL and C++ filter alike, and as the device's LINEAR cube sampler, at face sizes 255 and 512") {
    check_face_sizes({255, 512});
}
