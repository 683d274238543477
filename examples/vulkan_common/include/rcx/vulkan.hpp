// rcx/vulkan.hpp: a tiny Vulkan compute harness for RayCache's GLSL tests and its Vulkan example tracer.
//
// One Context (instance, one device with a compute queue, validation when installed), host-visible
// storage buffers (in the memory ContextOptions::buffer_memory prefers), compute pipelines loaded from SPIR-V files, a sampled cube image, and submissions
// that record dispatches and wait for them. Everything is synchronous and single-threaded: made for
// tests and small tracers, not for a renderer's frame loop.
//
// Errors: NoDeviceError when Vulkan or a usable device is missing (tests turn it into exit code 77,
// "skipped"); Error for any other failure, with the Vulkan call and VkResult in the message.
//
// AddressSanitizer builds: linking this harness makes every dlopen() of the process keep its module loaded
// until exit (RTLD_NODELETE), so that LeakSanitizer can name the Vulkan driver's frames (see vulkan.cpp and
// cmake/lsan_vulkan.supp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
#include <stdexcept>
#include <string>
#include <algorithm>
#include <vector>

#include <vulkan/vulkan.h>

namespace rcx::vk {

// Thrown when there is no Vulkan loader, no driver, or no device with a compute queue.
struct NoDeviceError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Thrown for every other failure (a Vulkan call that fails, a missing SPIR-V file, bad arguments).
struct Error : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// The name of a VkResult ("VK_ERROR_OUT_OF_DEVICE_MEMORY"), or its number.
std::string to_string(VkResult result);

// What a buffer is for, which chooses its memory. Every Buffer stays mapped whatever its memory, so the
// host can always read and write it; the choice only decides who pays for the distance.
enum class BufferUse {
    device,   // read and written by shaders; the host writes it at set-up and reads it now and then
    readback, // read by the host after most frames (a rendered image): host-cached memory first
};

// Which memory type a BufferUse::device buffer prefers (on a CPU device such as lavapipe all are one).
// On a discrete GPU, measured on an NVIDIA H200 (docs/RESULTS.md): its shaders read the small scenes of the
// examples as fast from host memory as from its own, while the host reads device memory across the bus
// uncached, so resizing cubes (which reads them on the host) took seconds there.
enum class BufferMemory {
    host,         // the first host-visible, host-coherent type, as the harness always took
    host_cached,  // host-cached host memory first: host reads at memory speed
    device_local, // device-local memory that the host can map first (PCI window, resizable BAR; small heaps
                  // that fill send further buffers to the next type)
};

struct ContextOptions {
    // Enable VK_LAYER_KHRONOS_validation when it is installed (environment RCX_VULKAN_VALIDATION=0
    // turns it off). Warnings and errors are printed to stderr; errors of type VALIDATION are counted
    // (Context::validation_errors()).
    bool validation = true;
    // Device choice: the first whose name contains this text; empty: the environment variable
    // RCX_VULKAN_DEVICE, else lavapipe (llvmpipe) if present, else a discrete, integrated, other GPU.
    std::string device_name;
    // Fail with NoDeviceError unless the device has shaderInt64 and shaderBufferInt64Atomics
    // (RayCache's CDCT stores need them). Either way they are enabled when supported.
    bool require_int64_atomics = false;
    // false: never enable shaderInt64 and shaderBufferInt64Atomics, so that a test can check that a shader
    // needs neither (the validation layer then reports a shader that declares Int64).
    bool enable_int64 = true;
    // Where buffers of BufferUse::device go (BufferMemory).
    BufferMemory buffer_memory = BufferMemory::host;
    // Let compute pipelines report the driver's statistics of their compiled code (registers, memory,
    // instructions: ComputePipeline::statistics()) where the device has VK_KHR_pipeline_executable_properties.
    bool shader_statistics = false;
};

// "device-local, host-visible, host-coherent" and so on: the property flags' names, for messages.
std::string memory_description(VkMemoryPropertyFlags flags);

// The memory types a buffer of `use` may be placed in, best first, among `type_bits` (a
// VkMemoryRequirements::memoryTypeBits) of the device described by `memory`; all are host-visible and
// host-coherent, in index order except that the preferred ones come first: HOST_CACHED for readback and
// host_cached, DEVICE_LOCAL for device_local, none for host. Empty when no allowed type is host-visible and
// host-coherent.
std::vector<std::uint32_t> buffer_memory_types(const VkPhysicalDeviceMemoryProperties& memory, std::uint32_t type_bits,
                                               BufferUse use, BufferMemory preference);

class Context;
class ComputePipeline;

// A storage buffer in host-visible, host-coherent memory, mapped for its whole life.
class Buffer {
public:
    // `bytes` > 0. Usage: storage, indirect dispatch arguments, transfer source and destination. Memory:
    // the first of buffer_memory_types(...) that the allocation succeeds in (Error if none does).
    Buffer(Context& context, VkDeviceSize bytes, BufferUse use = BufferUse::device);
    ~Buffer();
    Buffer(Buffer&& other) noexcept;
    Buffer& operator=(Buffer&& other) noexcept;
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;

    VkBuffer handle() const noexcept { return buffer_; }
    VkDeviceSize size() const noexcept { return size_; }
    void* data() const noexcept { return mapped_; }
    template <class T>
    T* as() const noexcept { return static_cast<T*>(mapped_); }
    // Copies `bytes` from `source` to the start of the buffer (bytes <= size(), else Error).
    void upload(const void* source, std::size_t bytes);
    // Sets every 32-bit word of the buffer to `word` (on the host).
    void fill(std::uint32_t word) noexcept;
    // The property flags of the memory type the buffer was placed in.
    VkMemoryPropertyFlags memory_flags() const noexcept { return memory_flags_; }

private:
    void release() noexcept;
    VkDevice device_ = VK_NULL_HANDLE;
    VkBuffer buffer_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    VkDeviceSize size_ = 0;
    void* mapped_ = nullptr;
    VkMemoryPropertyFlags memory_flags_ = 0;
};

// A buffer holding a copy of `values`, at least `min_bytes` long (a Vulkan buffer cannot be empty).
template <class T>
Buffer buffer_of(Context& context, const std::vector<T>& values, std::size_t min_bytes = sizeof(T)) {
    Buffer buffer(context, std::max(values.size() * sizeof(T), min_bytes));
    if (!values.empty()) buffer.upload(values.data(), values.size() * sizeof(T));
    return buffer;
}

// An optimally tiled image with memory of its own and one view of all its layers (one mip level).
struct ImageDescription {
    VkFormat format = VK_FORMAT_UNDEFINED;
    std::uint32_t width = 1, height = 1, layers = 1;
    VkImageUsageFlags usage = 0;
    VkImageCreateFlags flags = 0;
    VkImageViewType view_type = VK_IMAGE_VIEW_TYPE_2D;
    VkImageAspectFlags aspect = VK_IMAGE_ASPECT_COLOR_BIT;
    VkMemoryPropertyFlags memory = 0;
};

// Creates the image, binds it to new memory and makes the view, writing each handle as soon as it
// exists, so that the caller's clean-up releases what was made when this throws Error (naming the call).
void create_image(Context& context, const ImageDescription& description, VkImage& image, VkDeviceMemory& memory,
                  VkImageView& view);

// A cube-compatible image (6 layers of face_size x face_size), sampled through a cube view with a
// CLAMP_TO_EDGE sampler, NEAREST or LINEAR (seamless across faces, as Vulkan cube maps always are): what a
// `samplerCube` / `usamplerCube` binding sees.
class SampledCubeImage {
public:
    // format: a sampleable 4-byte format (default R32_UINT, read as usamplerCube); filter: the sampler's
    // magnification and minification filter (LINEAR needs a format whose optimal tiling has
    // SAMPLED_IMAGE_FILTER_LINEAR: see supports_linear_filter). Throws Error when the device cannot make
    // such an image (face_size beyond maxImageDimensionCube, memory, a format it cannot filter).
    SampledCubeImage(Context& context, std::uint32_t face_size, VkFormat format = VK_FORMAT_R32_UINT,
                     VkFilter filter = VK_FILTER_NEAREST);
    // Whether the device can sample `format` with a LINEAR filter from an optimally tiled image.
    static bool supports_linear_filter(const Context& context, VkFormat format);
    ~SampledCubeImage();
    SampledCubeImage(const SampledCubeImage&) = delete;
    SampledCubeImage& operator=(const SampledCubeImage&) = delete;

    // Uploads all six faces: 6 * face_size^2 texels of 4 bytes, face (= Vulkan layer) by face, row by
    // row, row 0 first (so texel (face, column, row) is element (face * N + row) * N + column).
    void upload(const void* texels, std::size_t bytes);

    std::uint32_t face_size() const noexcept { return face_size_; }
    VkImageView view() const noexcept { return view_; }
    VkSampler sampler() const noexcept { return sampler_; }

private:
    void destroy() noexcept;
    Context& context_;
    std::uint32_t face_size_;
    VkImage image_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    VkImageView view_ = VK_NULL_HANDLE;
    VkSampler sampler_ = VK_NULL_HANDLE;
};

// What a binding of a compute pipeline is given: a storage buffer or a sampled cube image.
struct Resource {
    Resource(const Buffer& b) : buffer(&b) {}                 // NOLINT: implicit on purpose
    Resource(const SampledCubeImage& i) : image(&i) {}        // NOLINT
    const Buffer* buffer = nullptr;
    const SampledCubeImage* image = nullptr;
};

// One submission being recorded (see Context::submit).
class Commands {
public:
    // Binds `resources` to bindings 0, 1, 2... of set 0 (in the order the pipeline declared them),
    // pushes `push_bytes` of push constants and dispatches groups_x * groups_y * groups_z groups.
    void dispatch(const ComputePipeline& pipeline, std::initializer_list<Resource> resources, const void* push,
                  std::uint32_t push_bytes, std::uint32_t groups_x, std::uint32_t groups_y = 1,
                  std::uint32_t groups_z = 1);
    // dispatch() with the group counts read on the device from `args` at `offset` (three uints, as
    // VkDispatchIndirectCommand): counts that earlier passes computed, with no trip to the host.
    void dispatch_indirect(const ComputePipeline& pipeline, std::initializer_list<Resource> resources, const void* push,
                           std::uint32_t push_bytes, const Buffer& args, VkDeviceSize offset);
    // Makes the shader and transfer writes recorded so far visible to later dispatches (their indirect
    // arguments included) and transfers.
    void barrier();
    // Fills `buffer` with the 32-bit `word` on the device (vkCmdFillBuffer).
    void fill(const Buffer& buffer, std::uint32_t word);
    VkCommandBuffer handle() const noexcept { return command_buffer_; }

private:
    friend class Context;
    void bind(const ComputePipeline& pipeline, std::initializer_list<Resource> resources, const void* push,
              std::uint32_t push_bytes);
    Commands(Context& context, VkCommandBuffer command_buffer) : context_(context), command_buffer_(command_buffer) {}
    Context& context_;
    VkCommandBuffer command_buffer_;
    std::vector<VkDescriptorPool> pools_;
};

class Context {
public:
    // Creates the instance (with validation if wanted and installed) and the device.
    // Throws NoDeviceError when Vulkan or a device with a compute queue is missing, Error otherwise.
    explicit Context(const ContextOptions& options = {});
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    VkInstance instance() const noexcept { return instance_; }
    VkPhysicalDevice physical_device() const noexcept { return physical_device_; }
    VkDevice device() const noexcept { return device_; }
    VkQueue queue() const noexcept { return queue_; }
    std::uint32_t queue_family() const noexcept { return queue_family_; }
    const VkPhysicalDeviceProperties& properties() const noexcept { return properties_; }
    std::string device_name() const { return properties_.deviceName; }

    // Whether VK_LAYER_KHRONOS_validation is active.
    bool validation_enabled() const noexcept { return validation_; }
    // Validation errors reported so far (messages of severity ERROR); every one was printed to stderr.
    std::uint64_t validation_errors() const noexcept;
    // Whether shaderInt64 + shaderBufferInt64Atomics were enabled (64-bit atomicMin on storage buffers).
    bool int64_atomics() const noexcept { return int64_atomics_; }
    // Whether pipelines capture the driver's statistics (ContextOptions::shader_statistics, where supported).
    bool shader_statistics() const noexcept { return shader_statistics_; }

    // Records commands with `record`, submits them to the compute queue and waits until they finished.
    void submit(const std::function<void(Commands&)>& record);
    // Submissions so far (submit() and dispatch() calls that reached the queue). The host waits for the
    // device only at the end of one, so a task done in one submission read nothing back in its course.
    std::uint64_t submissions() const noexcept { return submissions_; }
    // submit() with one dispatch.
    void dispatch(const ComputePipeline& pipeline, std::initializer_list<Resource> resources, const void* push,
                  std::uint32_t push_bytes, std::uint32_t groups_x, std::uint32_t groups_y = 1,
                  std::uint32_t groups_z = 1);

    // Index of a memory type allowed by `type_bits` with all of `flags`; Error if none.
    std::uint32_t memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags flags) const;
    const VkPhysicalDeviceMemoryProperties& memory_properties() const noexcept { return memory_properties_; }
    // ContextOptions::buffer_memory as given.
    BufferMemory buffer_memory() const noexcept { return buffer_memory_; }

    struct Messenger; // debug-utils state, shared with the callback

private:
    friend class Commands;
    VkDescriptorPool make_descriptor_pool();
    void destroy() noexcept;

    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    std::unique_ptr<Messenger> messenger_state_;
    VkPhysicalDevice physical_device_ = VK_NULL_HANDLE;
    VkPhysicalDeviceProperties properties_{};
    VkPhysicalDeviceMemoryProperties memory_properties_{};
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    std::uint32_t queue_family_ = 0;
    VkCommandPool command_pool_ = VK_NULL_HANDLE;
    bool validation_ = false;
    bool int64_atomics_ = false;
    bool shader_statistics_ = false;
    BufferMemory buffer_memory_ = BufferMemory::host;
    std::uint64_t submissions_ = 0;
};

// A pool of GPU timestamps on the context's queue, for timing the passes of one submission: reset() it
// while recording, write(i) after the commands whose end timestamp i marks, and after the submission has
// completed, ticks(n) reads the first n. On a queue without timestamps available() is false, every call
// records nothing and ticks() is empty, so callers need no second path.
class Timestamps {
public:
    Timestamps(Context& context, std::uint32_t count);
    ~Timestamps();
    Timestamps(const Timestamps&) = delete;
    Timestamps& operator=(const Timestamps&) = delete;

    bool available() const noexcept { return pool_ != VK_NULL_HANDLE; }
    std::uint32_t count() const noexcept { return count_; }
    void reset(Commands& commands) noexcept;
    // Timestamp `index` (< count()), taken when every command recorded before it has completed.
    void write(Commands& commands, std::uint32_t index) noexcept;
    // Timestamps 0..n-1 of the completed submission, in ticks (their valid bits only); empty when
    // unavailable or when the device does not return them.
    std::vector<std::uint64_t> ticks(std::uint32_t n) const;
    // Milliseconds between two tick values (0 when `to` is before `from`).
    double milliseconds(std::uint64_t from, std::uint64_t to) const noexcept {
        return to > from ? static_cast<double>(to - from) * nanoseconds_per_tick_ * 1e-6 : 0.0;
    }

private:
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueryPool pool_ = VK_NULL_HANDLE;
    std::uint32_t count_ = 0;
    std::uint64_t valid_mask_ = 0;
    double nanoseconds_per_tick_ = 0.0;
};

// A compute pipeline made from a SPIR-V file (entry point "main"), with one descriptor set (set 0)
// whose bindings 0..n-1 have the given types, and `push_constant_bytes` of push constants.
class ComputePipeline {
public:
    // Throws Error naming the file when it is missing or unreadable, or when Vulkan rejects the module.
    ComputePipeline(Context& context, const std::string& spirv_path, std::vector<VkDescriptorType> bindings,
                    std::uint32_t push_constant_bytes = 0);
    ~ComputePipeline();
    ComputePipeline(const ComputePipeline&) = delete;
    ComputePipeline& operator=(const ComputePipeline&) = delete;

    VkPipeline handle() const noexcept { return pipeline_; }
    VkPipelineLayout layout() const noexcept { return layout_; }
    VkDescriptorSetLayout set_layout() const noexcept { return set_layout_; }
    const std::vector<VkDescriptorType>& bindings() const noexcept { return bindings_; }
    std::uint32_t push_constant_bytes() const noexcept { return push_constant_bytes_; }

    // The driver's statistics of the compiled shader, "name value" each (VK_KHR_pipeline_executable_properties;
    // the names are the driver's, e.g. NVIDIA's register count); empty unless context.shader_statistics().
    std::vector<std::string> statistics() const;

private:
    void destroy() noexcept;
    Context& context_;
    std::vector<VkDescriptorType> bindings_;
    std::uint32_t push_constant_bytes_;
    VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
};

// Reads a SPIR-V file; Error naming the path when it is missing, unreadable, or not SPIR-V.
std::vector<std::uint32_t> read_spirv(const std::string& path);

// A shader module made from a SPIR-V file (read_spirv); Error naming the path when the file cannot be
// read or the driver rejects it. The caller destroys it.
VkShaderModule create_shader_module(Context& context, const std::string& path);

// Validation errors reported by every Context of this process so far, destroyed ones included (an error
// can come while a device or instance is destroyed).
std::uint64_t validation_errors_in_process() noexcept;

// Number of groups of `group_size` invocations that cover `count` invocations.
inline std::uint32_t group_count(std::uint64_t count, std::uint32_t group_size) {
    return static_cast<std::uint32_t>((count + group_size - 1) / group_size);
}

} // namespace rcx::vk
