// test_bits.hpp: bit-exact float comparisons for tests, so that -0, NaN payloads and the last bit count.
#pragma once

#include <glm/glm.hpp>

inline bool same_bits(float a, float b) { return glm::floatBitsToUint(a) == glm::floatBitsToUint(b); }

inline bool same_bits(const glm::vec3& a, const glm::vec3& b) {
    return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z);
}
