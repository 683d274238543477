// rcx/vulkan.cpp: the compute harness of rcx/vulkan.hpp.
#include "rcx/vulkan.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>

// ---- AddressSanitizer builds: no shared object is ever unloaded ------------------------------------
// The Vulkan loader dlopen()s the drivers (ICDs), their dependencies (lavapipe: libLLVM) and the layers,
// and dlclose()s them in vkDestroyInstance and after probing them. Memory that such a module leaks is
// reported by LeakSanitizer at exit, when the module is gone: its frames read "<unknown module>" and no
// suppression can name them (or tell them from a leak in RayCache). So in ASan builds every dlopen() of
// the process goes through this one, which adds RTLD_NODELETE: modules stay mapped until exit, their
// frames are symbolized with the module's path, and tests/lsan_vulkan.supp suppresses exactly the
// driver's and loader's modules. libvulkan.so.1 references dlopen, so the linker exports this
// definition from the executable and the loader's calls bind to it; the sanitizer's own dlopen
// interceptor is reached through RTLD_NEXT.
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RCX_VK_KEEP_MODULES_LOADED 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) && defined(__GLIBC__)
#define RCX_VK_KEEP_MODULES_LOADED 1
#endif
#if defined(RCX_VK_KEEP_MODULES_LOADED) && defined(__GLIBC__)
#include <dlfcn.h>

extern "C" void* dlopen(const char* file, int mode) {
    using Dlopen = void* (*)(const char*, int);
    static const Dlopen next = reinterpret_cast<Dlopen>(dlsym(RTLD_NEXT, "dlopen"));
    return next(file, mode | RTLD_NODELETE);
}
#endif

namespace rcx::vk {

namespace {

void check(VkResult result, const char* what) {
    if (result != VK_SUCCESS) throw Error(std::string("rcx::vk: ") + what + " failed: " + to_string(result));
}

bool environment_says_off(const char* name) {
    const char* value = std::getenv(name);
    return value && (std::strcmp(value, "0") == 0 || std::strcmp(value, "off") == 0 || std::strcmp(value, "OFF") == 0);
}

bool has_layer(const char* name) {
    std::uint32_t count = 0;
    if (vkEnumerateInstanceLayerProperties(&count, nullptr) != VK_SUCCESS) return false;
    std::vector<VkLayerProperties> layers(count);
    if (vkEnumerateInstanceLayerProperties(&count, layers.data()) != VK_SUCCESS) return false;
    return std::any_of(layers.begin(), layers.end(), [&](const VkLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

bool has_instance_extension(const char* layer, const char* name) {
    std::uint32_t count = 0;
    if (vkEnumerateInstanceExtensionProperties(layer, &count, nullptr) != VK_SUCCESS) return false;
    std::vector<VkExtensionProperties> extensions(count);
    if (vkEnumerateInstanceExtensionProperties(layer, &count, extensions.data()) != VK_SUCCESS) return false;
    return std::any_of(extensions.begin(), extensions.end(),
                       [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

int queue_family_with_compute(VkPhysicalDevice device) {
    std::uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(device, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    vkGetPhysicalDeviceQueueFamilyProperties(device, &count, families.data());
    for (std::uint32_t i = 0; i < count; ++i)
        if (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) return static_cast<int>(i);
    return -1;
}

bool has_device_extension(VkPhysicalDevice device, const char* name) {
    std::uint32_t count = 0;
    if (vkEnumerateDeviceExtensionProperties(device, nullptr, &count, nullptr) != VK_SUCCESS) return false;
    std::vector<VkExtensionProperties> extensions(count);
    if (vkEnumerateDeviceExtensionProperties(device, nullptr, &count, extensions.data()) != VK_SUCCESS) return false;
    return std::any_of(extensions.begin(), extensions.end(),
                       [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

// Whether the device has shaderInt64 and shaderBufferInt64Atomics (core from 1.2, an extension before).
bool has_int64_atomics(VkPhysicalDevice device, std::uint32_t api_version) {
    if (api_version < VK_API_VERSION_1_2 && !has_device_extension(device, VK_KHR_SHADER_ATOMIC_INT64_EXTENSION_NAME))
        return false;
    VkPhysicalDeviceShaderAtomicInt64Features atomics{};
    atomics.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_INT64_FEATURES;
    VkPhysicalDeviceFeatures2 features{};
    features.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
    features.pNext = &atomics;
    vkGetPhysicalDeviceFeatures2(device, &features);
    return features.features.shaderInt64 && atomics.shaderBufferInt64Atomics;
}

// Higher is preferred when no name is asked for: lavapipe first (the device RayCache is tested on).
int preference(const VkPhysicalDeviceProperties& p) {
    if (std::strstr(p.deviceName, "llvmpipe")) return 5;
    switch (p.deviceType) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 4;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 3;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 1;
    default: return 0;
    }
}

} // namespace

std::string to_string(VkResult result) {
    switch (result) {
#define RCX_CASE(x) \
    case x: return #x;
        RCX_CASE(VK_SUCCESS)
        RCX_CASE(VK_NOT_READY)
        RCX_CASE(VK_TIMEOUT)
        RCX_CASE(VK_INCOMPLETE)
        RCX_CASE(VK_ERROR_OUT_OF_HOST_MEMORY)
        RCX_CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY)
        RCX_CASE(VK_ERROR_INITIALIZATION_FAILED)
        RCX_CASE(VK_ERROR_DEVICE_LOST)
        RCX_CASE(VK_ERROR_MEMORY_MAP_FAILED)
        RCX_CASE(VK_ERROR_LAYER_NOT_PRESENT)
        RCX_CASE(VK_ERROR_EXTENSION_NOT_PRESENT)
        RCX_CASE(VK_ERROR_FEATURE_NOT_PRESENT)
        RCX_CASE(VK_ERROR_INCOMPATIBLE_DRIVER)
        RCX_CASE(VK_ERROR_TOO_MANY_OBJECTS)
        RCX_CASE(VK_ERROR_FORMAT_NOT_SUPPORTED)
        RCX_CASE(VK_ERROR_FRAGMENTED_POOL)
        RCX_CASE(VK_ERROR_OUT_OF_POOL_MEMORY)
        RCX_CASE(VK_ERROR_INVALID_SHADER_NV)
#undef RCX_CASE
    default: return "VkResult " + std::to_string(static_cast<int>(result));
    }
}

// ---- Context ---------------------------------------------------------------------------------------

struct Context::Messenger {
    std::atomic<std::uint64_t> errors{0};
    std::mutex print;
};

namespace {

std::atomic<std::uint64_t> g_process_errors{0};

// Prints every warning and error; counts the errors of type VALIDATION (not, say, the loader's complaints
// about a driver manifest it cannot use, which say nothing about this program's use of Vulkan).
VKAPI_ATTR VkBool32 VKAPI_CALL on_debug_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                VkDebugUtilsMessageTypeFlagsEXT types,
                                                const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    auto* state = static_cast<Context::Messenger*>(user);
    const bool error = severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    const bool validation = types & VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
    if (error && validation) {
        state->errors.fetch_add(1, std::memory_order_relaxed);
        g_process_errors.fetch_add(1, std::memory_order_relaxed);
    }
    std::lock_guard<std::mutex> lock(state->print);
    std::fprintf(stderr, "[vulkan %s %s] %s\n", validation ? "validation" : (types & VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT) ? "performance" : "general",
                 error ? "error" : "warning", data && data->pMessage ? data->pMessage : "(no message)");
    return VK_FALSE;
}

VkDebugUtilsMessengerCreateInfoEXT messenger_info(Context::Messenger* state) {
    VkDebugUtilsMessengerCreateInfoEXT info{};
    info.sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT;
    info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    info.pfnUserCallback = on_debug_message;
    info.pUserData = state;
    return info;
}

} // namespace

Context::Context(const ContextOptions& options)
    : messenger_state_(new Messenger), buffer_memory_(options.buffer_memory) {
    // --- Instance.
    std::uint32_t loader_version = VK_API_VERSION_1_0;
    // vkEnumerateInstanceVersion is absent from 1.0 loaders; the loader exports it from 1.1 on.
    auto enumerate_version = reinterpret_cast<PFN_vkEnumerateInstanceVersion>(
        vkGetInstanceProcAddr(VK_NULL_HANDLE, "vkEnumerateInstanceVersion"));
    if (enumerate_version) enumerate_version(&loader_version);
    if (loader_version < VK_API_VERSION_1_1)
        throw NoDeviceError("rcx::vk: the Vulkan loader supports only Vulkan 1.0; 1.1 is needed");

    validation_ = options.validation && !environment_says_off("RCX_VULKAN_VALIDATION") &&
                  has_layer("VK_LAYER_KHRONOS_validation");
    const bool debug_utils = validation_ && (has_instance_extension(nullptr, VK_EXT_DEBUG_UTILS_EXTENSION_NAME) ||
                                             has_instance_extension("VK_LAYER_KHRONOS_validation",
                                                                    VK_EXT_DEBUG_UTILS_EXTENSION_NAME));
    std::vector<const char*> layers, extensions;
    if (validation_) layers.push_back("VK_LAYER_KHRONOS_validation");
    if (debug_utils) extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    if (validation_ && !debug_utils) {
        std::fprintf(stderr, "rcx::vk: validation layer without VK_EXT_debug_utils: errors are not counted\n");
    }

    VkApplicationInfo app{};
    app.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO;
    app.pApplicationName = "RayCache";
    app.pEngineName = "rcx::vk";
    app.apiVersion = VK_API_VERSION_1_2;
    VkDebugUtilsMessengerCreateInfoEXT debug_info = messenger_info(messenger_state_.get());
    VkInstanceCreateInfo instance_info{};
    instance_info.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO;
    instance_info.pNext = debug_utils ? &debug_info : nullptr; // also covers instance creation and destruction
    instance_info.pApplicationInfo = &app;
    instance_info.enabledLayerCount = static_cast<std::uint32_t>(layers.size());
    instance_info.ppEnabledLayerNames = layers.data();
    instance_info.enabledExtensionCount = static_cast<std::uint32_t>(extensions.size());
    instance_info.ppEnabledExtensionNames = extensions.data();
    const VkResult created = vkCreateInstance(&instance_info, nullptr, &instance_);
    if (created == VK_ERROR_INCOMPATIBLE_DRIVER || created == VK_ERROR_INITIALIZATION_FAILED)
        throw NoDeviceError("rcx::vk: no Vulkan driver (vkCreateInstance: " + to_string(created) + ")");
    check(created, "vkCreateInstance");

    try {
        if (debug_utils) {
            auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
                vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
            if (create) check(create(instance_, &debug_info, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
        }

        // --- Physical device: one with a compute queue and Vulkan 1.1.
        std::uint32_t count = 0;
        const VkResult enumerated = vkEnumeratePhysicalDevices(instance_, &count, nullptr);
        if (enumerated != VK_SUCCESS || count == 0) throw NoDeviceError("rcx::vk: no Vulkan device");
        std::vector<VkPhysicalDevice> devices(count);
        check(vkEnumeratePhysicalDevices(instance_, &count, devices.data()), "vkEnumeratePhysicalDevices");
        std::string wanted = options.device_name;
        if (wanted.empty() && std::getenv("RCX_VULKAN_DEVICE")) wanted = std::getenv("RCX_VULKAN_DEVICE");
        int best_score = -1;
        std::string seen;
        for (VkPhysicalDevice candidate : devices) {
            VkPhysicalDeviceProperties p;
            vkGetPhysicalDeviceProperties(candidate, &p);
            seen += std::string(seen.empty() ? "" : ", ") + p.deviceName;
            if (p.apiVersion < VK_API_VERSION_1_1 || queue_family_with_compute(candidate) < 0) continue;
            if (options.require_int64_atomics && !has_int64_atomics(candidate, p.apiVersion)) continue;
            const int score = wanted.empty() ? preference(p) : (std::strstr(p.deviceName, wanted.c_str()) ? 1 : -1);
            if (score > best_score) {
                best_score = score;
                physical_device_ = candidate;
                properties_ = p;
            }
        }
        if (!physical_device_)
            throw NoDeviceError("rcx::vk: no suitable Vulkan device (Vulkan 1.1, a compute queue" +
                                std::string(options.require_int64_atomics ? ", 64-bit buffer atomics" : "") +
                                (wanted.empty() ? std::string() : ", name containing '" + wanted + "'") +
                                ") among: " + (seen.empty() ? std::string("none") : seen));
        vkGetPhysicalDeviceMemoryProperties(physical_device_, &memory_properties_);
        queue_family_ = static_cast<std::uint32_t>(queue_family_with_compute(physical_device_));

        // --- Device, with 64-bit integers and 64-bit buffer atomics when the device has them (core in
        // Vulkan 1.2, VK_KHR_shader_atomic_int64 before).
        VkPhysicalDeviceFeatures supported{};
        vkGetPhysicalDeviceFeatures(physical_device_, &supported);
        int64_atomics_ = options.enable_int64 && has_int64_atomics(physical_device_, properties_.apiVersion);
        std::vector<const char*> device_extensions;
        if (int64_atomics_ && properties_.apiVersion < VK_API_VERSION_1_2)
            device_extensions.push_back(VK_KHR_SHADER_ATOMIC_INT64_EXTENSION_NAME);
        VkPhysicalDevicePipelineExecutablePropertiesFeaturesKHR executable_info{};
        executable_info.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PIPELINE_EXECUTABLE_PROPERTIES_FEATURES_KHR;
        if (options.shader_statistics && has_device_extension(physical_device_, VK_KHR_PIPELINE_EXECUTABLE_PROPERTIES_EXTENSION_NAME)) {
            VkPhysicalDeviceFeatures2 query{};
            query.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
            query.pNext = &executable_info;
            vkGetPhysicalDeviceFeatures2(physical_device_, &query);
            shader_statistics_ = executable_info.pipelineExecutableInfo == VK_TRUE;
            executable_info.pNext = nullptr;
            if (shader_statistics_) device_extensions.push_back(VK_KHR_PIPELINE_EXECUTABLE_PROPERTIES_EXTENSION_NAME);
        }

        VkPhysicalDeviceShaderAtomicInt64Features enable_atomics{};
        enable_atomics.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_INT64_FEATURES;
        enable_atomics.shaderBufferInt64Atomics = VK_TRUE;
        VkPhysicalDeviceFeatures2 enable{};
        enable.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
        enable.pNext = int64_atomics_ ? &enable_atomics : nullptr;
        if (shader_statistics_) { // pipelineExecutableInfo is VK_TRUE from the query above
            executable_info.pNext = enable.pNext;
            enable.pNext = &executable_info;
        }
        enable.features.shaderInt64 = int64_atomics_;
        enable.features.fragmentStoresAndAtomics = supported.fragmentStoresAndAtomics;

        const float priority = 1.0f;
        VkDeviceQueueCreateInfo queue_info{};
        queue_info.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO;
        queue_info.queueFamilyIndex = queue_family_;
        queue_info.queueCount = 1;
        queue_info.pQueuePriorities = &priority;
        VkDeviceCreateInfo device_info{};
        device_info.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO;
        device_info.pNext = &enable;
        device_info.queueCreateInfoCount = 1;
        device_info.pQueueCreateInfos = &queue_info;
        device_info.enabledExtensionCount = static_cast<std::uint32_t>(device_extensions.size());
        device_info.ppEnabledExtensionNames = device_extensions.data();
        check(vkCreateDevice(physical_device_, &device_info, nullptr, &device_), "vkCreateDevice");
        vkGetDeviceQueue(device_, queue_family_, 0, &queue_);

        VkCommandPoolCreateInfo pool_info{};
        pool_info.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
        pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
        pool_info.queueFamilyIndex = queue_family_;
        check(vkCreateCommandPool(device_, &pool_info, nullptr, &command_pool_), "vkCreateCommandPool");
    } catch (...) {
        destroy();
        throw;
    }
}

Context::~Context() { destroy(); }

void Context::destroy() noexcept {
    if (device_) {
        vkDeviceWaitIdle(device_);
        if (command_pool_) vkDestroyCommandPool(device_, command_pool_, nullptr);
        vkDestroyDevice(device_, nullptr);
        device_ = VK_NULL_HANDLE;
    }
    if (instance_) {
        if (messenger_) {
            auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
                vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
            if (destroy) destroy(instance_, messenger_, nullptr);
            messenger_ = VK_NULL_HANDLE;
        }
        vkDestroyInstance(instance_, nullptr);
        instance_ = VK_NULL_HANDLE;
    }
}

std::uint64_t validation_errors_in_process() noexcept { return g_process_errors.load(std::memory_order_relaxed); }

std::uint64_t Context::validation_errors() const noexcept {
    return messenger_state_->errors.load(std::memory_order_relaxed);
}

std::uint32_t Context::memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags flags) const {
    for (std::uint32_t i = 0; i < memory_properties_.memoryTypeCount; ++i)
        if ((type_bits & (1u << i)) && (memory_properties_.memoryTypes[i].propertyFlags & flags) == flags) return i;
    throw Error("rcx::vk: no memory type with flags " + std::to_string(flags) + " on " + device_name());
}

VkDescriptorPool Context::make_descriptor_pool() {
    const VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 16},
                                          {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 4},
                                          {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 4}};
    VkDescriptorPoolCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO;
    info.maxSets = 1;
    info.poolSizeCount = 3;
    info.pPoolSizes = sizes;
    VkDescriptorPool pool = VK_NULL_HANDLE;
    check(vkCreateDescriptorPool(device_, &info, nullptr, &pool), "vkCreateDescriptorPool");
    return pool;
}

void Context::submit(const std::function<void(Commands&)>& record) {
    VkCommandBufferAllocateInfo allocate{};
    allocate.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
    allocate.commandPool = command_pool_;
    allocate.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    allocate.commandBufferCount = 1;
    VkCommandBuffer command_buffer = VK_NULL_HANDLE;
    check(vkAllocateCommandBuffers(device_, &allocate, &command_buffer), "vkAllocateCommandBuffers");
    Commands commands(*this, command_buffer);
    VkFence fence = VK_NULL_HANDLE;
    auto cleanup = [&] {
        if (fence) vkDestroyFence(device_, fence, nullptr);
        for (VkDescriptorPool pool : commands.pools_) vkDestroyDescriptorPool(device_, pool, nullptr);
        vkFreeCommandBuffers(device_, command_pool_, 1, &command_buffer);
    };
    try {
        VkCommandBufferBeginInfo begin{};
        begin.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        check(vkBeginCommandBuffer(command_buffer, &begin), "vkBeginCommandBuffer");
        record(commands);
        // Make every write visible to the host, which reads the mapped buffers next.
        VkMemoryBarrier to_host{};
        to_host.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER;
        to_host.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
        to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
        vkCmdPipelineBarrier(command_buffer, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                             VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0, nullptr, 0, nullptr);
        check(vkEndCommandBuffer(command_buffer), "vkEndCommandBuffer");

        VkFenceCreateInfo fence_info{};
        fence_info.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
        check(vkCreateFence(device_, &fence_info, nullptr, &fence), "vkCreateFence");
        VkSubmitInfo submit_info{};
        submit_info.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
        submit_info.commandBufferCount = 1;
        submit_info.pCommandBuffers = &command_buffer;
        check(vkQueueSubmit(queue_, 1, &submit_info, fence), "vkQueueSubmit");
        ++submissions_;
        check(vkWaitForFences(device_, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
    } catch (...) {
        vkQueueWaitIdle(queue_);
        cleanup();
        throw;
    }
    cleanup();
}

void Context::dispatch(const ComputePipeline& pipeline, std::initializer_list<Resource> resources, const void* push,
                       std::uint32_t push_bytes, std::uint32_t groups_x, std::uint32_t groups_y,
                       std::uint32_t groups_z) {
    submit([&](Commands& c) { c.dispatch(pipeline, resources, push, push_bytes, groups_x, groups_y, groups_z); });
}

// ---- Commands --------------------------------------------------------------------------------------

void Commands::dispatch(const ComputePipeline& pipeline, std::initializer_list<Resource> resources, const void* push,
                        std::uint32_t push_bytes, std::uint32_t groups_x, std::uint32_t groups_y,
                        std::uint32_t groups_z) {
    const std::uint32_t* limit = context_.properties().limits.maxComputeWorkGroupCount;
    if (groups_x > limit[0] || groups_y > limit[1] || groups_z > limit[2])
        throw Error("rcx::vk: dispatch of " + std::to_string(groups_x) + " x " + std::to_string(groups_y) + " x " +
                    std::to_string(groups_z) + " groups exceeds the device's maxComputeWorkGroupCount");
    bind(pipeline, resources, push, push_bytes);
    vkCmdDispatch(command_buffer_, groups_x, groups_y, groups_z);
}

void Commands::dispatch_indirect(const ComputePipeline& pipeline, std::initializer_list<Resource> resources,
                                 const void* push, std::uint32_t push_bytes, const Buffer& args, VkDeviceSize offset) {
    if (offset % 4 != 0 || offset + 12 > args.size())
        throw Error("rcx::vk: dispatch_indirect: arguments at offset " + std::to_string(offset) +
                    " are not 3 aligned uints inside the buffer");
    bind(pipeline, resources, push, push_bytes);
    vkCmdDispatchIndirect(command_buffer_, args.handle(), offset);
}

void Commands::bind(const ComputePipeline& pipeline, std::initializer_list<Resource> resources, const void* push,
                    std::uint32_t push_bytes) {
    if (resources.size() != pipeline.bindings().size())
        throw Error("rcx::vk: dispatch given " + std::to_string(resources.size()) + " resources for a pipeline with " +
                    std::to_string(pipeline.bindings().size()) + " bindings");
    if (push_bytes != pipeline.push_constant_bytes())
        throw Error("rcx::vk: dispatch given " + std::to_string(push_bytes) + " bytes of push constants, pipeline takes " +
                    std::to_string(pipeline.push_constant_bytes()));
    VkDescriptorPool pool = context_.make_descriptor_pool();
    pools_.push_back(pool);
    VkDescriptorSetLayout set_layout = pipeline.set_layout();
    VkDescriptorSetAllocateInfo allocate{};
    allocate.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO;
    allocate.descriptorPool = pool;
    allocate.descriptorSetCount = 1;
    allocate.pSetLayouts = &set_layout;
    VkDescriptorSet set = VK_NULL_HANDLE;
    check(vkAllocateDescriptorSets(context_.device(), &allocate, &set), "vkAllocateDescriptorSets");

    std::vector<VkDescriptorBufferInfo> buffers(resources.size());
    std::vector<VkDescriptorImageInfo> images(resources.size());
    std::vector<VkWriteDescriptorSet> writes(resources.size());
    std::uint32_t binding = 0;
    for (const Resource& r : resources) {
        const VkDescriptorType type = pipeline.bindings()[binding];
        VkWriteDescriptorSet& w = writes[binding];
        w.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
        w.dstSet = set;
        w.dstBinding = binding;
        w.descriptorCount = 1;
        w.descriptorType = type;
        if (type == VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER) {
            if (!r.image) throw Error("rcx::vk: binding " + std::to_string(binding) + " needs a SampledCubeImage");
            images[binding] = {r.image->sampler(), r.image->view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
            w.pImageInfo = &images[binding];
        } else {
            if (!r.buffer) throw Error("rcx::vk: binding " + std::to_string(binding) + " needs a Buffer");
            if (type == VK_DESCRIPTOR_TYPE_STORAGE_BUFFER &&
                r.buffer->size() > context_.properties().limits.maxStorageBufferRange)
                throw Error("rcx::vk: a buffer of " + std::to_string(r.buffer->size()) + " bytes at binding " +
                            std::to_string(binding) + " exceeds maxStorageBufferRange (" +
                            std::to_string(context_.properties().limits.maxStorageBufferRange) + ") on " +
                            context_.device_name());
            buffers[binding] = {r.buffer->handle(), 0, VK_WHOLE_SIZE};
            w.pBufferInfo = &buffers[binding];
        }
        ++binding;
    }
    vkUpdateDescriptorSets(context_.device(), static_cast<std::uint32_t>(writes.size()), writes.data(), 0, nullptr);

    vkCmdBindPipeline(command_buffer_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.handle());
    vkCmdBindDescriptorSets(command_buffer_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.layout(), 0, 1, &set, 0, nullptr);
    if (push_bytes)
        vkCmdPushConstants(command_buffer_, pipeline.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, push_bytes, push);
}

void Commands::barrier() {
    VkMemoryBarrier b{};
    b.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER;
    b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                      VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_INDIRECT_COMMAND_READ_BIT;
    const VkPipelineStageFlags stages = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
    vkCmdPipelineBarrier(command_buffer_, stages, stages | VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT, 0, 1, &b, 0, nullptr, 0,
                         nullptr);
}

void Commands::fill(const Buffer& buffer, std::uint32_t word) {
    vkCmdFillBuffer(command_buffer_, buffer.handle(), 0, VK_WHOLE_SIZE, word);
}

// ---- Buffer ----------------------------------------------------------------------------------------

std::string memory_description(VkMemoryPropertyFlags flags) {
    static const std::pair<VkMemoryPropertyFlags, const char*> names[] = {
        {VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, "device-local"},   {VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT, "host-visible"},
        {VK_MEMORY_PROPERTY_HOST_COHERENT_BIT, "host-coherent"}, {VK_MEMORY_PROPERTY_HOST_CACHED_BIT, "host-cached"},
        {VK_MEMORY_PROPERTY_LAZILY_ALLOCATED_BIT, "lazily allocated"}};
    std::string text;
    for (const auto& [bit, name] : names)
        if (flags & bit) text += (text.empty() ? "" : ", ") + std::string(name);
    return text.empty() ? "no-property" : text;
}

std::vector<std::uint32_t> buffer_memory_types(const VkPhysicalDeviceMemoryProperties& memory, std::uint32_t type_bits,
                                               BufferUse use, BufferMemory preference) {
    const VkMemoryPropertyFlags mappable = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    VkMemoryPropertyFlags first = 0; // the flag that puts a type in the first group
    if (use == BufferUse::readback || preference == BufferMemory::host_cached) first = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
    else if (preference == BufferMemory::device_local) first = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
    std::vector<std::uint32_t> preferred, others;
    for (std::uint32_t i = 0; i < memory.memoryTypeCount && i < 32; ++i) {
        const VkMemoryPropertyFlags flags = memory.memoryTypes[i].propertyFlags;
        if (!(type_bits & (1u << i)) || (flags & mappable) != mappable) continue;
        (first && (flags & first) ? preferred : others).push_back(i);
    }
    preferred.insert(preferred.end(), others.begin(), others.end());
    return preferred;
}

Buffer::Buffer(Context& context, VkDeviceSize bytes, BufferUse use) : device_(context.device()), size_(bytes) {
    if (bytes == 0) throw Error("rcx::vk: a Buffer needs at least 1 byte");
    VkBufferCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
    info.size = bytes;
    info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                 VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    check(vkCreateBuffer(device_, &info, nullptr, &buffer_), "vkCreateBuffer");
    try {
        VkMemoryRequirements needs;
        vkGetBufferMemoryRequirements(device_, buffer_, &needs);
        const std::vector<std::uint32_t> types =
            buffer_memory_types(context.memory_properties(), needs.memoryTypeBits, use, context.buffer_memory());
        if (types.empty())
            throw Error("rcx::vk: no host-visible, host-coherent memory type for a buffer on " + context.device_name());
        VkMemoryAllocateInfo allocate{};
        allocate.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
        allocate.allocationSize = needs.size;
        VkResult result = VK_ERROR_OUT_OF_DEVICE_MEMORY;
        for (const std::uint32_t type : types) {
            allocate.memoryTypeIndex = type;
            result = vkAllocateMemory(device_, &allocate, nullptr, &memory_);
            if (result != VK_SUCCESS) memory_ = VK_NULL_HANDLE;
            // A full heap (a small PCI window onto device memory, say) sends the buffer to the next type.
            if (result != VK_ERROR_OUT_OF_DEVICE_MEMORY && result != VK_ERROR_OUT_OF_HOST_MEMORY) break;
        }
        check(result, "vkAllocateMemory (buffer)");
        memory_flags_ = context.memory_properties().memoryTypes[allocate.memoryTypeIndex].propertyFlags;
        check(vkBindBufferMemory(device_, buffer_, memory_, 0), "vkBindBufferMemory");
        check(vkMapMemory(device_, memory_, 0, VK_WHOLE_SIZE, 0, &mapped_), "vkMapMemory");
    } catch (...) {
        release();
        throw;
    }
}

Buffer::~Buffer() { release(); }

Buffer::Buffer(Buffer&& other) noexcept
    : device_(other.device_), buffer_(other.buffer_), memory_(other.memory_), size_(other.size_), mapped_(other.mapped_),
      memory_flags_(other.memory_flags_) {
    other.buffer_ = VK_NULL_HANDLE;
    other.memory_ = VK_NULL_HANDLE;
    other.mapped_ = nullptr;
    other.size_ = 0;
}

Buffer& Buffer::operator=(Buffer&& other) noexcept {
    if (this != &other) {
        release();
        device_ = other.device_;
        buffer_ = other.buffer_;
        memory_ = other.memory_;
        size_ = other.size_;
        mapped_ = other.mapped_;
        memory_flags_ = other.memory_flags_;
        other.buffer_ = VK_NULL_HANDLE;
        other.memory_ = VK_NULL_HANDLE;
        other.mapped_ = nullptr;
        other.size_ = 0;
    }
    return *this;
}

void Buffer::release() noexcept {
    if (mapped_) vkUnmapMemory(device_, memory_);
    if (buffer_) vkDestroyBuffer(device_, buffer_, nullptr);
    if (memory_) vkFreeMemory(device_, memory_, nullptr);
    mapped_ = nullptr;
    buffer_ = VK_NULL_HANDLE;
    memory_ = VK_NULL_HANDLE;
}

void Buffer::upload(const void* source, std::size_t bytes) {
    if (bytes > size_)
        throw Error("rcx::vk: upload of " + std::to_string(bytes) + " bytes into a buffer of " + std::to_string(size_));
    std::memcpy(mapped_, source, bytes);
}

void Buffer::fill(std::uint32_t word) noexcept {
    std::uint32_t* words = as<std::uint32_t>();
    std::fill(words, words + size_ / 4, word);
}

// ---- images --------------------------------------------------------------------------------------

void create_image(Context& context, const ImageDescription& d, VkImage& image, VkDeviceMemory& memory, VkImageView& view) {
    const VkDevice device = context.device();
    VkImageCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO;
    info.flags = d.flags;
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = d.format;
    info.extent = {d.width, d.height, 1};
    info.mipLevels = 1;
    info.arrayLayers = d.layers;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = d.usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    check(vkCreateImage(device, &info, nullptr, &image), "vkCreateImage");
    VkMemoryRequirements needs;
    vkGetImageMemoryRequirements(device, image, &needs);
    VkMemoryAllocateInfo allocate{};
    allocate.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
    allocate.allocationSize = needs.size;
    allocate.memoryTypeIndex = context.memory_type(needs.memoryTypeBits, d.memory);
    check(vkAllocateMemory(device, &allocate, nullptr, &memory), "vkAllocateMemory (image)");
    check(vkBindImageMemory(device, image, memory, 0), "vkBindImageMemory");
    VkImageViewCreateInfo view_info{};
    view_info.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO;
    view_info.image = image;
    view_info.viewType = d.view_type;
    view_info.format = d.format;
    view_info.subresourceRange = {d.aspect, 0, 1, 0, d.layers};
    check(vkCreateImageView(device, &view_info, nullptr, &view), "vkCreateImageView");
}

// ---- SampledCubeImage ------------------------------------------------------------------------------

bool SampledCubeImage::supports_linear_filter(const Context& context, VkFormat format) {
    VkFormatProperties properties{};
    vkGetPhysicalDeviceFormatProperties(context.physical_device(), format, &properties);
    return (properties.optimalTilingFeatures & VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT) != 0;
}

SampledCubeImage::SampledCubeImage(Context& context, std::uint32_t face_size, VkFormat format, VkFilter filter)
    : context_(context), face_size_(face_size) {
    if (face_size == 0 || face_size > context.properties().limits.maxImageDimensionCube)
        throw Error("rcx::vk: cube face size " + std::to_string(face_size) + " outside 1.." +
                    std::to_string(context.properties().limits.maxImageDimensionCube) + " on " + context.device_name());
    if (filter == VK_FILTER_LINEAR && !supports_linear_filter(context, format))
        throw Error("rcx::vk: " + context.device_name() + " cannot filter format " + std::to_string(format) +
                    " linearly");
    const VkDevice device = context.device();
    try {
        ImageDescription cube;
        cube.format = format;
        cube.width = cube.height = face_size;
        cube.layers = 6;
        cube.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
        cube.flags = VK_IMAGE_CREATE_CUBE_COMPATIBLE_BIT;
        cube.view_type = VK_IMAGE_VIEW_TYPE_CUBE;
        create_image(context, cube, image_, memory_, view_);

        VkSamplerCreateInfo sampler{};
        sampler.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO;
        sampler.magFilter = filter;
        sampler.minFilter = filter;
        sampler.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
        sampler.addressModeU = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
        sampler.addressModeV = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
        sampler.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
        sampler.maxLod = 0.0f;
        check(vkCreateSampler(device, &sampler, nullptr, &sampler_), "vkCreateSampler");
    } catch (...) {
        destroy();
        throw;
    }
}

SampledCubeImage::~SampledCubeImage() { destroy(); }

void SampledCubeImage::destroy() noexcept {
    const VkDevice device = context_.device();
    if (sampler_) vkDestroySampler(device, sampler_, nullptr);
    if (view_) vkDestroyImageView(device, view_, nullptr);
    if (image_) vkDestroyImage(device, image_, nullptr);
    if (memory_) vkFreeMemory(device, memory_, nullptr);
    sampler_ = VK_NULL_HANDLE;
    view_ = VK_NULL_HANDLE;
    image_ = VK_NULL_HANDLE;
    memory_ = VK_NULL_HANDLE;
}

void SampledCubeImage::upload(const void* texels, std::size_t bytes) {
    const std::size_t expected = std::size_t{6} * face_size_ * face_size_ * 4;
    if (bytes != expected)
        throw Error("rcx::vk: cube upload of " + std::to_string(bytes) + " bytes, expected 6 * N^2 * 4 = " +
                    std::to_string(expected));
    Buffer staging(context_, bytes);
    staging.upload(texels, bytes);
    context_.submit([&](Commands& c) {
        VkImageMemoryBarrier to_transfer{};
        to_transfer.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER;
        to_transfer.srcAccessMask = 0;
        to_transfer.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        to_transfer.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        to_transfer.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
        to_transfer.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        to_transfer.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        to_transfer.image = image_;
        to_transfer.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 6};
        vkCmdPipelineBarrier(c.handle(), VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0,
                             nullptr, 0, nullptr, 1, &to_transfer);
        VkBufferImageCopy region{};
        region.bufferOffset = 0;
        region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 6};
        region.imageExtent = {face_size_, face_size_, 1};
        vkCmdCopyBufferToImage(c.handle(), staging.handle(), image_, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
        VkImageMemoryBarrier to_shader = to_transfer;
        to_shader.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        to_shader.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
        to_shader.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
        to_shader.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
        vkCmdPipelineBarrier(c.handle(), VK_PIPELINE_STAGE_TRANSFER_BIT,
                             VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, 0, 0, nullptr,
                             0, nullptr, 1, &to_shader);
    });
}

// ---- Timestamps ------------------------------------------------------------------------------------

Timestamps::Timestamps(Context& context, std::uint32_t count) : device_(context.device()), count_(count) {
    if (count == 0 || !context.properties().limits.timestampComputeAndGraphics) return;
    std::uint32_t families = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device(), &families, nullptr);
    std::vector<VkQueueFamilyProperties> properties(families);
    vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device(), &families, properties.data());
    const std::uint32_t bits = context.queue_family() < families ? properties[context.queue_family()].timestampValidBits : 0;
    if (bits == 0) return;
    VkQueryPoolCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO;
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = count;
    if (vkCreateQueryPool(device_, &info, nullptr, &pool_) != VK_SUCCESS) pool_ = VK_NULL_HANDLE;
    valid_mask_ = bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;
    nanoseconds_per_tick_ = context.properties().limits.timestampPeriod;
}

Timestamps::~Timestamps() {
    if (pool_) vkDestroyQueryPool(device_, pool_, nullptr);
}

void Timestamps::reset(Commands& commands) noexcept {
    if (pool_) vkCmdResetQueryPool(commands.handle(), pool_, 0, count_);
}

void Timestamps::write(Commands& commands, std::uint32_t index) noexcept {
    if (pool_ && index < count_) vkCmdWriteTimestamp(commands.handle(), VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool_, index);
}

std::vector<std::uint64_t> Timestamps::ticks(std::uint32_t n) const {
    std::vector<std::uint64_t> t(std::min(n, count_));
    if (!pool_ || t.empty()) return {};
    if (vkGetQueryPoolResults(device_, pool_, 0, static_cast<std::uint32_t>(t.size()), t.size() * sizeof(std::uint64_t), t.data(),
                              sizeof(std::uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) != VK_SUCCESS)
        return {};
    for (std::uint64_t& v : t) v &= valid_mask_;
    return t;
}

// ---- ComputePipeline -------------------------------------------------------------------------------

std::vector<std::uint32_t> read_spirv(const std::string& path) {
    std::ifstream file(path, std::ios::binary | std::ios::ate);
    if (!file)
        throw Error("rcx::vk: SPIR-V file '" + path + "' not found or unreadable (shaders are compiled at build time: "
                    "was the project built, and the shader listed in raycache_add_glsl_shader()?)");
    const std::streamsize bytes = file.tellg();
    if (bytes < 20 || bytes % 4 != 0)
        throw Error("rcx::vk: '" + path + "' is not SPIR-V (" + std::to_string(bytes) + " bytes)");
    std::vector<std::uint32_t> words(static_cast<std::size_t>(bytes) / 4);
    file.seekg(0);
    if (!file.read(reinterpret_cast<char*>(words.data()), bytes)) throw Error("rcx::vk: could not read '" + path + "'");
    if (words[0] != 0x07230203u) throw Error("rcx::vk: '" + path + "' is not SPIR-V (bad magic number)");
    return words;
}

VkShaderModule create_shader_module(Context& context, const std::string& path) {
    const std::vector<std::uint32_t> code = read_spirv(path);
    VkShaderModuleCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO;
    info.codeSize = code.size() * 4;
    info.pCode = code.data();
    VkShaderModule module = VK_NULL_HANDLE;
    check(vkCreateShaderModule(context.device(), &info, nullptr, &module), ("vkCreateShaderModule(" + path + ")").c_str());
    return module;
}

std::vector<std::string> ComputePipeline::statistics() const {
    std::vector<std::string> out;
    if (!context_.shader_statistics()) return out;
    // A report, not a frame's work: a failure is named in the list rather than thrown.
    auto failed = [&out](const char* call, VkResult result) {
        out.push_back(std::string("(") + call + ": " + to_string(result) + ")");
        return out;
    };
    const VkDevice device = context_.device();
    const auto executables = reinterpret_cast<PFN_vkGetPipelineExecutablePropertiesKHR>(
        vkGetDeviceProcAddr(device, "vkGetPipelineExecutablePropertiesKHR"));
    const auto statistics = reinterpret_cast<PFN_vkGetPipelineExecutableStatisticsKHR>(
        vkGetDeviceProcAddr(device, "vkGetPipelineExecutableStatisticsKHR"));
    if (!executables || !statistics) return failed("vkGetDeviceProcAddr", VK_ERROR_EXTENSION_NOT_PRESENT);
    VkPipelineInfoKHR pipeline{};
    pipeline.sType = VK_STRUCTURE_TYPE_PIPELINE_INFO_KHR;
    pipeline.pipeline = pipeline_;
    std::uint32_t executable_count = 0;
    if (const VkResult r = executables(device, &pipeline, &executable_count, nullptr); r != VK_SUCCESS)
        return failed("vkGetPipelineExecutablePropertiesKHR", r);
    for (std::uint32_t e = 0; e < executable_count; ++e) {
        VkPipelineExecutableInfoKHR which{};
        which.sType = VK_STRUCTURE_TYPE_PIPELINE_EXECUTABLE_INFO_KHR;
        which.pipeline = pipeline_;
        which.executableIndex = e;
        std::uint32_t count = 0;
        if (const VkResult r = statistics(device, &which, &count, nullptr); r != VK_SUCCESS)
            return failed("vkGetPipelineExecutableStatisticsKHR", r);
        std::vector<VkPipelineExecutableStatisticKHR> values(count);
        for (VkPipelineExecutableStatisticKHR& v : values) v.sType = VK_STRUCTURE_TYPE_PIPELINE_EXECUTABLE_STATISTIC_KHR;
        if (const VkResult r = statistics(device, &which, &count, values.data()); r != VK_SUCCESS && r != VK_INCOMPLETE)
            return failed("vkGetPipelineExecutableStatisticsKHR", r);
        for (std::uint32_t i = 0; i < count; ++i) {
            const VkPipelineExecutableStatisticKHR& v = values[i];
            std::string value;
            switch (v.format) {
            case VK_PIPELINE_EXECUTABLE_STATISTIC_FORMAT_BOOL32_KHR: value = v.value.b32 ? "true" : "false"; break;
            case VK_PIPELINE_EXECUTABLE_STATISTIC_FORMAT_INT64_KHR: value = std::to_string(v.value.i64); break;
            case VK_PIPELINE_EXECUTABLE_STATISTIC_FORMAT_UINT64_KHR: value = std::to_string(v.value.u64); break;
            default: value = std::to_string(v.value.f64); break;
            }
            out.push_back(std::string(v.name) + " " + value);
        }
    }
    return out;
}

ComputePipeline::ComputePipeline(Context& context, const std::string& spirv_path, std::vector<VkDescriptorType> bindings,
                                 std::uint32_t push_constant_bytes)
    : context_(context), bindings_(std::move(bindings)), push_constant_bytes_(push_constant_bytes) {
    const VkDevice device = context.device();
    VkShaderModule module = create_shader_module(context, spirv_path); // a missing or bad file: nothing made yet
    try {
        std::vector<VkDescriptorSetLayoutBinding> layout_bindings(bindings_.size());
        for (std::uint32_t i = 0; i < bindings_.size(); ++i)
            layout_bindings[i] = {i, bindings_[i], 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
        VkDescriptorSetLayoutCreateInfo set_info{};
        set_info.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO;
        set_info.bindingCount = static_cast<std::uint32_t>(layout_bindings.size());
        set_info.pBindings = layout_bindings.data();
        check(vkCreateDescriptorSetLayout(device, &set_info, nullptr, &set_layout_), "vkCreateDescriptorSetLayout");

        VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, push_constant_bytes_};
        VkPipelineLayoutCreateInfo layout_info{};
        layout_info.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO;
        layout_info.setLayoutCount = 1;
        layout_info.pSetLayouts = &set_layout_;
        layout_info.pushConstantRangeCount = push_constant_bytes_ ? 1 : 0;
        layout_info.pPushConstantRanges = &range;
        check(vkCreatePipelineLayout(device, &layout_info, nullptr, &layout_), "vkCreatePipelineLayout");

        VkComputePipelineCreateInfo pipeline_info{};
        pipeline_info.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO;
        pipeline_info.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
        pipeline_info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
        pipeline_info.stage.module = module;
        pipeline_info.stage.pName = "main";
        pipeline_info.layout = layout_;
        if (context.shader_statistics()) pipeline_info.flags |= VK_PIPELINE_CREATE_CAPTURE_STATISTICS_BIT_KHR;
        check(vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &pipeline_info, nullptr, &pipeline_),
              ("vkCreateComputePipelines(" + spirv_path + ")").c_str());
        vkDestroyShaderModule(device, module, nullptr);
    } catch (...) {
        if (module) vkDestroyShaderModule(device, module, nullptr);
        destroy();
        throw;
    }
}

ComputePipeline::~ComputePipeline() { destroy(); }

void ComputePipeline::destroy() noexcept {
    const VkDevice device = context_.device();
    if (pipeline_) vkDestroyPipeline(device, pipeline_, nullptr);
    if (layout_) vkDestroyPipelineLayout(device, layout_, nullptr);
    if (set_layout_) vkDestroyDescriptorSetLayout(device, set_layout_, nullptr);
    pipeline_ = VK_NULL_HANDLE;
    layout_ = VK_NULL_HANDLE;
    set_layout_ = VK_NULL_HANDLE;
}

} // namespace rcx::vk
