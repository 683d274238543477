// Fuzz target: the cache-file loader (raycache/cache_file.hpp). The first byte picks raw bytes or bytes
// whose checksums are first made right (so mutations reach the checks behind them: sizes, tile indices,
// texel words, identities). Checked: the loader returns or throws CacheFileError, never reads out of bounds
// (ASan) and never crashes; what it returns encodes to a file that loads back to the same texels, and
// encoding that again gives the same bytes.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_input.hpp"
#include "raycache/raycache.hpp"

namespace {

const raycache::SceneIdentity identity{0x5eed5eed5eed5eedull, "fuzz"};

void put_u64(std::vector<std::uint8_t>& b, std::size_t at, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (8 * i));
}

// Rewrites the prelude's and every whole chunk's checksum to match their bytes.
void fix_checksums(std::vector<std::uint8_t>& b) {
    if (b.size() < 16) return;
    const auto prelude = static_cast<std::uint32_t>(raycache::fnv1a64(b.data(), 12));
    for (int i = 0; i < 4; ++i) b[12 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(prelude >> (8 * i));
    for (std::size_t at = 16; b.size() - at >= 20;) {
        std::uint64_t payload = 0;
        for (int i = 0; i < 8; ++i) payload |= static_cast<std::uint64_t>(b[at + 4 + static_cast<std::size_t>(i)]) << (8 * i);
        if (payload > b.size() - at - 20) return;
        const std::size_t end = at + 12 + static_cast<std::size_t>(payload);
        put_u64(b, end, raycache::fnv1a64(b.data() + at, end - at));
        at = end + 8;
    }
}

template <class Texel>
void load(const std::vector<std::uint8_t>& bytes) {
    std::vector<raycache::LoadedCube<Texel>> cubes;
    try {
        cubes = raycache::decode_cache<Texel>(bytes.data(), bytes.size(), identity);
    } catch (const raycache::CacheFileError&) {
        return;
    }
    std::vector<raycache::CubeToSave<Texel>> again;
    std::size_t texels = 0;
    for (const auto& c : cubes) {
        FUZZ_CHECK(c.cube && raycache::is_valid_face_size(c.cube->face_size()));
        again.push_back({c.object, c.bounds, c.cube.get()});
        texels += c.cube->texel_count();
    }
    if (texels > std::size_t{6} * 512 * 512) return; // walking every texel three times would slow the fuzzer down
    const std::vector<std::uint8_t> encoded = raycache::encode_cache<Texel>(identity, again);
    const std::vector<raycache::LoadedCube<Texel>> back = raycache::decode_cache<Texel>(encoded.data(), encoded.size(), identity);
    FUZZ_CHECK(back.size() == cubes.size());
    std::vector<raycache::CubeToSave<Texel>> third;
    for (std::size_t i = 0; i < back.size(); ++i) {
        FUZZ_CHECK(back[i].object == cubes[i].object && raycache::same_placement(back[i].bounds, cubes[i].bounds));
        FUZZ_CHECK(back[i].cube->valid_texels() == cubes[i].cube->valid_texels());
        cubes[i].cube->for_each_valid_texel(
            [&](const raycache::TexelAddress& t) { FUZZ_CHECK(back[i].cube->load_word(t) == cubes[i].cube->load_word(t)); });
        third.push_back({back[i].object, back[i].bounds, back[i].cube.get()});
    }
    FUZZ_CHECK(raycache::encode_cache<Texel>(identity, third) == encoded);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    std::vector<std::uint8_t> bytes(data + 1, data + size);
    if (data[0] & 1) fix_checksums(bytes);
    load<raycache::CctTexel>(bytes);
    load<raycache::CdctTexel>(bytes);
    return 0;
}
