// What a shader that includes RayCache's GLSL asks of the device: a CCT-only shader through
// raycache/raycache.glsl declares no 64-bit capability, is created on lavapipe without shaderInt64 with no
// validation error, and behaves on buffers filled as raycache/gpu_buffers.hpp fills them (and shows, on
// zero-filled ones, the trap that fill avoids).
#include <doctest/doctest.h>

#include <cstdint>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include <raycache/raycache.hpp>

#include "vulkan_test.hpp"

TEST_CASE("a CCT-only shader through raycache.glsl declares no 64-bit capability, and one asking for the CDCT declares Int64") {
    const std::set<std::uint32_t> cct_only = rcx_test::capabilities_of(rcx_test::spirv("cct_only"));
    CHECK(cct_only.count(rcx_test::capability_shader) == 1);
    CHECK(cct_only.count(rcx_test::capability_int64) == 0);
    CHECK(cct_only.count(rcx_test::capability_int64_atomics) == 0);
    const std::set<std::uint32_t> with_cdct = rcx_test::capabilities_of(rcx_test::spirv("with_cdct"));
    CHECK(with_cdct.count(rcx_test::capability_int64) == 1);
    CHECK(with_cdct.count(rcx_test::capability_int64_atomics) == 1);
}

TEST_CASE("a CCT-only shader runs without shaderInt64 and no validation error: filled buffers miss and store, "
          "zero-filled ones hit black and store nothing") {
    if (!rcx_test::context()) return; // no Vulkan device: skipped
    rcx::vk::ContextOptions options;
    options.enable_int64 = false;
    rcx::vk::Context vk(options);
    REQUIRE_MESSAGE(vk.validation_enabled(), "this test needs VK_LAYER_KHRONOS_validation to mean anything");
    REQUIRE_FALSE(vk.int64_atomics());
    const std::uint64_t errors_before = vk.validation_errors();

    rcx::vk::ComputePipeline pipeline(vk, rcx_test::spirv("cct_only"),
                                      std::vector<VkDescriptorType>(4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
                                      sizeof(raycache::shared::raycache_gpu_cube));
    const raycache::GpuBufferLayout layout = raycache::gpu_buffer_layout<raycache::CctTexel>({{4, {}}});
    rcx::vk::Buffer texels = rcx_test::buffer_of(vk, raycache::cleared_gpu_words(layout));
    rcx::vk::Buffer pending = rcx_test::buffer_of(vk, raycache::cleared_gpu_words(layout));
    rcx::vk::Buffer results(vk, 6 * 8);
    const raycache::GpuFrameLayout frame_layout = raycache::gpu_frame_layout(1, 6);
    rcx::vk::Buffer frame(vk, frame_layout.bytes);
    auto run = [&] {
        frame.fill(0u);
        frame.upload(raycache::gpu_frame_start_words(frame_layout).data(), frame_layout.start_bytes);
        vk.dispatch(pipeline, {texels, pending, results, frame}, &layout.cubes[0], sizeof(layout.cubes[0]), 1);
        std::vector<std::uint32_t> r(results.as<std::uint32_t>(), results.as<std::uint32_t>() + 12);
        return r;
    };

    const std::vector<std::uint32_t> filled = run();
    for (int i = 0; i < 6; ++i) {
        CAPTURE(i);
        CHECK(filled[2 * i] == 0u);     // a miss
        CHECK(filled[2 * i + 1] == 1u); // and a store
    }
    texels.fill(0u);
    pending.fill(0u);
    const std::vector<std::uint32_t> zeros = run();
    for (int i = 0; i < 6; ++i) {
        CAPTURE(i);
        CHECK(zeros[2 * i] == 1u);     // black, from nothing
        CHECK(zeros[2 * i + 1] == 0u); // and nothing stored
    }
    CHECK(vk.validation_errors() == errors_before);
}

TEST_CASE("shader statistics are captured exactly where the device offers VK_KHR_pipeline_executable_properties") {
    if (!rcx_test::context()) return; // no Vulkan device: skipped
    rcx::vk::ContextOptions options;
    options.shader_statistics = true;
    rcx::vk::Context vk(options);
    const std::uint64_t errors_before = vk.validation_errors();
    // Whether the device offers the extension and its feature, asked here rather than of the harness.
    std::uint32_t count = 0;
    vkEnumerateDeviceExtensionProperties(vk.physical_device(), nullptr, &count, nullptr);
    std::vector<VkExtensionProperties> extensions(count);
    vkEnumerateDeviceExtensionProperties(vk.physical_device(), nullptr, &count, extensions.data());
    bool offered = false;
    for (const VkExtensionProperties& e : extensions)
        offered = offered || std::string(e.extensionName) == VK_KHR_PIPELINE_EXECUTABLE_PROPERTIES_EXTENSION_NAME;
    if (offered) {
        VkPhysicalDevicePipelineExecutablePropertiesFeaturesKHR feature{};
        feature.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PIPELINE_EXECUTABLE_PROPERTIES_FEATURES_KHR;
        VkPhysicalDeviceFeatures2 features{};
        features.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
        features.pNext = &feature;
        vkGetPhysicalDeviceFeatures2(vk.physical_device(), &features);
        offered = feature.pipelineExecutableInfo == VK_TRUE;
    }
    CHECK(vk.shader_statistics() == offered);
    rcx::vk::ComputePipeline pipeline(vk, rcx_test::spirv("cct_only"),
                                      std::vector<VkDescriptorType>(4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
                                      sizeof(raycache::shared::raycache_gpu_cube));
    const std::vector<std::string> statistics = pipeline.statistics();
    std::string listed;
    for (const std::string& s : statistics) listed += (listed.empty() ? "" : ", ") + s;
    MESSAGE(vk.device_name() << std::string(offered ? " offers" : " does not offer") << " the extension; statistics: " << listed);
    CHECK(statistics.empty() == !offered);
    for (const std::string& s : statistics) CHECK(s.front() != '('); // no call failed
    // Without asking, nothing is captured, whatever the device offers.
    rcx::vk::Context plain;
    CHECK_FALSE(plain.shader_statistics());
    CHECK(rcx::vk::ComputePipeline(plain, rcx_test::spirv("cct_only"), std::vector<VkDescriptorType>(4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
                                   sizeof(raycache::shared::raycache_gpu_cube))
              .statistics()
              .empty());
    CHECK(vk.validation_errors() == errors_before);
}
