// vulkan_test.hpp: what the Vulkan cross-check tests share: one rcx::vk::Context per test process,
// made on first use, and the paths of the SPIR-V files compiled at build time.
//
// A test case starts with `rcx::vk::Context* vk = rcx_test::context(); if (!vk) return;`: without a
// Vulkan device the case does nothing and the process exits 77 (CTest: skipped). After the cases, the
// process fails when the validation layer reported any error.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include <raycache/cache_cube.hpp>
#include <raycache/gpu_frame.hpp>
#include <raycache/shared/gpu_layout.h>
#include <rcx/vulkan.hpp>

#include "../cube_words.hpp"

namespace rcx_test {

// The process's Vulkan context, or nullptr when there is no Vulkan device (the reason is printed once).
rcx::vk::Context* context();

// Path of a SPIR-V file built from tests/vulkan/shaders/ ("face_map" -> ".../shaders/face_map.spv").
std::string spirv(const std::string& name);

using rcx::vk::buffer_of;

// Calls check(context, pipeline, n) for each face size n (captured for failure messages), with one compute
// pipeline made from shaders/<shader>.comp with these bindings and 8 bytes of push constants (face size,
// count). Does nothing without a Vulkan device.
template <class Check>
void for_face_sizes(const std::string& shader, const std::vector<VkDescriptorType>& bindings,
                    std::initializer_list<int> sizes, Check&& check) {
    rcx::vk::Context* vk = context();
    if (!vk) return;
    rcx::vk::ComputePipeline pipeline(*vk, spirv(shader), bindings, 8);
    for (int n : sizes) {
        CAPTURE(n);
        check(*vk, pipeline, n);
    }
}

// A device's sampler as an oracle: a software device (lavapipe) computes sampling coordinates in float,
// as RayCache does, so it must agree exactly; a GPU rounds them to subTexelPrecisionBits fractional bits
// of a texel (8 on NVIDIA's, a fixed-point unit), which moves texel choices and filter weights within that
// much. Returns those bits, or 0 for a device whose sampler is exact.
inline int sampler_fraction_bits(const rcx::vk::Context& vk) {
    return vk.properties().deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU
               ? 0
               : static_cast<int>(vk.properties().limits.subTexelPrecisionBits);
}

// Bindings of the cross-check shaders (shaders/*_cross.comp: six storage buffers, the frame buffer last), of
// the sweep (shaders/end_frame.comp: texels and pending) and of the library's end-of-frame pass
// (shaders/end_frame_listed.comp: CCT texels and pending, CDCT texels and pending, frame).
inline const std::vector<VkDescriptorType> cross_bindings(6, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
inline const std::vector<VkDescriptorType> end_frame_bindings(2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
inline const std::vector<VkDescriptorType> listed_end_frame_bindings(5, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);

// A frame buffer (raycache/gpu_frame.hpp) and its layout, started for a frame (start()).
struct Frame {
    Frame(rcx::vk::Context& vk, std::uint32_t cube_count, std::uint32_t list_capacity)
        : layout(raycache::gpu_frame_layout(cube_count, list_capacity)), buffer(vk, layout.bytes) {
        buffer.fill(0xDEADBEEFu); // list entries are never read before they are written
        start();
    }
    void start(bool mark_coverage = true, const std::vector<std::uint32_t>& resting = {}) {
        buffer.upload(raycache::gpu_frame_start_words(layout, mark_coverage, resting).data(), layout.start_bytes);
    }
    raycache::GpuFrameStatistics statistics() const { return raycache::read_gpu_statistics(buffer.as<std::uint32_t>(), layout); }
    // The entries listed this frame.
    std::vector<std::uint32_t> listed() const {
        const std::uint32_t* w = buffer.as<std::uint32_t>() + raycache::shared::raycache_frame_list_word(layout.cube_count, 0);
        return std::vector<std::uint32_t>(w, w + statistics().listed);
    }
    raycache::GpuFrameLayout layout;
    rcx::vk::Buffer buffer;
};

// Records the library's end-of-frame pass, dispatched indirectly from the frame buffer's own count.
inline void record_listed_end_frame(rcx::vk::Commands& commands, const rcx::vk::ComputePipeline& end_frame,
                                    const rcx::vk::Buffer& cct_texels, const rcx::vk::Buffer& cct_pending,
                                    const rcx::vk::Buffer& cdct_texels, const rcx::vk::Buffer& cdct_pending,
                                    const Frame& frame) {
    commands.dispatch_indirect(end_frame, {cct_texels, cct_pending, cdct_texels, cdct_pending, frame.buffer}, nullptr, 0,
                               frame.buffer, raycache::gpu_end_frame_dispatch_offset);
}

// Records the end-frame pass (shaders/end_frame.comp) over `elements` elements of texels and pending.
inline void record_end_frame(rcx::vk::Commands& commands, const rcx::vk::ComputePipeline& end_frame,
                             const rcx::vk::Buffer& texels, const rcx::vk::Buffer& pending, std::uint64_t elements) {
    const std::uint32_t groups = rcx::vk::group_count(elements, 64);
    const std::uint32_t x = std::min<std::uint32_t>(groups, 65535u);
    commands.dispatch(end_frame, {texels, pending}, nullptr, 0, x, (groups + x - 1) / x);
}

// SPIR-V's OpCapability operands present in a module (the SPIR-V specification: a 5-word header, then
// instructions whose first word is word count << 16 | opcode; OpCapability is opcode 17).
inline std::set<std::uint32_t> capabilities_of(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    REQUIRE_MESSAGE(file, "cannot read " << path);
    std::vector<char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    REQUIRE(bytes.size() % 4 == 0);
    std::vector<std::uint32_t> words(bytes.size() / 4);
    std::memcpy(words.data(), bytes.data(), bytes.size());
    REQUIRE(words.size() > 5);
    REQUIRE(words[0] == 0x07230203u); // the SPIR-V magic number
    std::set<std::uint32_t> found;
    for (std::size_t i = 5; i < words.size();) {
        const std::uint32_t count = words[i] >> 16, opcode = words[i] & 0xFFFFu;
        REQUIRE(count > 0);
        if (opcode == 17 && i + 1 < words.size()) found.insert(words[i + 1]);
        i += count;
    }
    return found;
}

inline constexpr std::uint32_t capability_shader = 1, capability_int64 = 11, capability_int64_atomics = 12;

} // namespace rcx_test
