// The doctest runner of the Vulkan tests: exit code 77 (skipped) when there is no Vulkan device, and a
// failure when the validation layer reported an error, whatever the cases said.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <memory>

#include "vulkan_test.hpp"

namespace {
std::unique_ptr<rcx::vk::Context> g_context;
bool g_tried = false;
bool g_no_device = false;
} // namespace

namespace rcx_test {

rcx::vk::Context* context() {
    if (!g_tried) {
        g_tried = true;
        try {
            g_context = std::make_unique<rcx::vk::Context>();
            std::printf("vulkan: %s, validation %s, 64-bit buffer atomics %s\n", g_context->device_name().c_str(),
                        g_context->validation_enabled() ? "on" : "off (layer not installed)",
                        g_context->int64_atomics() ? "yes" : "no");
        } catch (const rcx::vk::NoDeviceError& e) {
            g_no_device = true;
            std::printf("vulkan: skipped: %s\n", e.what());
        }
    }
    return g_context.get();
}

// The tests' shaders: built beside them, or where RAYCACHE_TEST_SHADERS says (a bundle run on another machine).
std::string spirv(const std::string& name) {
    const char* moved = std::getenv("RAYCACHE_TEST_SHADERS");
    return std::string(moved && *moved ? moved : RCX_TEST_SPIRV_DIR) + "/" + name + ".spv";
}

} // namespace rcx_test

int main(int argc, char** argv) {
    doctest::Context runner(argc, argv);
    int result = runner.run();
    if (runner.shouldExit()) return result;
    if (g_no_device) return 77;
    g_context.reset(); // destroying the device and instance can report errors too
    if (const std::uint64_t errors = rcx::vk::validation_errors_in_process()) {
        std::printf("vulkan: FAILED: the validation layer reported %llu error(s), printed above\n",
                    static_cast<unsigned long long>(errors));
        return result ? result : 1;
    }
    return result;
}
