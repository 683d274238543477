// fuzz_input.hpp: what the fuzz targets read their input with. Bytes are taken from the front, and an
// exhausted input reads as zeros, so every input is a valid program. float() makes the values that break
// geometry code common (zeros of both signs, NaN, infinities, subnormals, FLT_MAX, tiny steps) while raw
// 32-bit patterns stay reachable.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include <glm/glm.hpp>

// Stops the fuzzer with a message: an invariant of the library did not hold (libFuzzer saves the input).
#define FUZZ_CHECK(condition)                                                                       \
    do {                                                                                            \
        if (!(condition)) {                                                                         \
            std::fprintf(stderr, "%s:%d: fuzz check failed: %s\n", __FILE__, __LINE__, #condition); \
            std::abort();                                                                           \
        }                                                                                           \
    } while (false)

class FuzzInput {
public:
    FuzzInput(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

    bool empty() const noexcept { return position_ >= size_; }
    std::size_t remaining() const noexcept { return empty() ? 0 : size_ - position_; }

    std::uint8_t u8() noexcept { return empty() ? 0 : data_[position_++]; }
    std::uint16_t u16() noexcept { return static_cast<std::uint16_t>(u8() | u8() << 8); }
    std::uint32_t u32() noexcept { return static_cast<std::uint32_t>(u16()) | static_cast<std::uint32_t>(u16()) << 16; }
    std::uint64_t u64() noexcept { return static_cast<std::uint64_t>(u32()) | static_cast<std::uint64_t>(u32()) << 32; }
    int in_range(int lo, int hi) noexcept { return lo + static_cast<int>(u32() % static_cast<std::uint32_t>(hi - lo + 1)); }

    float raw_float() noexcept { return bits(u32()); }
    // A float: a raw bit pattern, a special value, or a moderate number (k / 64 for a 16-bit k).
    float number() noexcept {
        switch (u8() % 4) {
        case 0: return raw_float();
        case 1: return special(u8());
        default: return static_cast<float>(static_cast<std::int16_t>(u16())) / 64.0f;
        }
    }
    glm::vec3 vec3() noexcept {
        const float x = number(), y = number();
        return glm::vec3(x, y, number());
    }

    static float special(std::uint8_t k) noexcept {
        constexpr float inf = std::numeric_limits<float>::infinity();
        const float values[] = {0.0f, -0.0f, 1.0f, -1.0f, inf, -inf, std::numeric_limits<float>::quiet_NaN(),
                                std::numeric_limits<float>::denorm_min(), -std::numeric_limits<float>::denorm_min(),
                                std::numeric_limits<float>::min(), std::numeric_limits<float>::max(),
                                -std::numeric_limits<float>::max(), std::numeric_limits<float>::epsilon(), 1e-30f,
                                1e30f, 65280.0f, 65536.0f, 0.5f, 1e-7f, 100.0f, bits(0x7FC00001u), bits(0xFFFFFFFFu)};
        return values[k % (sizeof values / sizeof values[0])];
    }
    static float bits(std::uint32_t b) noexcept {
        float f;
        std::memcpy(&f, &b, sizeof f);
        return f;
    }

private:
    const std::uint8_t* data_;
    std::size_t size_;
    std::size_t position_ = 0;
};

inline bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
