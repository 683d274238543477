// test_support.hpp: what the example's Vulkan tests share: the context (or the reason there is none) and
// the closing check that the validation layer reported nothing.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>

#include <rcx/vulkan.hpp>

namespace rcx::gpu::test {

// The test's context; nullptr, after printing why, when there is no usable Vulkan device (exit 77).
inline std::unique_ptr<vk::Context> context_or_skip(bool int64_atomics = false) {
    try {
        vk::ContextOptions options;
        options.require_int64_atomics = int64_atomics;
        auto context = std::make_unique<vk::Context>(options);
        std::printf("device %s, validation %s\n", context->device_name().c_str(), context->validation_enabled() ? "on" : "off");
        return context;
    } catch (const vk::NoDeviceError& e) {
        std::printf("skipped: %s\n", e.what());
        return nullptr;
    }
}

// After the context is gone: 1, with a FAIL line, when the validation layer reported an error; else 0.
inline int validation_failures() {
    const std::uint64_t errors = vk::validation_errors_in_process();
    if (errors == 0) return 0;
    std::printf("FAIL: the validation layer reported %llu error(s)\n", static_cast<unsigned long long>(errors));
    return 1;
}

} // namespace rcx::gpu::test
