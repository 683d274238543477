// vulkan_test.hpp: what the Vulkan cross-check tests share: one rcx::vk::Context per test process,
// made on first use, and the paths of the SPIR-V files compiled at build time.
//
// A test case starts with `rcx::vk::Context* vk = rcx_test::context(); if (!vk) return;`: without a
// Vulkan device the case does nothing and the process exits 77 (CTest: skipped). After the cases, the
// process fails when the validation layer reported any error.
#pragma once

#include <algorithm>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include <raycache/cache_cube.hpp>
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

// Bindings of the cross-check shaders (shaders/*_cross.comp: five storage buffers) and of the
// end-frame pass (texels and pending).
inline const std::vector<VkDescriptorType> cross_bindings(5, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
inline const std::vector<VkDescriptorType> end_frame_bindings(2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);

// Records the end-frame pass (shaders/end_frame.comp) over `elements` elements of texels and pending.
inline void record_end_frame(rcx::vk::Commands& commands, const rcx::vk::ComputePipeline& end_frame,
                             const rcx::vk::Buffer& texels, const rcx::vk::Buffer& pending, std::uint64_t elements) {
    const std::uint32_t groups = rcx::vk::group_count(elements, 64);
    const std::uint32_t x = std::min<std::uint32_t>(groups, 65535u);
    commands.dispatch(end_frame, {texels, pending}, nullptr, 0, x, (groups + x - 1) / x);
}

} // namespace rcx_test
