// GPU cubes in cache files (raycache/gpu_cache_file.hpp): texel and doubtful-bit buffers and origin records
// saved and loaded back come out word for word and bit for bit; a file a CPU cache wrote loads into GPU buffers as those
// cubes' own words; files that do not match the GPU cubes are refused by name.
#include <doctest/doctest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "raycache/cache_file.hpp"
#include "raycache/gpu_cache_file.hpp"
#include "test_cache_files.hpp"
#include "test_random.hpp"

namespace {

using raycache::CacheCube;
using raycache::CacheFileError;
using raycache::CctTexel;
using raycache::CdctTexel;
using raycache::CubeBounds;
using raycache::GpuBufferLayout;
using raycache::GpuCubeKey;
using raycache::GpuCubeShape;

const raycache::SceneIdentity scene{0xfeedull, "gpu cubes"};
const std::vector<GpuCubeKey> keys{{3, 0, CubeBounds{glm::vec3(1.0f, 0.0f, 0.0f), 0.5f}},
                                   {5, 0, CubeBounds{glm::vec3(-2.0f, 1.0f, 0.0f), 1.0f}},
                                   {5, 9, CubeBounds{glm::vec3(0.0f, 0.0f, 4.0f), 0.25f}}};

std::vector<GpuCubeShape> shapes_of(const std::vector<int>& sizes) {
    std::vector<GpuCubeShape> shapes;
    for (std::size_t k = 0; k < sizes.size(); ++k) shapes.push_back(GpuCubeShape{sizes[k], keys[k].bounds});
    return shapes;
}

// GPU buffers as a GPU tracer leaves them: cubes filled at random through CPU cubes (write_gpu_words), a
// few of their texels doubtful.
template <class Texel>
struct Buffers {
    GpuBufferLayout layout;
    std::vector<std::uint32_t> words, doubtful, origins;
    std::vector<std::unique_ptr<CacheCube<Texel>>> cubes; // what was written
};
template <class Texel>
Buffers<Texel> filled(const std::vector<int>& sizes, std::uint64_t seed) {
    Buffers<Texel> b;
    b.layout = raycache::gpu_buffer_layout<Texel>(shapes_of(sizes));
    b.words = raycache::cleared_gpu_words(b.layout);
    b.doubtful.assign(static_cast<std::size_t>(b.layout.doubtful_words), raycache::gpu_doubtful_clear_word);
    b.origins.assign(static_cast<std::size_t>(b.layout.origin_words), raycache::gpu_clear_word);
    Lcg rng{seed};
    for (std::size_t k = 0; k < sizes.size(); ++k) {
        auto cube = std::make_unique<CacheCube<Texel>>(sizes[k]);
        fill_randomly(*cube, rng, 200);
        raycache::write_gpu_words(*cube, b.layout.cubes[k], b.words.data(), b.words.size());
        int marked = 0;
        cube->for_each_valid_texel([&](const raycache::TexelAddress& t) {
            if (marked++ % 7 != 0) return;
            cube->set_doubtful(t);
            raycache::set_gpu_doubtful(b.doubtful.data(),
                                       b.layout.cubes[k].first_texel + static_cast<std::uint32_t>(raycache::texel_linear_index(t, sizes[k])));
        });
        // Every tile holding a texel: an origin box and nearest distance of its own (the CCT's origin test).
        cube->for_each_valid_texel([&](const raycache::TexelAddress& t) {
            const raycache::TexelAddress first{t.face, t.column / 16 * 16, t.row / 16 * 16};
            const glm::vec3 lo = 0.5f * glm::vec3(float(k), float(first.column), float(first.row)) - glm::vec3(float(t.face));
            cube->set_origin_box(first, lo, lo + 0.25f, 1.0f + float(t.face));
        });
        raycache::write_gpu_origins(*cube, b.layout.cubes[k], b.origins.data(), b.origins.size());
        b.cubes.push_back(std::move(cube));
    }
    return b;
}

template <class Texel>
void check_round_trip(const std::vector<int>& sizes) {
    const Buffers<Texel> saved = filled<Texel>(sizes, 17);
    const std::vector<std::uint8_t> bytes =
        raycache::encode_gpu_cache<Texel>(scene, saved.layout, keys, saved.words.data(), saved.words.size(), saved.doubtful.data(),
                                          saved.origins.data());
    const auto cubes = raycache::decode_gpu_cache<Texel>(bytes.data(), bytes.size(), scene, keys);
    REQUIRE(raycache::loaded_face_sizes(cubes) == sizes);
    // A fresh layout at the loaded sizes, cleared, then written: the same words and marks, bit for bit.
    const GpuBufferLayout layout = raycache::gpu_buffer_layout<Texel>(shapes_of(raycache::loaded_face_sizes(cubes)));
    std::vector<std::uint32_t> words = raycache::cleared_gpu_words(layout);
    std::vector<std::uint32_t> doubtful(static_cast<std::size_t>(layout.doubtful_words), raycache::gpu_doubtful_clear_word);
    std::vector<std::uint32_t> origins(static_cast<std::size_t>(layout.origin_words), raycache::gpu_clear_word);
    std::size_t valid = 0;
    for (const auto& c : saved.cubes) valid += c->valid_texels();
    CHECK(raycache::write_gpu_cubes(cubes, layout, words.data(), words.size(), doubtful.data(), origins.data()) == valid);
    CHECK(words == saved.words);
    CHECK(doubtful == saved.doubtful);
    CHECK(origins == saved.origins); // every tile's origin box and nearest distance
    std::size_t boxes = 0;
    for (std::size_t w = 0; w < origins.size(); w += RAYCACHE_ORIGIN_RECORD_WORDS) boxes += origins[w] != raycache::gpu_clear_word;
    CHECK(boxes > 10u);
    CHECK(valid > 100u);
}

} // namespace

TEST_CASE("GPU cubes saved and loaded back: every texel word and doubtful bit, CCT and CDCT, partial tiles") {
    check_round_trip<CctTexel>({20, 7, 33});
    check_round_trip<CdctTexel>({20, 7, 33});
}

TEST_CASE("a file a CPU cache wrote loads into GPU buffers as those cubes' own words") {
    const Buffers<CdctTexel> gpu = filled<CdctTexel>({12, 16, 5}, 23);
    std::vector<raycache::CubeToSave<CdctTexel>> save;
    for (std::size_t k = 0; k < keys.size(); ++k) save.push_back({keys[k].object, keys[k].bounds, gpu.cubes[k].get(), keys[k].part});
    const std::vector<std::uint8_t> bytes = raycache::encode_cache<CdctTexel>(scene, save);
    const auto cubes = raycache::decode_gpu_cache<CdctTexel>(bytes.data(), bytes.size(), scene, keys);
    std::vector<std::uint32_t> words = raycache::cleared_gpu_words(gpu.layout);
    std::vector<std::uint32_t> doubtful(static_cast<std::size_t>(gpu.layout.doubtful_words), raycache::gpu_doubtful_clear_word);
    raycache::write_gpu_cubes(cubes, gpu.layout, words.data(), words.size(), doubtful.data());
    CHECK(words == gpu.words);
    CHECK(doubtful == gpu.doubtful);
}

TEST_CASE("a file that does not match the GPU cubes is refused by name, and a layout of other sizes is not written") {
    const Buffers<CctTexel> gpu = filled<CctTexel>({8, 8, 8}, 29);
    const std::vector<std::uint8_t> bytes =
        raycache::encode_gpu_cache<CctTexel>(scene, gpu.layout, keys, gpu.words.data(), gpu.words.size(), gpu.doubtful.data());
    auto error = [&](const std::vector<GpuCubeKey>& k, const std::vector<int>& fixed = {}) {
        return cache_file_error([&] { raycache::decode_gpu_cache<CctTexel>(bytes.data(), bytes.size(), scene, k, fixed); });
    };
    std::vector<GpuCubeKey> fewer(keys.begin(), keys.begin() + 2);
    CHECK(contains(error(fewer), "the file has a cube for object 5 part 9, which has none here"));
    std::vector<GpuCubeKey> more = keys;
    more.push_back({11, 0, CubeBounds{glm::vec3(0.0f), 1.0f}});
    CHECK(contains(error(more), "object 11 has a cube here but none in the file"));
    std::vector<GpuCubeKey> moved = keys;
    moved[1].bounds.centre.x += 0.5f;
    CHECK(contains(error(moved), "object 5's cube sits at centre (-1.5"));
    CHECK(contains(error(keys, {8, 16, 0}), "object 5's cube has 16-texel faces (fixed), in the file 8"));
    CHECK(raycache::decode_gpu_cache<CctTexel>(bytes.data(), bytes.size(), scene, keys, {8, 0, 0}).size() == 3u); // 0: adaptive
    CHECK(contains(cache_file_error([&] { raycache::decode_gpu_cache<CctTexel>(bytes.data(), bytes.size(), raycache::SceneIdentity{1, "other"}, keys); }),
                   "it was saved for scene 'gpu cubes'"));
    const auto cubes = raycache::decode_gpu_cache<CctTexel>(bytes.data(), bytes.size(), scene, keys);
    const GpuBufferLayout other = raycache::gpu_buffer_layout<CctTexel>(shapes_of({8, 9, 8}));
    std::vector<std::uint32_t> words = raycache::cleared_gpu_words(other);
    CHECK_THROWS_AS(raycache::write_gpu_cubes(cubes, other, words.data(), words.size(), nullptr), std::invalid_argument);
    CHECK(words == raycache::cleared_gpu_words(other)); // nothing written, not even the first cube that fits
    std::vector<GpuCubeKey> twice = keys;
    twice[2].part = 0; // object 5 part 0 twice
    CHECK_THROWS_AS(raycache::encode_gpu_cache<CctTexel>(scene, gpu.layout, twice, gpu.words.data(), gpu.words.size(), nullptr),
                    std::invalid_argument);
    CHECK_THROWS_AS(raycache::encode_gpu_cache<CctTexel>(scene, gpu.layout, fewer, gpu.words.data(), gpu.words.size(), nullptr),
                    std::invalid_argument);
}
