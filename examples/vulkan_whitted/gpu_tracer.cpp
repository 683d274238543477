// The Vulkan compute Whitted tracer core; see gpu_tracer.hpp.
#include "gpu_tracer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <stdexcept>

#include <embree3/rtcore.h>
#include <glm/glm.hpp>
#include <raycache/shared/depth_secant.h>
#include <raycache/gpu_buffers.hpp>
#include <raycache/shared/gpu_layout.h>

#include "rcx/meshes.hpp"
#include "rcx/rsh_reference.hpp"

namespace rcx::gpu {

namespace {

// Nodes made by Embree's builder callbacks, in Embree's thread-local memory.
struct BuildNode {
    bool leaf = false;
};
struct InnerNode : BuildNode {
    BuildNode* children[2] = {nullptr, nullptr};
    RTCBounds bounds[2];
};
struct LeafNode : BuildNode {
    std::uint32_t count = 0;
    std::uint32_t ids[1]; // count entries (allocated to fit)
};

void* create_node(RTCThreadLocalAllocator alloc, unsigned int child_count, void*) {
    if (child_count != 2) return nullptr;
    void* memory = rtcThreadLocalAlloc(alloc, sizeof(InnerNode), 16);
    return new (memory) InnerNode();
}

void set_children(void* node, void** children, unsigned int child_count, void*) {
    auto* inner = static_cast<InnerNode*>(node);
    for (unsigned i = 0; i < child_count && i < 2; ++i) inner->children[i] = static_cast<BuildNode*>(children[i]);
}

void set_bounds(void* node, const RTCBounds** bounds, unsigned int child_count, void*) {
    auto* inner = static_cast<InnerNode*>(node);
    for (unsigned i = 0; i < child_count && i < 2; ++i) inner->bounds[i] = *bounds[i];
}

void* create_leaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* prims, size_t count, void*) {
    const std::size_t bytes = sizeof(LeafNode) + (count > 0 ? count - 1 : 0) * sizeof(std::uint32_t);
    void* memory = rtcThreadLocalAlloc(alloc, bytes, 16);
    auto* leaf = new (memory) LeafNode();
    leaf->leaf = true;
    leaf->count = static_cast<std::uint32_t>(count);
    for (std::size_t i = 0; i < count; ++i) leaf->ids[i] = prims[i].primID;
    return leaf;
}

RTCBounds bounds_of_points(std::initializer_list<glm::vec3> points, float pad) {
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
    for (const glm::vec3& p : points) lo = glm::min(lo, p), hi = glm::max(hi, p);
    RTCBounds b{};
    b.lower_x = lo.x - pad, b.lower_y = lo.y - pad, b.lower_z = lo.z - pad;
    b.upper_x = hi.x + pad, b.upper_y = hi.y + pad, b.upper_z = hi.z + pad;
    return b;
}

void set4(float* out, glm::vec3 v, float w) {
    out[0] = v.x, out[1] = v.y, out[2] = v.z, out[3] = w;
}

struct Flattener {
    const std::vector<GpuPrimitive>& all;
    FlatBvh& out;
    void fill(std::size_t index, const BuildNode* node, const RTCBounds& b) {
        BvhNode n{};
        n.lo[0] = b.lower_x, n.lo[1] = b.lower_y, n.lo[2] = b.lower_z;
        n.hi[0] = b.upper_x, n.hi[1] = b.upper_y, n.hi[2] = b.upper_z;
        if (node->leaf) {
            const auto* leaf = static_cast<const LeafNode*>(node);
            n.a = static_cast<std::int32_t>(out.primitives.size());
            n.b = static_cast<std::int32_t>(leaf->count);
            for (std::uint32_t i = 0; i < leaf->count; ++i) out.primitives.push_back(all[leaf->ids[i]]);
            out.nodes[index] = n;
            return;
        }
        const auto* inner = static_cast<const InnerNode*>(node);
        const std::size_t child = out.nodes.size();
        out.nodes.resize(child + 2);
        n.a = static_cast<std::int32_t>(child);
        n.b = 0;
        out.nodes[index] = n;
        fill(child, inner->children[0], inner->bounds[0]);
        fill(child + 1, inner->children[1], inner->bounds[1]);
    }
};

double ms_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

std::vector<GpuPrimitive> gather_primitives(const Scene& scene) {
    std::vector<GpuPrimitive> all;
    std::uint32_t object = 0;
    for (const Sphere& s : scene.spheres) {
        GpuPrimitive p{};
        set4(p.p[0], s.centre, s.radius);
        p.info[0] = 0, p.info[1] = object, p.info[2] = 0;
        all.push_back(p);
        ++object;
    }
    for (const Mesh& m : scene.meshes) {
        if (m.normals.size() != m.positions.size())
            throw std::invalid_argument("Vulkan tracer: mesh '" + m.name + "' needs one normal per vertex");
        for (std::size_t k = 0; k < m.triangles.size(); ++k) {
            const glm::uvec3 t = m.triangles[k];
            if (t.x >= m.positions.size() || t.y >= m.positions.size() || t.z >= m.positions.size())
                throw std::invalid_argument("Vulkan tracer: mesh '" + m.name + "' has a vertex index out of range");
            GpuPrimitive p{};
            for (int c = 0; c < 3; ++c) {
                set4(p.p[c], m.positions[t[c]], 0.0f);
                set4(p.n[c], m.normals[t[c]], 0.0f);
            }
            p.info[0] = 1, p.info[1] = object, p.info[2] = static_cast<std::uint32_t>(k);
            all.push_back(p);
        }
        ++object;
    }
    return all;
}

FlatBvh build_bvh(const Scene& scene) {
    // Every primitive, with its bounds for the builder.
    std::vector<GpuPrimitive> all = gather_primitives(scene);
    std::vector<RTCBuildPrimitive> build;
    for (std::size_t i = 0; i < all.size(); ++i) {
        const GpuPrimitive& p = all[i];
        const glm::vec3 a(p.p[0][0], p.p[0][1], p.p[0][2]);
        const RTCBounds b = p.info[0] == 0 ? bounds_of_points({a - glm::vec3(p.p[0][3]), a + glm::vec3(p.p[0][3])}, 0.0f)
                                           : bounds_of_points({a, glm::vec3(p.p[1][0], p.p[1][1], p.p[1][2]),
                                                               glm::vec3(p.p[2][0], p.p[2][1], p.p[2][2])}, 0.0f);
        RTCBuildPrimitive bp{};
        bp.lower_x = b.lower_x, bp.lower_y = b.lower_y, bp.lower_z = b.lower_z;
        bp.upper_x = b.upper_x, bp.upper_y = b.upper_y, bp.upper_z = b.upper_z;
        bp.geomID = p.info[1];
        bp.primID = static_cast<unsigned>(i);
        build.push_back(bp);
    }
    if (all.empty()) throw std::runtime_error("Vulkan tracer: the scene has no primitives");

    RTCDevice device = rtcNewDevice(nullptr);
    if (!device) throw std::runtime_error("Vulkan tracer: cannot create an Embree device for the BVH builder");
    RTCBVH bvh = rtcNewBVH(device);
    RTCBuildArguments args = rtcDefaultBuildArguments();
    args.byteSize = sizeof(args);
    args.buildFlags = RTC_BUILD_FLAG_NONE;
    args.buildQuality = RTC_BUILD_QUALITY_MEDIUM;
    args.maxBranchingFactor = 2;
    args.maxDepth = 48;
    args.sahBlockSize = 1;
    args.minLeafSize = 1;
    args.maxLeafSize = 4;
    args.traversalCost = 1.0f;
    args.intersectionCost = 1.0f;
    args.bvh = bvh;
    const std::size_t count = build.size();
    build.reserve(count * 2); // spare capacity, as the builder may use it
    args.primitives = build.data();
    args.primitiveCount = count;
    args.primitiveArrayCapacity = build.capacity();
    args.createNode = create_node;
    args.setNodeChildren = set_children;
    args.setNodeBounds = set_bounds;
    args.createLeaf = create_leaf;
    args.splitPrimitive = nullptr;
    args.buildProgress = nullptr;
    args.userPtr = nullptr;
    const BuildNode* root = static_cast<const BuildNode*>(rtcBuildBVH(&args));
    const RTCError error = rtcGetDeviceError(device);
    if (!root || error != RTC_ERROR_NONE) {
        rtcReleaseBVH(bvh);
        rtcReleaseDevice(device);
        throw std::runtime_error("Vulkan tracer: Embree's BVH builder failed (error " + std::to_string(static_cast<int>(error)) + ")");
    }

    RTCBounds scene_bounds{};
    scene_bounds.lower_x = scene_bounds.lower_y = scene_bounds.lower_z = std::numeric_limits<float>::infinity();
    scene_bounds.upper_x = scene_bounds.upper_y = scene_bounds.upper_z = -std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i < count; ++i) {
        const RTCBuildPrimitive& p = build[i];
        scene_bounds.lower_x = std::min(scene_bounds.lower_x, p.lower_x);
        scene_bounds.lower_y = std::min(scene_bounds.lower_y, p.lower_y);
        scene_bounds.lower_z = std::min(scene_bounds.lower_z, p.lower_z);
        scene_bounds.upper_x = std::max(scene_bounds.upper_x, p.upper_x);
        scene_bounds.upper_y = std::max(scene_bounds.upper_y, p.upper_y);
        scene_bounds.upper_z = std::max(scene_bounds.upper_z, p.upper_z);
    }
    FlatBvh flat;
    flat.nodes.resize(1);
    Flattener{all, flat}.fill(0, root, scene_bounds);
    rtcReleaseBVH(bvh); // frees the nodes
    rtcReleaseDevice(device);
    return flat;
}

std::string default_spirv_dir() {
    if (const char* env = std::getenv("RAYCACHE_VULKAN_WHITTED_SHADERS"); env && *env) return env;
    return RCX_VULKAN_WHITTED_SPIRV_DIR;
}

namespace {

struct GpuObject {
    float m[5][4];
};

struct GpuParams {
    float eye[4], forward[4], right[4], up[4];
    float light_position[4];  // w: ambient
    float light_intensity[4]; // w: tan(fov / 2)
    float environment[4];     // w: aspect
    std::int32_t frame[4];    // width, height, mode, max depth
    float relief[4];          // step, epsilon, max depth, max gap
    std::int32_t relief_i[4]; // max steps, search (RAYCACHE_DEPTH_SEARCH_*), max reads
};

int mode_number(CacheMode mode) {
    switch (mode) {
    case CacheMode::off: return 0;
    case CacheMode::cct: return 1;
    case CacheMode::cdct: return 2;
    case CacheMode::ceiling: return 3;
    }
    return 0;
}


// ---- the raster pass of the hybrid mode ---------------------------------------------------------------

void check(VkResult result, const char* what) {
    if (result != VK_SUCCESS) throw vk::Error(std::string("Vulkan tracer: ") + what + ": " + vk::to_string(result));
}

// Primary visibility by rasterisation into a G-buffer image of (t, primitive, u, v) per pixel
// (shaders/gbuffer.vert, gbuffer.frag), copied into a storage buffer that the tracing shader reads.
class Raster {
public:
    Raster(vk::Context& context, const std::string& spirv_dir, std::initializer_list<const vk::Buffer*> scene_buffers)
        : context_(context), device_(context.device()) {
        std::uint32_t families = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device(), &families, nullptr);
        std::vector<VkQueueFamilyProperties> properties(families);
        vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device(), &families, properties.data());
        if (context.queue_family() >= families || !(properties[context.queue_family()].queueFlags & VK_QUEUE_GRAPHICS_BIT))
            throw std::invalid_argument("Vulkan tracer: --hybrid needs a queue with graphics and compute; this device's has no graphics");
        try {
            create(spirv_dir, scene_buffers);
        } catch (...) {
            destroy();
            throw;
        }
    }
    ~Raster() { destroy(); }
    Raster(const Raster&) = delete;
    Raster& operator=(const Raster&) = delete;

    // Records the pass for a width x height image and the copy of its G-buffer into `gbuffer`.
    void record(VkCommandBuffer cb, int width, int height, std::uint32_t primitives, const vk::Buffer& gbuffer) {
        resize(width, height);
        VkClearValue clears[2]{};
        clears[0].color.uint32[0] = 0u;
        clears[0].color.uint32[1] = 0xFFFFFFFFu; // no primitive
        clears[1].depthStencil.depth = 1.0f;
        VkRenderPassBeginInfo begin{};
        begin.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO;
        begin.renderPass = pass_;
        begin.framebuffer = framebuffer_;
        begin.renderArea.extent = {static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)};
        begin.clearValueCount = 2;
        begin.pClearValues = clears;
        vkCmdBeginRenderPass(cb, &begin, VK_SUBPASS_CONTENTS_INLINE);
        vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_);
        vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, layout_, 0, 1, &set_, 0, nullptr);
        VkViewport viewport{0.0f, 0.0f, static_cast<float>(width), static_cast<float>(height), 0.0f, 1.0f};
        VkRect2D scissor{{0, 0}, {static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)}};
        vkCmdSetViewport(cb, 0, 1, &viewport);
        vkCmdSetScissor(cb, 0, 1, &scissor);
        vkCmdDraw(cb, 36u * primitives, 1, 0, 0);
        vkCmdEndRenderPass(cb);
        VkBufferImageCopy region{};
        region.imageSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
        region.imageSubresource.layerCount = 1;
        region.imageExtent = {static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height), 1};
        vkCmdCopyImageToBuffer(cb, color_, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, gbuffer.handle(), 1, &region);
    }

private:
    void create(const std::string& spirv_dir, std::initializer_list<const vk::Buffer*> scene_buffers) {
        vs_ = vk::create_shader_module(context_, spirv_dir + "/gbuffer_vert.spv");
        fs_ = vk::create_shader_module(context_, spirv_dir + "/gbuffer_frag.spv");

        // Set 0: the scene buffers at bindings 5.. (as in scene.glsl).
        std::vector<VkDescriptorSetLayoutBinding> bindings;
        for (std::uint32_t i = 0; i < scene_buffers.size(); ++i) {
            VkDescriptorSetLayoutBinding b{};
            b.binding = 5 + i;
            b.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
            b.descriptorCount = 1;
            b.stageFlags = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
            bindings.push_back(b);
        }
        VkDescriptorSetLayoutCreateInfo set_info{};
        set_info.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO;
        set_info.bindingCount = static_cast<std::uint32_t>(bindings.size());
        set_info.pBindings = bindings.data();
        check(vkCreateDescriptorSetLayout(device_, &set_info, nullptr, &set_layout_), "vkCreateDescriptorSetLayout");
        VkPipelineLayoutCreateInfo layout_info{};
        layout_info.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO;
        layout_info.setLayoutCount = 1;
        layout_info.pSetLayouts = &set_layout_;
        check(vkCreatePipelineLayout(device_, &layout_info, nullptr, &layout_), "vkCreatePipelineLayout");
        VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, static_cast<std::uint32_t>(bindings.size())};
        VkDescriptorPoolCreateInfo pool_info{};
        pool_info.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO;
        pool_info.maxSets = 1;
        pool_info.poolSizeCount = 1;
        pool_info.pPoolSizes = &size;
        check(vkCreateDescriptorPool(device_, &pool_info, nullptr, &pool_), "vkCreateDescriptorPool");
        VkDescriptorSetAllocateInfo alloc{};
        alloc.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO;
        alloc.descriptorPool = pool_;
        alloc.descriptorSetCount = 1;
        alloc.pSetLayouts = &set_layout_;
        check(vkAllocateDescriptorSets(device_, &alloc, &set_), "vkAllocateDescriptorSets");
        std::vector<VkDescriptorBufferInfo> infos;
        for (const vk::Buffer* b : scene_buffers) infos.push_back({b->handle(), 0, VK_WHOLE_SIZE});
        std::vector<VkWriteDescriptorSet> writes;
        for (std::uint32_t i = 0; i < infos.size(); ++i) {
            VkWriteDescriptorSet w{};
            w.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
            w.dstSet = set_;
            w.dstBinding = 5 + i;
            w.descriptorCount = 1;
            w.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
            w.pBufferInfo = &infos[i];
            writes.push_back(w);
        }
        vkUpdateDescriptorSets(device_, static_cast<std::uint32_t>(writes.size()), writes.data(), 0, nullptr);

        // Render pass: the G-buffer (cleared, then read by a transfer) and a depth buffer.
        VkAttachmentDescription attachments[2]{};
        attachments[0].format = color_format;
        attachments[0].samples = VK_SAMPLE_COUNT_1_BIT;
        attachments[0].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        attachments[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        attachments[0].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        attachments[0].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        attachments[0].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        attachments[0].finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        attachments[1] = attachments[0];
        attachments[1].format = depth_format;
        attachments[1].storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        attachments[1].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
        VkAttachmentReference color_ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
        VkAttachmentReference depth_ref{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
        VkSubpassDescription subpass{};
        subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
        subpass.colorAttachmentCount = 1;
        subpass.pColorAttachments = &color_ref;
        subpass.pDepthStencilAttachment = &depth_ref;
        VkSubpassDependency dependencies[2]{};
        dependencies[0].srcSubpass = VK_SUBPASS_EXTERNAL;
        dependencies[0].dstSubpass = 0;
        dependencies[0].srcStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
        dependencies[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT;
        dependencies[0].srcAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
        dependencies[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                                        VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT;
        dependencies[1].srcSubpass = 0;
        dependencies[1].dstSubpass = VK_SUBPASS_EXTERNAL;
        dependencies[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
        dependencies[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
        dependencies[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
        dependencies[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        VkRenderPassCreateInfo pass_info{};
        pass_info.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO;
        pass_info.attachmentCount = 2;
        pass_info.pAttachments = attachments;
        pass_info.subpassCount = 1;
        pass_info.pSubpasses = &subpass;
        pass_info.dependencyCount = 2;
        pass_info.pDependencies = dependencies;
        check(vkCreateRenderPass(device_, &pass_info, nullptr, &pass_), "vkCreateRenderPass");

        VkPipelineShaderStageCreateInfo stages[2]{};
        stages[0].sType = stages[1].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
        stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
        stages[0].module = vs_;
        stages[0].pName = "main";
        stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
        stages[1].module = fs_;
        stages[1].pName = "main";
        VkPipelineVertexInputStateCreateInfo vertex_input{};
        vertex_input.sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO;
        VkPipelineInputAssemblyStateCreateInfo assembly{};
        assembly.sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO;
        assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
        VkPipelineViewportStateCreateInfo viewport{};
        viewport.sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO;
        viewport.viewportCount = 1;
        viewport.scissorCount = 1;
        VkPipelineRasterizationStateCreateInfo raster{};
        raster.sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO;
        raster.polygonMode = VK_POLYGON_MODE_FILL;
        raster.cullMode = VK_CULL_MODE_NONE;
        raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
        raster.lineWidth = 1.0f;
        VkPipelineMultisampleStateCreateInfo multisample{};
        multisample.sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO;
        multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
        VkPipelineDepthStencilStateCreateInfo depth{};
        depth.sType = VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO;
        depth.depthTestEnable = VK_TRUE;
        depth.depthWriteEnable = VK_TRUE;
        depth.depthCompareOp = VK_COMPARE_OP_LESS;
        VkPipelineColorBlendAttachmentState blend_attachment{};
        blend_attachment.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT |
                                          VK_COLOR_COMPONENT_A_BIT;
        VkPipelineColorBlendStateCreateInfo blend{};
        blend.sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO;
        blend.attachmentCount = 1;
        blend.pAttachments = &blend_attachment;
        const VkDynamicState dynamic_states[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
        VkPipelineDynamicStateCreateInfo dynamic{};
        dynamic.sType = VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO;
        dynamic.dynamicStateCount = 2;
        dynamic.pDynamicStates = dynamic_states;
        VkGraphicsPipelineCreateInfo info{};
        info.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO;
        info.stageCount = 2;
        info.pStages = stages;
        info.pVertexInputState = &vertex_input;
        info.pInputAssemblyState = &assembly;
        info.pViewportState = &viewport;
        info.pRasterizationState = &raster;
        info.pMultisampleState = &multisample;
        info.pDepthStencilState = &depth;
        info.pColorBlendState = &blend;
        info.pDynamicState = &dynamic;
        info.layout = layout_;
        info.renderPass = pass_;
        check(vkCreateGraphicsPipelines(device_, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline_), "vkCreateGraphicsPipelines");
    }

    void make_image(VkFormat format, VkImageUsageFlags usage, VkImageAspectFlags aspect, VkImage& image,
                    VkDeviceMemory& memory, VkImageView& view) {
        vk::ImageDescription d;
        d.format = format;
        d.width = static_cast<std::uint32_t>(width_);
        d.height = static_cast<std::uint32_t>(height_);
        d.usage = usage;
        d.aspect = aspect;
        d.memory = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
        vk::create_image(context_, d, image, memory, view);
    }

    void destroy_images() noexcept {
        if (framebuffer_) vkDestroyFramebuffer(device_, framebuffer_, nullptr);
        if (color_view_) vkDestroyImageView(device_, color_view_, nullptr);
        if (depth_view_) vkDestroyImageView(device_, depth_view_, nullptr);
        if (color_) vkDestroyImage(device_, color_, nullptr);
        if (depth_) vkDestroyImage(device_, depth_, nullptr);
        if (color_memory_) vkFreeMemory(device_, color_memory_, nullptr);
        if (depth_memory_) vkFreeMemory(device_, depth_memory_, nullptr);
        framebuffer_ = VK_NULL_HANDLE, color_view_ = depth_view_ = VK_NULL_HANDLE, color_ = depth_ = VK_NULL_HANDLE;
        color_memory_ = depth_memory_ = VK_NULL_HANDLE;
        width_ = height_ = 0;
    }

    void resize(int width, int height) {
        if (width == width_ && height == height_ && framebuffer_) return;
        destroy_images();
        width_ = width, height_ = height;
        make_image(color_format, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
                   color_, color_memory_, color_view_);
        make_image(depth_format, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT, depth_,
                   depth_memory_, depth_view_);
        const VkImageView views[2] = {color_view_, depth_view_};
        VkFramebufferCreateInfo info{};
        info.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO;
        info.renderPass = pass_;
        info.attachmentCount = 2;
        info.pAttachments = views;
        info.width = static_cast<std::uint32_t>(width);
        info.height = static_cast<std::uint32_t>(height);
        info.layers = 1;
        check(vkCreateFramebuffer(device_, &info, nullptr, &framebuffer_), "vkCreateFramebuffer");
    }

    void destroy() noexcept {
        destroy_images();
        if (pipeline_) vkDestroyPipeline(device_, pipeline_, nullptr);
        if (pass_) vkDestroyRenderPass(device_, pass_, nullptr);
        if (pool_) vkDestroyDescriptorPool(device_, pool_, nullptr);
        if (layout_) vkDestroyPipelineLayout(device_, layout_, nullptr);
        if (set_layout_) vkDestroyDescriptorSetLayout(device_, set_layout_, nullptr);
        if (vs_) vkDestroyShaderModule(device_, vs_, nullptr);
        if (fs_) vkDestroyShaderModule(device_, fs_, nullptr);
        pipeline_ = VK_NULL_HANDLE, pass_ = VK_NULL_HANDLE, pool_ = VK_NULL_HANDLE, layout_ = VK_NULL_HANDLE;
        set_layout_ = VK_NULL_HANDLE, vs_ = fs_ = VK_NULL_HANDLE;
    }

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

} // namespace

struct Tracer::Impl {
    Impl(vk::Context& c, const Scene& s, const TracerSettings& t) : context(c), scene(s), settings(t) {}
    vk::Context& context;
    Scene scene;
    TracerSettings settings;
    FlatBvh bvh;
    std::unique_ptr<vk::ComputePipeline> whitted, end_frame;
    std::unique_ptr<vk::Buffer> nodes, primitives, objects, cubes, params, dummy, texels, pending;
    std::unique_ptr<vk::Buffer> output, frame, gbuffer;
    raycache::GpuFrameLayout frame_layout;          // RayCache's frame buffer: counters, store list
    std::vector<std::uint32_t> frame_start;         // its words before every frame
    std::unique_ptr<Raster> raster;
    std::unique_ptr<RshFrame> rsh;          // --secondary rsh: every ray through the ray-space hierarchy
    std::unique_ptr<vk::Buffer> rsh_prims;  // ... its primitives (raycache_rsh_primitive, scene order)
    double update_ms = 0.0;                 // the last set_scene
    std::uint32_t texel_count = 0;
    bool cdct = false;
};

Tracer::Tracer(vk::Context& context, const Scene& scene, const std::string& spirv_dir, const TracerSettings& settings)
    : impl_(std::make_unique<Impl>(context, scene, settings)) {
    Impl& t = *impl_;
    t.cdct = settings.mode == CacheMode::cdct;
    if (t.cdct && !context.int64_atomics())
        throw std::invalid_argument("Vulkan tracer: --cache cdct needs a device with shaderInt64 and shaderBufferInt64Atomics");
    // Shaders first: a missing or rejected SPIR-V file is the first thing to report.
    const std::string suffix = t.cdct ? "_cdct" : "";
    std::vector<VkDescriptorType> bindings(12, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    t.whitted = std::make_unique<vk::ComputePipeline>(context, spirv_dir + "/whitted" + suffix + ".spv", bindings, 0);
    if (uses_caches(settings.mode))
        t.end_frame = std::make_unique<vk::ComputePipeline>(
            context, spirv_dir + "/end_frame" + suffix + ".spv", std::vector<VkDescriptorType>(5, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
            0);
    const bool rsh = settings.secondary == Secondary::rsh;
    if (rsh && settings.mode != CacheMode::off)
        throw std::invalid_argument("Vulkan tracer: --secondary rsh traces every ray, without caching cubes: use --cache off");
    if (rsh) {
        t.bvh.primitives = gather_primitives(scene); // no scene structure: the primitives in scene order
        if (t.bvh.primitives.empty()) throw std::runtime_error("Vulkan tracer: the scene has no primitives");
        t.bvh.nodes.assign(1, BvhNode{});
        RshSettings rs;
        rs.pair_capacity = settings.pair_capacity;
        t.rsh = std::make_unique<RshFrame>(context, spirv_dir, rs);
        t.rsh_prims = std::make_unique<vk::Buffer>(vk::buffer_of(context, rsh::primitives_of(scene), 48));
    } else {
        t.bvh = build_bvh(scene);
    }

    // Objects: materials, and a cube descriptor for each cached one (face size 0: none).
    std::vector<GpuObject> objects;
    std::vector<raycache::shared::raycache_gpu_cube> cubes;
    const bool caching = uses_caches(settings.mode);
    if (caching && (settings.face_size < 1 || settings.face_size > RAYCACHE_MAX_FACE_SIZE))
        throw std::invalid_argument("Vulkan tracer: --face-size must be 1.." + std::to_string(RAYCACHE_MAX_FACE_SIZE));
    // The GLSL include reads one texel buffer per technique, so all cubes must fit in one storage buffer
    // (lavapipe: 128 MiB): raycache::fit_gpu_face_sizes lowers the faces to the largest size that fits, leaving
    // room for the frame buffer's counters, so that its store list can hold every texel (up to 16,776,960).
    const std::uint64_t word_bytes = t.cdct ? 8 : 4;
    const std::uint64_t range = context.properties().limits.maxStorageBufferRange;
    const std::uint32_t cached = caching ? static_cast<std::uint32_t>(scene.cached_object_count()) : 0u;
    const std::uint64_t counter_bytes = 4 * (std::uint64_t{RAYCACHE_FRAME_HEADER_WORDS} + std::uint64_t{cached} * RAYCACHE_FRAME_CUBE_WORDS);
    if (cached > 0) {
        if (range <= counter_bytes) throw std::invalid_argument("Vulkan tracer: too many cached objects for one storage buffer");
        t.settings.face_size = raycache::fit_gpu_face_sizes(std::vector<int>(cached, t.settings.face_size), word_bytes,
                                                            range - counter_bytes)[0];
    }
    std::vector<raycache::GpuCubeShape> shapes; // the cached objects' cubes, in object order
    std::vector<int> shape_of;                  // per object: its cube in shapes, or -1
    auto add_object = [&](const Material& m, bool sphere, glm::vec3 centre, float radius, glm::vec3 lo, glm::vec3 hi) {
        GpuObject o{};
        set4(o.m[0], m.diffuse, m.specular);
        set4(o.m[1], m.checker_color, m.shininess);
        o.m[2][0] = m.reflectivity, o.m[2][1] = m.transparency, o.m[2][2] = m.ior, o.m[2][3] = m.checker_scale;
        o.m[3][0] = m.checker ? 1.0f : 0.0f, o.m[3][1] = m.cached ? 1.0f : 0.0f, o.m[3][2] = sphere ? 1.0f : 0.0f;
        set4(o.m[4], centre, radius);
        objects.push_back(o);
        shape_of.push_back(-1);
        if (caching && m.cached) {
            const glm::vec3 half = 0.5f * (hi - lo);
            shapes.push_back({t.settings.face_size, raycache::CubeBounds{0.5f * (lo + hi), std::max(half.x, std::max(half.y, half.z))}});
            shape_of.back() = static_cast<int>(shapes.size() - 1);
        }
    };
    for (const Sphere& s : scene.spheres)
        add_object(s.material, true, s.centre, s.radius, s.centre - glm::vec3(s.radius), s.centre + glm::vec3(s.radius));
    for (const Mesh& m : scene.meshes) {
        const Bounds b = mesh_bounds(m);
        add_object(m.material, false, glm::vec3(0.0f), 0.0f, b.min, b.max);
    }
    const raycache::GpuBufferLayout layout =
        t.cdct ? raycache::gpu_buffer_layout<raycache::CdctTexel>(shapes) : raycache::gpu_buffer_layout<raycache::CctTexel>(shapes);
    for (const int k : shape_of) {
        raycache::shared::raycache_gpu_cube none{};
        none.face_size = 0; // no texels: lookups miss, stores are refused (counted nowhere: index 0 of face size 0)
        cubes.push_back(k >= 0 ? layout.cubes[static_cast<std::size_t>(k)] : none);
    }
    const std::uint64_t texels = layout.texels;
    if (layout.bytes > range)
        throw std::invalid_argument("Vulkan tracer: the cubes need " + std::to_string(layout.bytes) +
                                    " bytes, more than one storage buffer may hold on this device (" +
                                    std::to_string(range) + "); use a smaller --face-size");
    t.texel_count = static_cast<std::uint32_t>(texels);
    t.frame_layout = raycache::gpu_frame_layout(cached, raycache::gpu_frame_list_capacity(cached, texels, range), range);
    t.frame_start = raycache::gpu_frame_start_words(t.frame_layout);

    // Room for any binary BVH over these primitives (2n - 1 nodes), so set_scene uploads in place.
    t.nodes = std::make_unique<vk::Buffer>(context, std::max(t.bvh.nodes.size(), 2 * t.bvh.primitives.size()) * sizeof(BvhNode));
    t.nodes->upload(t.bvh.nodes.data(), t.bvh.nodes.size() * sizeof(BvhNode));
    t.primitives = std::make_unique<vk::Buffer>(vk::buffer_of(context, t.bvh.primitives, 16));
    t.objects = std::make_unique<vk::Buffer>(vk::buffer_of(context, objects, 16));
    t.cubes = std::make_unique<vk::Buffer>(vk::buffer_of(context, cubes, 16));
    t.params = std::make_unique<vk::Buffer>(context, sizeof(GpuParams));
    t.frame = std::make_unique<vk::Buffer>(context, std::max<std::uint64_t>(t.frame_layout.bytes, 16));
    t.dummy = std::make_unique<vk::Buffer>(context, 16);
    t.dummy->fill(RAYCACHE_GPU_CLEAR_WORD);
    if (texels > 0) {
        t.texels = std::make_unique<vk::Buffer>(context, texels * word_bytes);
        t.pending = std::make_unique<vk::Buffer>(context, texels * word_bytes);
        t.texels->fill(RAYCACHE_GPU_CLEAR_WORD);
        t.pending->fill(RAYCACHE_GPU_CLEAR_WORD);
    }
    if (settings.hybrid)
        t.raster = std::make_unique<Raster>(
            context, spirv_dir,
            std::initializer_list<const vk::Buffer*>{t.nodes.get(), t.primitives.get(), t.objects.get(), t.params.get()});
}

Tracer::~Tracer() = default;

const char* to_string(Secondary secondary) { return secondary == Secondary::rsh ? "rsh" : "bvh"; }

void Tracer::set_scene(const Scene& moved) {
    Impl& t = *impl_;
    const auto start = std::chrono::steady_clock::now();
    if (t.rsh) {
        const std::vector<GpuPrimitive> prims = gather_primitives(moved);
        const std::vector<rsh::Primitive> rp = rsh::primitives_of(moved);
        if (prims.size() != t.bvh.primitives.size())
            throw std::invalid_argument("Vulkan tracer: set_scene needs the same primitives, moved");
        t.primitives->upload(prims.data(), prims.size() * sizeof(GpuPrimitive));
        t.rsh_prims->upload(rp.data(), rp.size() * sizeof(rsh::Primitive));
    } else {
        FlatBvh bvh = build_bvh(moved);
        if (bvh.primitives.size() != t.bvh.primitives.size() || bvh.nodes.size() * sizeof(BvhNode) > t.nodes->size())
            throw std::invalid_argument("Vulkan tracer: set_scene needs the same primitives, moved");
        t.bvh = std::move(bvh);
        t.nodes->upload(t.bvh.nodes.data(), t.bvh.nodes.size() * sizeof(BvhNode));
        t.primitives->upload(t.bvh.primitives.data(), t.bvh.primitives.size() * sizeof(GpuPrimitive));
    }
    t.scene = moved;
    t.update_ms = ms_since(start);
}

std::size_t Tracer::bvh_nodes() const noexcept { return impl_->rsh ? 0 : impl_->bvh.nodes.size(); }
int Tracer::face_size() const noexcept { return impl_->settings.face_size; }
std::size_t Tracer::cube_bytes() const noexcept {
    return impl_->texels ? static_cast<std::size_t>(2 * impl_->texels->size()) : 0;
}

Image Tracer::render(const Camera& camera, int width, int height, FrameStats* stats) {
    if (width < 1 || height < 1)
        throw std::invalid_argument("Vulkan tracer: image size must be at least 1x1");
    Impl& t = *impl_;
    const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    if (!t.output || t.output->size() < pixels * 16) t.output = std::make_unique<vk::Buffer>(t.context, pixels * 16);
    if (t.raster && (!t.gbuffer || t.gbuffer->size() < pixels * 16)) t.gbuffer = std::make_unique<vk::Buffer>(t.context, pixels * 16);

    // The camera basis as the Embree tracer computes it (on the CPU, with glm); the shaders finish
    // rcx::primary_direction per pixel.
    const CameraBasis basis = camera_basis(camera, width, height);
    GpuParams p{};
    set4(p.eye, basis.eye, 0.0f);
    set4(p.forward, basis.forward, 0.0f);
    set4(p.right, basis.right, 0.0f);
    set4(p.up, basis.up, 0.0f);
    set4(p.light_position, t.scene.light.position, t.scene.ambient);
    set4(p.light_intensity, t.scene.light.intensity, basis.tan_half_fov);
    set4(p.environment, t.scene.environment, basis.aspect);
    p.frame[0] = width, p.frame[1] = height, p.frame[2] = mode_number(t.settings.mode) + (t.raster ? 16 : 0), p.frame[3] = t.scene.max_depth;
    p.relief[0] = t.settings.delta, p.relief[1] = t.settings.epsilon, p.relief[2] = 100.0f;
    p.relief[3] = t.settings.max_gap > 0.0f ? t.settings.max_gap : std::numeric_limits<float>::infinity();
    p.relief_i[0] = t.settings.max_steps;
    p.relief_i[1] = t.settings.secant ? RAYCACHE_DEPTH_SEARCH_SECANT : RAYCACHE_DEPTH_SEARCH_RELIEF;
    p.relief_i[2] = t.settings.max_reads;
    t.params->upload(&p, sizeof p);
    t.frame->upload(t.frame_start.data(), t.frame_start.size() * 4); // RayCache's frame buffer, started

    const vk::Buffer& cct_texels = (!t.cdct && t.texels) ? *t.texels : *t.dummy;
    const vk::Buffer& cct_pending = (!t.cdct && t.pending) ? *t.pending : *t.dummy;
    const vk::Buffer& cdct_texels = (t.cdct && t.texels) ? *t.texels : *t.dummy;
    const vk::Buffer& cdct_pending = (t.cdct && t.pending) ? *t.pending : *t.dummy;

    auto start = std::chrono::steady_clock::now();
    const vk::Buffer& gbuffer = t.gbuffer ? *t.gbuffer : *t.dummy;
    if (t.rsh) {
        if (t.raster)
            t.context.submit([&](vk::Commands& commands) {
                t.raster->record(commands.handle(), width, height, static_cast<std::uint32_t>(t.bvh.primitives.size()), gbuffer);
            });
        RshSceneBuffers b;
        b.prims = t.primitives.get(), b.objects = t.objects.get(), b.params = t.params.get(), b.rsh_prims = t.rsh_prims.get();
        b.prim_count = static_cast<std::uint32_t>(t.bvh.primitives.size());
        b.gbuffer = t.raster ? &gbuffer : nullptr;
        t.rsh->render(width, height, t.scene.max_depth, b, *t.output, stats ? &stats->rsh : nullptr);
    } else t.context.submit([&](vk::Commands& commands) {
        if (t.raster) {
            t.raster->record(commands.handle(), width, height, static_cast<std::uint32_t>(t.bvh.primitives.size()), gbuffer);
            commands.barrier(); // the copy's writes, visible to the tracing shader
        }
        commands.dispatch(*t.whitted,
                          {cct_texels, cct_pending, cdct_texels, cdct_pending, *t.frame, *t.nodes, *t.primitives, *t.objects,
                           *t.params, *t.output, *t.cubes, gbuffer},
                          nullptr, 0, vk::group_count(static_cast<std::uint64_t>(width), 8),
                          vk::group_count(static_cast<std::uint64_t>(height), 8));
    });
    const double ms = ms_since(start);

    // RayCache's end-of-frame pass over the texels stored this frame, dispatched from the frame buffer's own
    // group count (the frame's submission has completed, so its writes are visible to this one).
    double end_ms = 0.0;
    if (t.end_frame && t.texel_count > 0) {
        start = std::chrono::steady_clock::now();
        t.context.submit([&](vk::Commands& commands) {
            commands.dispatch_indirect(*t.end_frame, {cct_texels, cct_pending, cdct_texels, cdct_pending, *t.frame}, nullptr, 0,
                                       *t.frame, raycache::gpu_end_frame_dispatch_offset);
        });
        end_ms = ms_since(start);
    }
    const raycache::GpuFrameStatistics gpu_stats = raycache::read_gpu_statistics(t.frame->as<std::uint32_t>(), t.frame_layout);
    // The list holds every texel, or 16,776,960 of them for larger cubes: more stores in one frame would need
    // the library's sweep, which this tracer does not run.
    if (gpu_stats.overflow > 0)
        throw std::runtime_error("Vulkan tracer: more texels stored in one frame than RayCache's store list holds (" +
                                 std::to_string(t.frame_layout.list_capacity) + ")");

    Image image(width, height);
    const float* out = t.output->as<float>();
    for (std::size_t i = 0; i < pixels; ++i) image.pixels[i] = glm::vec3(out[4 * i], out[4 * i + 1], out[4 * i + 2]);
    if (stats) {
        stats->milliseconds = ms;
        stats->end_frame_milliseconds = end_ms;
        stats->stored_texels = gpu_stats.listed;
        stats->lookups = gpu_stats.total.lookups;
        stats->hits = gpu_stats.total.hits;
        stats->update_ms = t.update_ms;
    }
    t.update_ms = 0.0;
    return image;
}

} // namespace rcx::gpu
