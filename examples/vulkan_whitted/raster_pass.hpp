// raster_pass.hpp: the hybrid mode's raster pass (--hybrid): primary visibility by rasterisation into a
// G-buffer of (t, primitive, u, v) per pixel (shaders/gbuffer.vert, gbuffer.frag), copied into a storage
// buffer that the tracing shader reads.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>

#include <rcx/vulkan.hpp>

namespace rcx::gpu {

class Raster {
public:
    // Loads gbuffer_vert.spv and gbuffer_frag.spv from spirv_dir; binds scene_buffers at bindings 5..
    // (as in shaders/scene.glsl). Throws std::invalid_argument when the queue has no graphics.
    Raster(vk::Context& context, const std::string& spirv_dir, std::initializer_list<const vk::Buffer*> scene_buffers);
    ~Raster();
    Raster(const Raster&) = delete;
    Raster& operator=(const Raster&) = delete;

    // Records the pass for a width x height image and the copy of its G-buffer into `gbuffer`.
    void record(VkCommandBuffer cb, int width, int height, std::uint32_t primitives, const vk::Buffer& gbuffer);

private:
    void create(const std::string& spirv_dir, std::initializer_list<const vk::Buffer*> scene_buffers);
    void make_image(VkFormat format, VkImageUsageFlags usage, VkImageAspectFlags aspect, VkImage& image,
                    VkDeviceMemory& memory, VkImageView& view);
    void destroy_images() noexcept;
    void resize(int width, int height);
    void destroy() noexcept;

    static constexpr VkFormat color_format = VK_FORMAT_R32G32B32A32_UINT;
    static constexpr VkFormat depth_format = VK_FORMAT_D32_SFLOAT;
    vk::Context& context_;
    VkDevice device_;
    VkShaderModule vs_ = VK_NULL_HANDLE, fs_ = VK_NULL_HANDLE;
    VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
    VkRenderPass pass_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
    int width_ = 0, height_ = 0;
    VkImage color_ = VK_NULL_HANDLE, depth_ = VK_NULL_HANDLE;
    VkDeviceMemory color_memory_ = VK_NULL_HANDLE, depth_memory_ = VK_NULL_HANDLE;
    VkImageView color_view_ = VK_NULL_HANDLE, depth_view_ = VK_NULL_HANDLE;
    VkFramebuffer framebuffer_ = VK_NULL_HANDLE;
};

} // namespace rcx::gpu
