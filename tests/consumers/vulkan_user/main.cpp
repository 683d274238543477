// A Vulkan user's first RayCache program, written from README.md ("In your own Vulkan shaders") and the
// headers it names: one CCT cube in GPU buffers made by the host helpers, two frames of lookups and stores
// (frame.comp), the end-of-frame pass (end_frame.comp), and the GPU's hit/miss counters read back.
// Frame 1 misses everywhere and stores; frame 2 hits everywhere with the colours frame 1 stored. The
// validation layer (with synchronization validation) must report nothing.
// Exit codes: 0 passed, 1 failed, 77 no Vulkan device or no validation layer (skipped).
#include <raycache/gpu_buffers.hpp>
#include <raycache/raycache.hpp>

#include <vulkan/vulkan.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

int failures = 0;
int validation_messages = 0;

#define EXPECT(cond)                                                                  \
    do {                                                                              \
        if (!(cond)) {                                                                \
            std::printf("FAIL line %d: %s\n", __LINE__, #cond);                       \
            ++failures;                                                               \
        }                                                                             \
    } while (0)

void check(VkResult r, const char* what) {
    if (r != VK_SUCCESS) throw std::runtime_error(std::string(what) + " failed: " + std::to_string(r));
}

VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                          VkDebugUtilsMessageTypeFlagsEXT, const VkDebugUtilsMessengerCallbackDataEXT* data,
                                          void*) {
    if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        ++validation_messages;
        std::printf("validation: %s\n", data->pMessage);
    }
    return VK_FALSE;
}

bool layer_has_extension(const char* layer, const char* name) {
    std::uint32_t count = 0;
    vkEnumerateInstanceExtensionProperties(layer, &count, nullptr);
    std::vector<VkExtensionProperties> extensions(count);
    vkEnumerateInstanceExtensionProperties(layer, &count, extensions.data());
    for (const VkExtensionProperties& e : extensions)
        if (std::strcmp(e.extensionName, name) == 0) return true;
    return false;
}

bool has_validation_layer() {
    std::uint32_t count = 0;
    vkEnumerateInstanceLayerProperties(&count, nullptr);
    std::vector<VkLayerProperties> layers(count);
    vkEnumerateInstanceLayerProperties(&count, layers.data());
    for (const VkLayerProperties& l : layers)
        if (std::strcmp(l.layerName, "VK_LAYER_KHRONOS_validation") == 0) return true;
    return false;
}

std::vector<std::uint32_t> read_spirv(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (bytes.empty() || bytes.size() % 4) throw std::runtime_error("cannot read " + path);
    std::vector<std::uint32_t> words(bytes.size() / 4);
    std::memcpy(words.data(), bytes.data(), bytes.size());
    return words;
}

// A buffer in host-visible, coherent memory, mapped for its whole life.
struct Buffer {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    void* mapped = nullptr;
    VkDeviceSize size = 0;
};

struct Gpu {
    VkInstance instance = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
    VkPhysicalDevice physical = VK_NULL_HANDLE;
    VkPhysicalDeviceProperties properties{};
    VkDevice device = VK_NULL_HANDLE;
    std::uint32_t family = 0;
    VkQueue queue = VK_NULL_HANDLE;

    Buffer make_buffer(VkDeviceSize size, VkBufferUsageFlags usage) {
        Buffer b;
        b.size = size;
        VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        info.size = size;
        info.usage = usage;
        check(vkCreateBuffer(device, &info, nullptr, &b.buffer), "vkCreateBuffer");
        VkMemoryRequirements req;
        vkGetBufferMemoryRequirements(device, b.buffer, &req);
        VkPhysicalDeviceMemoryProperties mem;
        vkGetPhysicalDeviceMemoryProperties(physical, &mem);
        const VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        std::uint32_t type = ~0u;
        for (std::uint32_t i = 0; i < mem.memoryTypeCount && type == ~0u; ++i)
            if ((req.memoryTypeBits & (1u << i)) && (mem.memoryTypes[i].propertyFlags & want) == want) type = i;
        if (type == ~0u) throw std::runtime_error("no host-visible coherent memory");
        VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        alloc.allocationSize = req.size;
        alloc.memoryTypeIndex = type;
        check(vkAllocateMemory(device, &alloc, nullptr, &b.memory), "vkAllocateMemory");
        check(vkBindBufferMemory(device, b.buffer, b.memory, 0), "vkBindBufferMemory");
        check(vkMapMemory(device, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped), "vkMapMemory");
        return b;
    }
    void destroy(Buffer& b) {
        vkDestroyBuffer(device, b.buffer, nullptr);
        vkFreeMemory(device, b.memory, nullptr);
    }
};

// Directions spread over the sphere (a Fibonacci lattice).
std::vector<glm::vec4> ray_directions(std::uint32_t count) {
    std::vector<glm::vec4> d;
    for (std::uint32_t k = 0; k < count; ++k) {
        const float z = 1.0f - 2.0f * (static_cast<float>(k) + 0.5f) / static_cast<float>(count);
        const float r = std::sqrt(1.0f - z * z), phi = 2.39996323f * static_cast<float>(k);
        d.emplace_back(r * std::cos(phi), r * std::sin(phi), z, 0.0f);
    }
    return d;
}

glm::vec3 colour_of(std::uint32_t k) { // as frame.comp
    return glm::vec3(static_cast<float>(k % 8u), static_cast<float>((k / 8u) % 8u), 4.0f) / 8.0f;
}

int run() {
    if (!has_validation_layer()) {
        std::printf("skipped: no VK_LAYER_KHRONOS_validation (Debian: vulkan-validationlayers)\n");
        return 77;
    }
    Gpu g;
    // --- Instance with the validation layer, synchronization validation on: a missing barrier is a message.
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.apiVersion = VK_API_VERSION_1_1;
    const char* layer = "VK_LAYER_KHRONOS_validation";
    std::vector<const char*> extensions{VK_EXT_DEBUG_UTILS_EXTENSION_NAME};
    const bool sync_validation = layer_has_extension(layer, VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
    if (sync_validation) extensions.push_back(VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
    VkValidationFeatureEnableEXT enables[] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
    VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
    features.enabledValidationFeatureCount = 1;
    features.pEnabledValidationFeatures = enables;
    VkDebugUtilsMessengerCreateInfoEXT messenger{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    messenger.pNext = sync_validation ? &features : nullptr;
    messenger.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    messenger.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                            VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    messenger.pfnUserCallback = on_message;
    VkInstanceCreateInfo instance_info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    instance_info.pNext = &messenger;
    instance_info.pApplicationInfo = &app;
    instance_info.enabledLayerCount = 1;
    instance_info.ppEnabledLayerNames = &layer;
    instance_info.enabledExtensionCount = static_cast<std::uint32_t>(extensions.size());
    instance_info.ppEnabledExtensionNames = extensions.data();
    if (vkCreateInstance(&instance_info, nullptr, &g.instance) != VK_SUCCESS) {
        std::printf("skipped: no Vulkan driver\n");
        return 77;
    }
    auto create_messenger = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(g.instance, "vkCreateDebugUtilsMessengerEXT"));
    messenger.pNext = nullptr;
    check(create_messenger(g.instance, &messenger, nullptr, &g.messenger), "vkCreateDebugUtilsMessengerEXT");

    // --- A device with a compute queue. The CCT needs no feature beyond Vulkan 1.1: none is enabled.
    std::uint32_t count = 0;
    vkEnumeratePhysicalDevices(g.instance, &count, nullptr);
    std::vector<VkPhysicalDevice> physicals(count);
    vkEnumeratePhysicalDevices(g.instance, &count, physicals.data());
    for (VkPhysicalDevice p : physicals) {
        std::uint32_t families = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(p, &families, nullptr);
        std::vector<VkQueueFamilyProperties> props(families);
        vkGetPhysicalDeviceQueueFamilyProperties(p, &families, props.data());
        for (std::uint32_t f = 0; f < families && !g.physical; ++f)
            if (props[f].queueFlags & VK_QUEUE_COMPUTE_BIT) g.physical = p, g.family = f;
    }
    if (!g.physical) {
        std::printf("skipped: no Vulkan device with a compute queue\n");
        return 77;
    }
    vkGetPhysicalDeviceProperties(g.physical, &g.properties);
    std::printf("device: %s, synchronization validation %s\n", g.properties.deviceName, sync_validation ? "on" : "off");
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queue_info.queueFamilyIndex = g.family;
    queue_info.queueCount = 1;
    queue_info.pQueuePriorities = &priority;
    VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    device_info.queueCreateInfoCount = 1;
    device_info.pQueueCreateInfos = &queue_info;
    check(vkCreateDevice(g.physical, &device_info, nullptr, &g.device), "vkCreateDevice");
    vkGetDeviceQueue(g.device, g.family, 0, &g.queue);

    // --- 1. Buffers: one CCT cube of face size 16 (fitted under maxStorageBufferRange), its texel buffer,
    // its pending twin, the frame buffer, and the program's own: descriptors, directions, results.
    const std::uint64_t max_range = g.properties.limits.maxStorageBufferRange;
    const std::vector<int> sizes =
        raycache::fit_gpu_face_sizes({16}, raycache::gpu_words_per_texel<raycache::CctTexel> * 4, max_range);
    const raycache::GpuBufferLayout layout = raycache::gpu_buffer_layout<raycache::CctTexel>({{sizes[0], {}}});
    const auto cube_count = static_cast<std::uint32_t>(layout.cubes.size());
    const raycache::GpuFrameLayout frame =
        raycache::gpu_frame_layout(cube_count, raycache::gpu_frame_list_capacity(cube_count, layout.texels, max_range));
    const std::uint32_t rays = 64;
    const std::vector<glm::vec4> directions = ray_directions(rays);

    const VkBufferUsageFlags storage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    Buffer texels = g.make_buffer(layout.bytes, storage | VK_BUFFER_USAGE_TRANSFER_DST_BIT);
    Buffer pending = g.make_buffer(layout.bytes, storage | VK_BUFFER_USAGE_TRANSFER_DST_BIT);
    Buffer frame_buffer = g.make_buffer(frame.bytes, storage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT);
    Buffer cubes = g.make_buffer(layout.cubes.size() * sizeof(layout.cubes[0]), storage);
    Buffer rays_in = g.make_buffer(directions.size() * sizeof(glm::vec4), storage);
    Buffer results = g.make_buffer(rays * sizeof(glm::vec4), storage);
    std::memcpy(cubes.mapped, layout.cubes.data(), cubes.size);
    std::memcpy(rays_in.mapped, directions.data(), rays_in.size);

    // --- Descriptors: RayCache's bindings (set 0; CCT only: texels, pending, frame) and the program's.
    const std::uint32_t bindings[] = {raycache::gpu_bindings.cct_texels, raycache::gpu_bindings.cct_pending,
                                      raycache::gpu_bindings.frame, 5, 6, 7};
    Buffer* bound[] = {&texels, &pending, &frame_buffer, &cubes, &rays_in, &results};
    std::vector<VkDescriptorSetLayoutBinding> set_bindings;
    for (std::uint32_t b : bindings)
        set_bindings.push_back({b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
    VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    set_info.bindingCount = static_cast<std::uint32_t>(set_bindings.size());
    set_info.pBindings = set_bindings.data();
    VkDescriptorSetLayout set_layout;
    check(vkCreateDescriptorSetLayout(g.device, &set_info, nullptr, &set_layout), "vkCreateDescriptorSetLayout");
    VkDescriptorPoolSize pool_size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 6};
    VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pool_info.maxSets = 1;
    pool_info.poolSizeCount = 1;
    pool_info.pPoolSizes = &pool_size;
    VkDescriptorPool pool;
    check(vkCreateDescriptorPool(g.device, &pool_info, nullptr, &pool), "vkCreateDescriptorPool");
    VkDescriptorSetAllocateInfo set_alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    set_alloc.descriptorPool = pool;
    set_alloc.descriptorSetCount = 1;
    set_alloc.pSetLayouts = &set_layout;
    VkDescriptorSet set;
    check(vkAllocateDescriptorSets(g.device, &set_alloc, &set), "vkAllocateDescriptorSets");
    VkDescriptorBufferInfo buffer_infos[6];
    VkWriteDescriptorSet writes[6];
    for (int i = 0; i < 6; ++i) {
        buffer_infos[i] = {bound[i]->buffer, 0, VK_WHOLE_SIZE};
        writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        writes[i].dstSet = set;
        writes[i].dstBinding = bindings[i];
        writes[i].descriptorCount = 1;
        writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        writes[i].pBufferInfo = &buffer_infos[i];
    }
    vkUpdateDescriptorSets(g.device, 6, writes, 0, nullptr);

    // --- Pipelines: the frame's shader and the end-of-frame pass, one layout.
    VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(std::uint32_t)};
    VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layout_info.setLayoutCount = 1;
    layout_info.pSetLayouts = &set_layout;
    layout_info.pushConstantRangeCount = 1;
    layout_info.pPushConstantRanges = &push;
    VkPipelineLayout pipeline_layout;
    check(vkCreatePipelineLayout(g.device, &layout_info, nullptr, &pipeline_layout), "vkCreatePipelineLayout");
    auto make_pipeline = [&](const char* name) {
        const std::vector<std::uint32_t> code = read_spirv(std::string(SPIRV_DIR) + "/" + name);
        VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
        module_info.codeSize = code.size() * 4;
        module_info.pCode = code.data();
        VkShaderModule module;
        check(vkCreateShaderModule(g.device, &module_info, nullptr, &module), "vkCreateShaderModule");
        VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
        info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
        info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
        info.stage.module = module;
        info.stage.pName = "main";
        info.layout = pipeline_layout;
        VkPipeline pipeline;
        check(vkCreateComputePipelines(g.device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline), "vkCreateComputePipelines");
        vkDestroyShaderModule(g.device, module, nullptr);
        return pipeline;
    };
    VkPipeline frame_pipeline = make_pipeline("frame.spv");
    VkPipeline end_pipeline = make_pipeline("end_frame.spv");

    VkCommandPoolCreateInfo command_pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    command_pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    command_pool_info.queueFamilyIndex = g.family;
    VkCommandPool command_pool;
    check(vkCreateCommandPool(g.device, &command_pool_info, nullptr, &command_pool), "vkCreateCommandPool");
    VkCommandBufferAllocateInfo command_alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    command_alloc.commandPool = command_pool;
    command_alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    command_alloc.commandBufferCount = 1;
    VkCommandBuffer cmd;
    check(vkAllocateCommandBuffers(g.device, &command_alloc, &cmd), "vkAllocateCommandBuffers");

    auto barrier = [&](VkPipelineStageFlags src_stage, VkAccessFlags src, VkPipelineStageFlags dst_stage, VkAccessFlags dst) {
        VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        b.srcAccessMask = src;
        b.dstAccessMask = dst;
        vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 1, &b, 0, nullptr, 0, nullptr);
    };

    // --- Two frames, one submission each.
    const std::vector<std::uint32_t> start = raycache::gpu_frame_start_words(frame);
    std::vector<glm::vec4> seen[2];
    raycache::GpuFrameStatistics statistics[2];
    for (int f = 0; f < 2; ++f) {
        VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");
        if (f == 0) { // 2. Fill, once, before the first frame: zeros would read as black texels.
            vkCmdFillBuffer(cmd, texels.buffer, 0, VK_WHOLE_SIZE, raycache::gpu_clear_word);
            vkCmdFillBuffer(cmd, pending.buffer, 0, VK_WHOLE_SIZE, raycache::gpu_clear_word);
        }
        // 3. Start the frame: the frame buffer's header and zeroed counters.
        vkCmdUpdateBuffer(cmd, frame_buffer.buffer, 0, frame.start_bytes, start.data());
        barrier(VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
        // 4. The frame's lookups and stores.
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, frame_pipeline);
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_layout, 0, 1, &set, 0, nullptr);
        vkCmdPushConstants(cmd, pipeline_layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(rays), &rays);
        vkCmdDispatch(cmd, (rays + 63) / 64, 1, 1);
        // 5. End of frame: barrier, the pass dispatched from the frame buffer, barrier again.
        barrier(VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_SHADER_READ_BIT);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, end_pipeline);
        vkCmdDispatchIndirect(cmd, frame_buffer.buffer, raycache::gpu_end_frame_dispatch_offset);
        barrier(VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_HOST_BIT,
                VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_HOST_READ_BIT);
        check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
        VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        submit.commandBufferCount = 1;
        submit.pCommandBuffers = &cmd;
        check(vkQueueSubmit(g.queue, 1, &submit, VK_NULL_HANDLE), "vkQueueSubmit");
        check(vkQueueWaitIdle(g.queue), "vkQueueWaitIdle");
        // 6. Statistics.
        statistics[f] = raycache::read_gpu_statistics(static_cast<const std::uint32_t*>(frame_buffer.mapped), frame);
        const auto* r = static_cast<const glm::vec4*>(results.mapped);
        seen[f].assign(r, r + rays);
    }

    // --- What the frames must have done.
    std::set<std::uint32_t> distinct; // the texels the rays fall in (the host's face table, the shader's too)
    for (const glm::vec4& d : directions) {
        const raycache::TexelAddress a = raycache::texel_of(glm::vec3(d), layout.cubes[0].face_size).value();
        distinct.insert(static_cast<std::uint32_t>((a.face * sizes[0] + a.row) * sizes[0] + a.column));
    }
    const raycache::CubeStatistics& one = statistics[0].total;
    const raycache::CubeStatistics& two = statistics[1].total;
    std::printf("frame 1: %llu lookups, %llu hits, %llu misses, %llu stores, %llu texels published\n",
                (unsigned long long)one.lookups, (unsigned long long)one.hits, (unsigned long long)one.misses,
                (unsigned long long)one.stores, (unsigned long long)statistics[0].listed);
    std::printf("frame 2: %llu lookups, %llu hits, %llu misses, %llu stores\n", (unsigned long long)two.lookups,
                (unsigned long long)two.hits, (unsigned long long)two.misses, (unsigned long long)two.stores);
    EXPECT(distinct.size() == rays); // each ray its own texel, so every store wins its texel
    EXPECT(one.lookups == rays && one.hits == 0 && one.misses == rays && one.stores == rays);
    EXPECT(statistics[0].listed == rays && statistics[0].overflow == 0);
    EXPECT(two.lookups == rays && two.hits == rays && two.misses == 0 && two.stores == 0);
    EXPECT(statistics[1].listed == 0);
    for (std::uint32_t k = 0; k < rays; ++k) {
        const glm::vec3 c = colour_of(k);
        EXPECT(seen[0][k] == glm::vec4(c, 0.0f)); // a miss: the traced colour
        EXPECT(seen[1][k] == glm::vec4(c, 1.0f)); // a hit: frame 1's colour, exact in RGB9E5
    }
    // The GPU's texels read into a C++ cube answer the same colours.
    raycache::CctCube cube(sizes[0]);
    const std::size_t valid = raycache::read_gpu_words(cube, layout.cubes[0], static_cast<const std::uint32_t*>(texels.mapped),
                                                       static_cast<std::size_t>(layout.words));
    cube.begin_frame();
    EXPECT(valid == rays);
    for (std::uint32_t k = 0; k < rays; ++k) {
        const std::optional<glm::vec3> c = cube.lookup(glm::vec3(directions[k]));
        EXPECT(c && *c == colour_of(k));
    }

    vkDestroyCommandPool(g.device, command_pool, nullptr);
    vkDestroyPipeline(g.device, frame_pipeline, nullptr);
    vkDestroyPipeline(g.device, end_pipeline, nullptr);
    vkDestroyPipelineLayout(g.device, pipeline_layout, nullptr);
    vkDestroyDescriptorPool(g.device, pool, nullptr);
    vkDestroyDescriptorSetLayout(g.device, set_layout, nullptr);
    for (Buffer* b : bound) g.destroy(*b);
    vkDestroyDevice(g.device, nullptr);
    auto destroy_messenger = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(g.instance, "vkDestroyDebugUtilsMessengerEXT"));
    destroy_messenger(g.instance, g.messenger, nullptr);
    vkDestroyInstance(g.instance, nullptr);

    EXPECT(validation_messages == 0);
    std::printf("%s: %d failed checks, %d validation messages\n", failures ? "FAILED" : "passed", failures,
                validation_messages);
    return failures ? 1 : 0;
}

} // namespace

int main() {
    try {
        return run();
    } catch (const std::exception& e) {
        std::printf("FAILED: %s\n", e.what());
        return 1;
    }
}
