// raycache_fuzz_make_seeds: writes the fuzz targets' seed corpora into fuzz/corpus/<target>/ (checked in;
// run it again when the cache-file format or a target's input layout changes: cache-file seeds are named
// after their format version, so the seeds of older formats stay beside them, and the tests read them):
//   raycache_fuzz_make_seeds <repository>/fuzz/corpus
// Cache-file seeds are small valid files (CCT and CDCT, one to three cubes, partial edge tiles, a 4096-texel
// cube with one tile, origin boxes and doubtful marks) behind a byte that asks for checksums to be fixed; the other targets' inputs are read
// as a stream of choices, so their seeds are a few short byte strings from a fixed generator.
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <type_traits>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "raycache/raycache.hpp"

namespace {

struct Lcg {
    std::uint64_t state;
    std::uint32_t next() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<std::uint32_t>(state >> 32);
    }
};

void write(const std::filesystem::path& file, const std::vector<std::uint8_t>& bytes) {
    std::filesystem::create_directories(file.parent_path());
    std::ofstream out(file, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw std::runtime_error("cannot write " + file.string());
}

template <class Texel>
std::vector<std::uint8_t> cache_seed(std::uint8_t mode, const std::vector<int>& sizes, std::uint32_t seed, unsigned per_mille) {
    const raycache::SceneIdentity identity{0x5eed5eed5eed5eedull, "fuzz"};
    Lcg rng{seed};
    std::vector<std::unique_ptr<raycache::CacheCube<Texel>>> cubes;
    std::vector<raycache::CubeToSave<Texel>> save;
    for (int n : sizes) {
        cubes.push_back(std::make_unique<raycache::CacheCube<Texel>>(n));
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column) {
                    if (rng.next() % 1000 >= per_mille) continue;
                    if constexpr (std::is_same_v<Texel, raycache::CctTexel>)
                        cubes.back()->store_word_at({face, column, row}, rng.next() & 0x7FFFFFFFu);
                    else
                        cubes.back()->store_word_at({face, column, row}, std::uint64_t{rng.next() % 0x7F800000u} << 32 | rng.next());
                }
        // A store with the origin it left from (its tile gets an origin box), one with what its path saw (its
        // block gets a path record) and a doubtful texel.
        raycache::PathRecord path;
        path.hit(5, glm::vec3(2.0f, 1.0f, -1.0f));
        path.hit(9, glm::vec3(3.0f, 4.0f, 0.5f));
        path.lit = path.chained = true;
        path.escaped(glm::vec3(0.0f, 1.0f, 1.0f));
        path.track_cached_reads();
        path.read_cached(glm::vec3(1.0f, 0.0f, 0.0f), glm::vec3(1.0f, 0.0f, 0.0f)); // a cube answered a bounce toward +x
        if constexpr (std::is_same_v<Texel, raycache::CctTexel>) {
            cubes.back()->store(glm::vec3(1.0f, 0.2f, 0.1f), glm::vec3(0.5f), glm::vec3(0.3f, 1.0f, 2.0f));
            cubes.back()->store(glm::vec3(-0.3f, 1.0f, 0.2f), glm::vec3(0.25f), path);
        } else {
            cubes.back()->store(glm::vec3(1.0f, 0.2f, 0.1f), raycache::DepthSample{glm::vec3(0.5f), 2.0f}, glm::vec3(0.3f, 1.0f, 2.0f));
            cubes.back()->store(glm::vec3(-0.3f, 1.0f, 0.2f), raycache::DepthSample{glm::vec3(0.25f), 3.0f}, path);
        }
        cubes.back()->begin_frame();
        bool marked = false;
        cubes.back()->for_each_valid_texel([&](const raycache::TexelAddress& t) { marked = marked || cubes.back()->set_doubtful(t); });
        // Every other cube as exact invalidation leaves one: its rays' reach known and its answers limited to it.
        const float seen = 0.25f + 0.01f * static_cast<float>(save.size());
        const bool limited = save.size() % 2 == 1;
        save.push_back({static_cast<std::uint64_t>(save.size()) * 3 + 1, raycache::CubeBounds{glm::vec3(1.0f, -2.0f, 0.5f), 0.25f},
                        cubes.back().get(), 0, seen, limited ? 1.02f * seen : std::numeric_limits<float>::infinity()});
    }
    std::vector<std::uint8_t> bytes{mode};
    const std::vector<std::uint8_t> file = raycache::encode_cache<Texel>(identity, save);
    bytes.insert(bytes.end(), file.begin(), file.end());
    return bytes;
}

} // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: raycache_fuzz_make_seeds <fuzz/corpus folder>\n");
        return 2;
    }
    const std::filesystem::path root = argv[1];
    const std::filesystem::path files = root / "cache_file";
    const std::string format = "-format" + std::to_string(raycache::cache_file_version);
    write(files / ("cct-one-small-cube" + format), cache_seed<raycache::CctTexel>(1, {3}, 1, 300));
    write(files / ("cct-two-cubes-raw" + format), cache_seed<raycache::CctTexel>(0, {1, 2}, 2, 150));
    write(files / ("cdct-edge-tiles" + format), cache_seed<raycache::CdctTexel>(1, {17}, 3, 4));
    write(files / ("cdct-three-cubes" + format), cache_seed<raycache::CdctTexel>(1, {1, 2, 1}, 4, 120));
    {
        raycache::CdctCube big(4096);
        big.store(glm::vec3(0.2f, 1.0f, -0.3f), raycache::DepthSample{glm::vec3(1.0f, 0.5f, 0.25f), 3.0f});
        std::vector<std::uint8_t> bytes{1};
        const auto file = raycache::encode_cache<raycache::CdctTexel>(raycache::SceneIdentity{0x5eed5eed5eed5eedull, "fuzz"},
                                                                       {{7, raycache::CubeBounds{glm::vec3(0.0f), 1.0f}, &big}});
        bytes.insert(bytes.end(), file.begin(), file.end());
        write(files / ("cdct-4096-one-tile" + format), bytes);
    }
    const char* streams[] = {"cct_lookup_store", "cdct_search", "texel_encoding", "prefill"};
    for (const char* target : streams) {
        Lcg rng{raycache::fnv1a64(target, std::strlen(target))};
        for (int k = 0; k < 3; ++k) {
            std::vector<std::uint8_t> bytes(static_cast<std::size_t>(64) << (2 * k));
            for (std::uint8_t& b : bytes) b = static_cast<std::uint8_t>(rng.next());
            write(root / target / ("random-" + std::to_string(bytes.size())), bytes);
        }
    }
    return 0;
}
