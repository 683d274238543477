// The memory a run of an example tracer needs, checked before it starts (rcx/memory.hpp): a run that
// cannot fit is refused with a message naming the need and what is available.
#include <doctest/doctest.h>

#include <cstdlib>
#include <string>

#include <raycache/cache_cube.hpp>
#include <raycache/depth_pyramid.hpp>

#include "rcx/memory.hpp"

namespace {
// Stores a value into every texel: the cube at its largest.
template <class Cube, class Value>
void fill(Cube& cube, const Value& value) {
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < cube.face_size(); ++row)
            for (int column = 0; column < cube.face_size(); ++column) cube.store_at(raycache::TexelAddress{face, column, row}, value);
}
} // namespace

TEST_CASE("cpu_cubes counts the tiles, tile tables and depth pyramids of full cubes of the Embree tracer") {
    raycache::CdctCube cdct(64);
    raycache::CctCube cct(64);
    fill(cdct, raycache::DepthSample{glm::vec3(0.5f), 1.0f});
    fill(cct, glm::vec3(0.5f));
    const raycache::DepthPyramid pyramid(64);
    const std::uint64_t with_pyramids = rcx::cpu_cubes(rcx::CacheMode::cdct, 3, 64, true).bytes;
    CHECK(with_pyramids >= 3 * (cdct.texel_bytes() + pyramid.bytes()));
    CHECK(with_pyramids <= 3 * (cdct.bytes() + pyramid.bytes()));
    CHECK(rcx::cpu_cubes(rcx::CacheMode::cdct, 3, 64, false).bytes == with_pyramids - 3 * pyramid.bytes());
    const std::uint64_t colour = rcx::cpu_cubes(rcx::CacheMode::cct, 3, 64, true).bytes; // no pyramid for the CCT
    CHECK(colour >= 3 * cct.texel_bytes());
    CHECK(colour <= 3 * cct.bytes());
    CHECK(rcx::cpu_cubes(rcx::CacheMode::off, 3, 64, true).bytes == 0);
    CHECK(rcx::cpu_cubes(rcx::CacheMode::ceiling, 3, 64, true).bytes == 0);
    // Without path records (a static scene's caches) the same full cubes, filled, hold what they count.
    raycache::CctCube static_cct(64, nullptr, false);
    fill(static_cct, glm::vec3(0.5f));
    const std::uint64_t static_colour = rcx::cpu_cubes(rcx::CacheMode::cct, 3, 64, true, false).bytes;
    CHECK(static_colour >= 3 * static_cct.texel_bytes());
    CHECK(static_colour <= 3 * static_cct.bytes());
    CHECK(static_colour < colour);
}

TEST_CASE("a run that needs more memory than is available is refused, naming the need and what is available") {
    // behind-32 (33 cached objects) with 4096-texel CDCT faces: per cube 6 x 256^2 tiles of 8136 bytes plus an
    // 8-byte table entry each, and a depth pyramid of 6 x 4 x (2048^2 + 1024^2 + ... + 1) bytes:
    // 33 x (393,216 x 8144 + 134,217,720 = 3,336,568,824) bytes + 3 MiB of images = 102.5 GiB.
    const std::vector<rcx::MemoryNeed> needs{rcx::cpu_cubes(rcx::CacheMode::cdct, 33, 4096, true),
                                             rcx::MemoryNeed{"frame images", 3u << 20}};
    const rcx::AvailableMemory sixteen{16ull << 30, "MemAvailable in /proc/meminfo"};
    CHECK_THROWS_WITH_AS(rcx::check_memory(needs, sixteen), doctest::Contains("needs about 102.5 GiB"), std::runtime_error);
    CHECK_THROWS_WITH_AS(rcx::check_memory(needs, sixteen), doctest::Contains("33 cdct cubes of 6 x 4096 x 4096 texels"),
                         std::runtime_error);
    CHECK_THROWS_WITH_AS(rcx::check_memory(needs, sixteen),
                         doctest::Contains("only 16.0 GiB is available (MemAvailable in /proc/meminfo)"), std::runtime_error);
    CHECK_NOTHROW(rcx::check_memory(needs, rcx::AvailableMemory{128ull << 30, "a big machine"}));
    CHECK_NOTHROW(rcx::check_memory(needs, std::nullopt)); // unknown: nothing to check against
}

TEST_CASE("available memory comes from RCX_AVAILABLE_MEMORY when set, else from the system") {
    const char* saved = std::getenv("RCX_AVAILABLE_MEMORY");
    const std::string before = saved ? saved : "";
    setenv("RCX_AVAILABLE_MEMORY", "123456789", 1);
    const std::optional<rcx::AvailableMemory> forced = rcx::available_memory();
    REQUIRE(forced.has_value());
    CHECK(forced->bytes == 123456789u);
    CHECK(forced->source == "RCX_AVAILABLE_MEMORY");
    unsetenv("RCX_AVAILABLE_MEMORY");
    const std::optional<rcx::AvailableMemory> system = rcx::available_memory();
    REQUIRE(system.has_value()); // Linux: /proc/meminfo
    CHECK(system->bytes > 0);
    CHECK(system->source != "RCX_AVAILABLE_MEMORY");
    if (saved) setenv("RCX_AVAILABLE_MEMORY", before.c_str(), 1);
}

TEST_CASE("an RCX_AVAILABLE_MEMORY that is not a number of bytes is an error naming it, not the system's memory") {
    const char* saved = std::getenv("RCX_AVAILABLE_MEMORY");
    const std::string before = saved ? saved : "";
    for (const char* bad : {"lots", "", "12GiB", "-5", " -5", " 123", "1e9", "99999999999999999999999"}) {
        CAPTURE(bad);
        setenv("RCX_AVAILABLE_MEMORY", bad, 1);
        CHECK_THROWS_WITH_AS(rcx::available_memory(),
                             ("RCX_AVAILABLE_MEMORY: '" + std::string(bad) + "' is not a number of bytes (digits only)").c_str(),
                             std::runtime_error);
        // As the tracers check a run's memory: the same error, not a check against the machine's memory.
        CHECK_THROWS_AS(rcx::check_memory({{"one image", 1}}), std::runtime_error);
    }
    setenv("RCX_AVAILABLE_MEMORY", "0", 1);
    CHECK(rcx::available_memory()->bytes == 0);
    if (saved) setenv("RCX_AVAILABLE_MEMORY", before.c_str(), 1);
    else unsetenv("RCX_AVAILABLE_MEMORY");
}
