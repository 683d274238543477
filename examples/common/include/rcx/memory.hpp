// rcx/memory.hpp: the memory a run of an example tracer needs, known before it starts, checked against
// what the machine has, so that a run that cannot fit is refused with a message (exit 2) instead of
// allocating until the kernel kills it (behind-32 with --face-size 4096 --cache cdct needs about 26 GiB).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "rcx/options.hpp"

namespace rcx {

// One part of what a run allocates, for the message: "33 CDCT cubes of 6 x 4096 x 4096 texels".
struct MemoryNeed {
    std::string what;
    std::uint64_t bytes = 0;
};

// Memory this process can still allocate, and where the number comes from (for the message).
struct AvailableMemory {
    std::uint64_t bytes = 0;
    std::string source;
};

// MemAvailable from /proc/meminfo (else the free physical pages, sysconf), lowered to what the cgroup v2
// memory.max of this process leaves; std::nullopt when none can be read. The environment variable
// RCX_AVAILABLE_MEMORY (a number of bytes) overrides it, for tests and to keep a run below a budget;
// set to anything but digits, it throws std::runtime_error naming it.
std::optional<AvailableMemory> available_memory();

// Host bytes of `count` RayCache cubes of face_size as the Embree tracer holds them: every CacheCube
// tile (CacheCube::tile_bytes(path_records): texels, their bits and origins, path records when the cache
// keeps them, as it does for dynamic scenes) and the tile table, plus a DepthPyramid each for CDCT with
// `pyramid`. 0 for modes without cubes.
MemoryNeed cpu_cubes(CacheMode mode, int count, int face_size, bool pyramid, bool path_records = true);

// The frame images a tracer holds at once: the frame, with --compare also the uncached frame and the
// difference image (linear RGB floats), and the 8-bit copy a PNG is written from.
MemoryNeed frame_images(const Options& options);

// Throws std::runtime_error when the needs add up to more than `available`: the message names the
// total, each part, what is available and where that number comes from, and what to lower. Does
// nothing when `available` is unknown.
void check_memory(const std::vector<MemoryNeed>& needs,
                  const std::optional<AvailableMemory>& available = available_memory());

// "26.3 GiB", "512.0 MiB", "300 bytes".
std::string memory_text(std::uint64_t bytes);

} // namespace rcx
