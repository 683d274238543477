// test_random.hpp: a tiny deterministic random generator for tests, so a failure reproduces on any
// platform (std::uniform_*_distribution differs between standard libraries).
#pragma once

#include <cstdint>

struct Lcg {
    std::uint64_t state;
    // The next 32 random bits (PCG's 64-bit LCG constants, upper half).
    std::uint32_t next() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<std::uint32_t>(state >> 32);
    }
    float uniform() { return static_cast<float>(next() >> 8) * (1.0f / 16777216.0f); } // [0, 1)
    float signed_uniform() { return 2.0f * uniform() - 1.0f; }                        // [-1, 1)
};
