// The memory a run needs against the memory the machine has (rcx/memory.hpp).
#include "rcx/memory.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

#include <glm/glm.hpp>
#include <raycache/cache_cube.hpp>
#include <raycache/depth_pyramid.hpp>

namespace rcx {

namespace {

// The first line of a file, or nullopt when it cannot be read.
std::optional<std::string> first_line(const std::string& path) {
    std::ifstream in(path);
    std::string line;
    if (!in || !std::getline(in, line)) return std::nullopt;
    return line;
}

std::optional<std::uint64_t> parse_bytes(const std::string& text) {
    errno = 0;
    char* end = nullptr;
    const unsigned long long v = std::strtoull(text.c_str(), &end, 10);
    // Digits only: strtoull passes over white space and takes "-5" as a huge number.
    if (text.empty() || text[0] < '0' || text[0] > '9' || *end != '\0' || errno == ERANGE) return std::nullopt;
    return v;
}

// MemAvailable (kB) from /proc/meminfo.
std::optional<std::uint64_t> meminfo_available() {
    std::ifstream in("/proc/meminfo");
    std::string key;
    std::uint64_t kib = 0;
    std::string unit;
    while (in >> key >> kib) {
        std::getline(in, unit);
        if (key == "MemAvailable:") return kib * 1024;
    }
    return std::nullopt;
}

// What the cgroup v2 memory.max of this process leaves (memory.max - memory.current); nullopt without a limit.
std::optional<std::uint64_t> cgroup_left() {
    std::ifstream in("/proc/self/cgroup");
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("0::", 0) != 0) continue; // the v2 hierarchy
        const std::string dir = "/sys/fs/cgroup" + line.substr(3);
        const std::optional<std::string> max = first_line(dir + "/memory.max");
        const std::optional<std::string> current = first_line(dir + "/memory.current");
        if (!max || !current || *max == "max") return std::nullopt;
        const std::optional<std::uint64_t> limit = parse_bytes(*max), used = parse_bytes(*current);
        if (!limit || !used) return std::nullopt;
        return *limit > *used ? *limit - *used : 0;
    }
    return std::nullopt;
}

} // namespace

std::optional<AvailableMemory> available_memory() {
    if (const char* forced = std::getenv("RCX_AVAILABLE_MEMORY")) {
        // A value set to limit a run that is ignored would let it take the machine's memory instead.
        const std::optional<std::uint64_t> bytes = parse_bytes(forced);
        if (!bytes) throw std::runtime_error("RCX_AVAILABLE_MEMORY: '" + std::string(forced) + "' is not a number of bytes (digits only)");
        return AvailableMemory{*bytes, "RCX_AVAILABLE_MEMORY"};
    }
    std::optional<AvailableMemory> best;
    if (const std::optional<std::uint64_t> bytes = meminfo_available()) {
        best = AvailableMemory{*bytes, "MemAvailable in /proc/meminfo"};
    } else {
        const long pages = sysconf(_SC_AVPHYS_PAGES), page = sysconf(_SC_PAGESIZE);
        if (pages > 0 && page > 0)
            best = AvailableMemory{static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page), "free physical memory"};
    }
    if (const std::optional<std::uint64_t> left = cgroup_left())
        if (!best || *left < best->bytes) best = AvailableMemory{*left, "what this cgroup's memory.max leaves"};
    return best;
}

MemoryNeed cpu_cubes(CacheMode mode, int count, int face_size, bool pyramid, bool path_records) {
    if (!uses_caches(mode) || count <= 0 || face_size <= 0) return {};
    const bool cdct = mode == CacheMode::cdct;
    // Every tile allocated (texels, their bits, origins, path records when kept) and the tile table: a full cube.
    const std::uint64_t per_edge = static_cast<std::uint64_t>((face_size + raycache::CctCube::tile_edge - 1) / raycache::CctCube::tile_edge);
    const std::uint64_t tiles = 6ull * per_edge * per_edge;
    const std::uint64_t tile = cdct ? raycache::CdctCube::tile_bytes(path_records) : raycache::CctCube::tile_bytes(path_records);
    std::uint64_t one = tiles * (tile + sizeof(void*));
    if (cdct && pyramid) one += raycache::DepthPyramid::bytes_for(face_size);
    const std::string n = std::to_string(face_size);
    return MemoryNeed{std::to_string(count) + " " + to_string(mode) + " cube" + (count == 1 ? "" : "s") + " of 6 x " + n +
                          " x " + n + " texels" + (cdct && pyramid ? " with depth pyramids" : ""),
                      static_cast<std::uint64_t>(count) * one};
}

MemoryNeed frame_images(const Options& options) {
    const std::uint64_t pixels = static_cast<std::uint64_t>(options.width) * static_cast<std::uint64_t>(options.height);
    const std::uint64_t images = options.compare ? 3 : 1;
    return MemoryNeed{"frame images of " + std::to_string(options.width) + " x " + std::to_string(options.height),
                      pixels * (images * sizeof(glm::vec3) + 3)};
}

std::string memory_text(std::uint64_t bytes) {
    char text[64];
    if (bytes >= (1ull << 30))
        std::snprintf(text, sizeof text, "%.1f GiB", static_cast<double>(bytes) / (1ull << 30));
    else if (bytes >= (1ull << 20))
        std::snprintf(text, sizeof text, "%.1f MiB", static_cast<double>(bytes) / (1ull << 20));
    else
        std::snprintf(text, sizeof text, "%llu bytes", static_cast<unsigned long long>(bytes));
    return text;
}

void check_memory(const std::vector<MemoryNeed>& needs, const std::optional<AvailableMemory>& available) {
    std::uint64_t total = 0;
    for (const MemoryNeed& n : needs) total += n.bytes;
    if (!available || total <= available->bytes) return;
    std::string parts;
    for (const MemoryNeed& n : needs)
        if (n.bytes) parts += (parts.empty() ? "" : ", ") + n.what + " (" + memory_text(n.bytes) + ")";
    throw std::runtime_error("this run needs about " + memory_text(total) + " of memory (" + parts + "), but only " +
                             memory_text(available->bytes) + " is available (" + available->source +
                             "); lower --face-size (half the size, a quarter of the memory), --size, or use "
                             "a scene with fewer cached objects");
}

} // namespace rcx
