// Where the Vulkan harness puts a buffer: rcx::vk::buffer_memory_types on hand-written memory tables of
// three kinds of device (expected orders derived by hand from each table), and on the device at hand, the
// flags a Buffer reports against the device's own memory table read here.
#include <cstdint>
#include <vector>

#include "vulkan_test.hpp"

namespace {

using rcx::vk::BufferUse;
using rcx::vk::buffer_memory_types;
using Types = std::vector<std::uint32_t>;

constexpr VkMemoryPropertyFlags DL = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
constexpr VkMemoryPropertyFlags HV = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT;
constexpr VkMemoryPropertyFlags HC = VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
constexpr VkMemoryPropertyFlags CACHED = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;

VkPhysicalDeviceMemoryProperties table(std::initializer_list<VkMemoryPropertyFlags> types) {
    VkPhysicalDeviceMemoryProperties p{};
    p.memoryHeapCount = 1;
    p.memoryHeaps[0].size = 1ull << 30;
    for (VkMemoryPropertyFlags flags : types) p.memoryTypes[p.memoryTypeCount++] = {flags, 0};
    return p;
}

// A discrete GPU as NVIDIA's Linux driver lists its types: device memory the host cannot map, host memory
// (plain and cached), and a small window of device memory that the host can map.
const VkPhysicalDeviceMemoryProperties discrete = table({0, DL, HV | HC, HV | HC | CACHED, DL | HV | HC});
// lavapipe: one type for everything.
const VkPhysicalDeviceMemoryProperties cpu_device = table({DL | HV | HC | CACHED});
// An integrated GPU: device memory, host memory, mappable device memory, cached host memory.
const VkPhysicalDeviceMemoryProperties integrated = table({DL, HV | HC, DL | HV | HC, HV | HC | CACHED});

} // namespace

using rcx::vk::BufferMemory;

TEST_CASE("buffer memory: shader buffers take the preferred kind first, then every other mappable type by index") {
    // host: every mappable type in index order (the first is what the harness always took before).
    CHECK(buffer_memory_types(discrete, ~0u, BufferUse::device, BufferMemory::host) == Types{2, 3, 4});
    CHECK(buffer_memory_types(integrated, ~0u, BufferUse::device, BufferMemory::host) == Types{1, 2, 3});
    CHECK(buffer_memory_types(cpu_device, ~0u, BufferUse::device, BufferMemory::host) == Types{0});
    CHECK(buffer_memory_types(discrete, ~0u, BufferUse::device, BufferMemory::host_cached) == Types{3, 2, 4});
    CHECK(buffer_memory_types(integrated, ~0u, BufferUse::device, BufferMemory::host_cached) == Types{3, 1, 2});
    CHECK(buffer_memory_types(discrete, ~0u, BufferUse::device, BufferMemory::device_local) == Types{4, 2, 3});
    CHECK(buffer_memory_types(integrated, ~0u, BufferUse::device, BufferMemory::device_local) == Types{2, 1, 3});
    CHECK(buffer_memory_types(cpu_device, ~0u, BufferUse::device, BufferMemory::device_local) == Types{0});
}

TEST_CASE("buffer memory: read-back buffers go to host-cached memory first, whatever the preference") {
    CHECK(buffer_memory_types(discrete, ~0u, BufferUse::readback, BufferMemory::host) == Types{3, 2, 4});
    CHECK(buffer_memory_types(discrete, ~0u, BufferUse::readback, BufferMemory::device_local) == Types{3, 2, 4});
    CHECK(buffer_memory_types(integrated, ~0u, BufferUse::readback, BufferMemory::host) == Types{3, 1, 2});
    CHECK(buffer_memory_types(cpu_device, ~0u, BufferUse::readback, BufferMemory::host) == Types{0});
}

TEST_CASE("buffer memory: only the types the buffer allows, and none that the host cannot map") {
    // The buffer allows types 0..3 only: the mappable device window (4) is out.
    CHECK(buffer_memory_types(discrete, 0b01111u, BufferUse::device, BufferMemory::device_local) == Types{2, 3});
    CHECK(buffer_memory_types(discrete, 0b10011u, BufferUse::readback, BufferMemory::host) == Types{4});
    CHECK(buffer_memory_types(discrete, 0b00011u, BufferUse::device, BufferMemory::host).empty());
    // Host-visible without host-coherent is never taken (the harness neither flushes nor invalidates).
    CHECK(buffer_memory_types(table({DL, HV, DL | HV}), ~0u, BufferUse::device, BufferMemory::device_local).empty());
}

TEST_CASE("buffer memory: flags are named for messages") {
    CHECK(rcx::vk::memory_description(DL | HV | HC) == "device-local, host-visible, host-coherent");
    CHECK(rcx::vk::memory_description(HV | HC | CACHED) == "host-visible, host-coherent, host-cached");
    CHECK(rcx::vk::memory_description(0) == "no-property");
}

TEST_CASE("buffer memory: on this device, buffers land where its own memory table says they should") {
    rcx::vk::Context* vk = rcx_test::context();
    if (!vk) return;
    VkPhysicalDeviceMemoryProperties memory{};
    vkGetPhysicalDeviceMemoryProperties(vk->physical_device(), &memory);
    bool mappable_device_memory = false, mappable_cached_memory = false;
    VkMemoryPropertyFlags first_mappable = 0; // flags of the lowest-index host-visible, host-coherent type
    for (std::uint32_t i = memory.memoryTypeCount; i-- > 0;) {
        const VkMemoryPropertyFlags f = memory.memoryTypes[i].propertyFlags;
        if ((f & (HV | HC)) != (HV | HC)) continue;
        first_mappable = f;
        if (f & DL) mappable_device_memory = true;
        if (f & CACHED) mappable_cached_memory = true;
    }
    INFO("device " << vk->device_name());

    // The default preference (host): the first mappable type, whatever it is.
    rcx::vk::Buffer shader_buffer(*vk, 4096);
    CHECK(shader_buffer.memory_flags() == first_mappable);
    rcx::vk::Buffer image(*vk, 4096, BufferUse::readback);
    CHECK((image.memory_flags() & (HV | HC)) == (HV | HC));
    CHECK(((image.memory_flags() & CACHED) != 0) == mappable_cached_memory);

    // Whatever the memory, the host reads back what it wrote, and a moved buffer keeps its flags.
    const std::vector<std::uint32_t> words{1u, 0xDEADBEEFu, 7u};
    shader_buffer.upload(words.data(), words.size() * 4);
    CHECK(shader_buffer.as<std::uint32_t>()[1] == 0xDEADBEEFu);
    const VkMemoryPropertyFlags flags = shader_buffer.memory_flags();
    rcx::vk::Buffer moved(std::move(shader_buffer));
    CHECK(moved.memory_flags() == flags);
    CHECK(moved.as<std::uint32_t>()[2] == 7u);

    // device_local: device-local memory wherever the device lets the host map some.
    rcx::vk::ContextOptions device_options;
    device_options.buffer_memory = BufferMemory::device_local;
    rcx::vk::Context device_context(device_options);
    if (device_context.device_name() != vk->device_name()) return; // another device was picked: nothing to compare
    rcx::vk::Buffer device_buffer(device_context, 4096);
    CHECK((device_buffer.memory_flags() & (HV | HC)) == (HV | HC));
    CHECK(((device_buffer.memory_flags() & DL) != 0) == mappable_device_memory);
}
