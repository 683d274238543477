// leak_on_purpose: proves that leak checking still works in the Vulkan tests. It loads Vulkan as they do
// (the harness's Context: loader, lavapipe, LLVM, layers, kept mapped in AddressSanitizer builds), fills a
// RayCache cube and then drops the only pointer to it. Run in AddressSanitizer builds only, under the
// Vulkan tests' LSAN_OPTIONS (cmake/lsan_vulkan.supp); tests/vulkan/CMakeLists.txt expects it to fail
// with a leak report naming leak_a_cube_on_purpose. If the suppressions hid RayCache's leaks, it would pass.
#include <cstdio>

#include <glm/vec3.hpp>
#include <raycache/raycache.hpp>
#include <rcx/vulkan.hpp>

namespace {

raycache::CctCube* volatile g_cube = nullptr;

__attribute__((noinline)) void leak_a_cube_on_purpose() {
    g_cube = new raycache::CctCube(8);
    raycache::cached_trace(*g_cube, glm::vec3(1, 0, 0), [] { return glm::vec3(0.5f); });
    g_cube->begin_frame();
    g_cube = nullptr; // the cube and its texels are now unreachable
}

} // namespace

int main() {
    try {
        rcx::vk::Context context;
        rcx::vk::Buffer buffer(context, 256);
        buffer.fill(0);
        std::printf("vulkan: %s\n", context.device_name().c_str());
    } catch (const rcx::vk::NoDeviceError& e) {
        std::printf("vulkan: none (%s); the leak is checked without a driver loaded\n", e.what());
    }
    leak_a_cube_on_purpose();
    std::printf("leaked one CctCube(8) on purpose: LeakSanitizer must report it at exit\n");
    return 0;
}
