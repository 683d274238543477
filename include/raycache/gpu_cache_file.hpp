// raycache/gpu_cache_file.hpp: a GPU technique's cubes saved to a cache file and loaded back, in the
// format of raycache/cache_file.hpp, so that a GPU tracer's walkthrough can start warm as a CPU
// SceneCache's does. Between frames, with the device done with the buffers:
//
//   save: read back the texel buffer, the doubtful-bit buffer and (CCT with the origin test) the origin
//         records (the pending twin is empty between frames);
//         bytes = encode_gpu_cache<Texel>(scene, layout, keys, words, word_count, doubtful, origins);
//         write_file_atomically(path, bytes);
//   load: cubes = load_gpu_cache_file<Texel>(path, scene, keys, fixed_face_sizes);
//         place the cubes at loaded_face_sizes(cubes) (gpu_buffer_layout), fill the new texel buffer with
//         gpu_clear_word and the doubtful bits with gpu_doubtful_clear_word, then
//         write_gpu_cubes(cubes, layout, words, word_count, doubtful, origins) (origin records filled with
//         gpu_clear_word first); upload; the next frame reads them.
//
// `keys` names the layout's cubes, in its order: the caller's (object, part) key of what each caches and
// where it sits, as a SceneCache keys its cubes. Tiles keep their origin boxes and nearest distances when
// origin records are given (the CCT's origin test, RAYCACHE_ORIGINS). What the GPU does not keep is not in
// its files: no path records (GPU caches are not invalidated), and the cubes' rays' reach is unknown. A file
// saved by a SceneCache loads here with those left out.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "raycache/cache_cube.hpp"
#include "raycache/cache_file.hpp"
#include "raycache/gpu_buffers.hpp"

namespace raycache {

// One GPU cube as a cache file names it: the caller's key (object, part; unique) and its placement.
struct GpuCubeKey {
    std::uint64_t object = 0;
    std::uint64_t part = 0;
    CubeBounds bounds;
};

namespace detail {
// Throws std::invalid_argument unless `keys` names every cube of `layout` once, each key its own.
inline void check_gpu_keys(const GpuBufferLayout& layout, const std::vector<GpuCubeKey>& keys) {
    if (keys.size() != layout.cubes.size())
        throw std::invalid_argument("RayCache: " + std::to_string(keys.size()) + " keys for " + std::to_string(layout.cubes.size()) +
                                    " GPU cubes");
    std::set<std::pair<std::uint64_t, std::uint64_t>> seen;
    for (const GpuCubeKey& k : keys)
        if (!seen.insert({k.object, k.part}).second)
            throw std::invalid_argument("RayCache: two GPU cubes have the key " + key_text(k.object, k.part));
}
} // namespace detail

// The bytes of a cache file holding the layout's cubes, read from `words` (the texel buffer's contents,
// `word_count` 32-bit words), `doubtful` (the doubtful-bit buffer's, layout.doubtful_words words; null:
// none doubtful) and `origins` (the origin records, layout.origin_words words; null: no origin boxes).
// Throws std::invalid_argument for keys that do not match the layout, a cube that does not fit in `words`,
// or as encode_cache does.
template <class Texel>
std::vector<std::uint8_t> encode_gpu_cache(const SceneIdentity& scene, const GpuBufferLayout& layout, const std::vector<GpuCubeKey>& keys,
                                           const std::uint32_t* words, std::size_t word_count, const std::uint32_t* doubtful,
                                           const std::uint32_t* origins = nullptr) {
    detail::check_gpu_keys(layout, keys);
    std::vector<std::unique_ptr<CacheCube<Texel>>> cubes;
    std::vector<CubeToSave<Texel>> save;
    for (std::size_t k = 0; k < layout.cubes.size(); ++k) {
        const shared::raycache_gpu_cube& at = layout.cubes[k];
        auto cube = std::make_unique<CacheCube<Texel>>(at.face_size);
        read_gpu_words(*cube, at, words, word_count);
        if (origins) read_gpu_origins(*cube, at, origins, static_cast<std::size_t>(layout.origin_words));
        cube->begin_frame(); // the read texels become the cube's (doubtful marks need visible ones)
        if (doubtful)
            cube->for_each_valid_texel([&](const TexelAddress& t) {
                if (gpu_doubtful(doubtful, static_cast<std::size_t>(layout.doubtful_words), gpu_element(at, t))) cube->set_doubtful(t);
            });
        save.push_back(CubeToSave<Texel>{keys[k].object, keys[k].bounds, cube.get(), keys[k].part});
        cubes.push_back(std::move(cube));
    }
    return encode_cache<Texel>(scene, save);
}

// The cubes of a cache file for the GPU cubes `keys` names, in that order: the file must hold one cube for
// each key and no other, at the key's placement, and, where fixed_face_sizes[k] > 0 (a cube of a fixed
// face size; 0: any, an adaptive cube), of that face size (an empty vector: all any). Otherwise, or as
// decode_cache refuses, throws CacheFileError saying what is wrong (`source` names the bytes).
template <class Texel>
std::vector<LoadedCube<Texel>> decode_gpu_cache(const std::uint8_t* data, std::size_t size, const SceneIdentity& expected,
                                                const std::vector<GpuCubeKey>& keys, const std::vector<int>& fixed_face_sizes = {},
                                                const std::string& source = "cache data") {
    if (!fixed_face_sizes.empty() && fixed_face_sizes.size() != keys.size())
        throw std::invalid_argument("RayCache: decode_gpu_cache: " + std::to_string(fixed_face_sizes.size()) + " face sizes for " +
                                    std::to_string(keys.size()) + " keys");
    std::vector<LoadedCube<Texel>> file = decode_cache<Texel>(data, size, expected, nullptr, source);
    auto fail = [&](const std::string& what) { throw CacheFileError("RayCache: " + source + ": " + what + "; nothing was loaded"); };
    std::map<std::pair<std::uint64_t, std::uint64_t>, std::size_t> by_key;
    for (std::size_t i = 0; i < file.size(); ++i) by_key[{file[i].object, file[i].part}] = i;
    std::vector<LoadedCube<Texel>> cubes;
    for (std::size_t k = 0; k < keys.size(); ++k) {
        const std::string name = detail::key_text(keys[k].object, keys[k].part);
        const auto it = by_key.find({keys[k].object, keys[k].part});
        if (it == by_key.end()) fail(name + " has a cube here but none in the file");
        LoadedCube<Texel>& c = file[it->second];
        if (!same_placement(c.bounds, keys[k].bounds))
            fail(name + "'s cube sits at " + describe(keys[k].bounds) + ", in the file at " + describe(c.bounds));
        if (!fixed_face_sizes.empty() && fixed_face_sizes[k] > 0 && c.cube->face_size() != fixed_face_sizes[k])
            fail(name + "'s cube has " + std::to_string(fixed_face_sizes[k]) + "-texel faces (fixed), in the file " +
                 std::to_string(c.cube->face_size()));
        c.cube->begin_frame(); // visible: write_gpu_cubes reads the texels and their marks
        cubes.push_back(std::move(c));
        by_key.erase(it);
    }
    if (!by_key.empty()) {
        const auto& [object, part] = by_key.begin()->first;
        fail("the file has a cube for " + detail::key_text(object, part) + ", which has none here (" + std::to_string(by_key.size()) +
             " such cubes)");
    }
    return cubes;
}

// decode_gpu_cache of the file at `path`. Throws CacheFileError naming the file and what is wrong.
template <class Texel>
std::vector<LoadedCube<Texel>> load_gpu_cache_file(const std::string& path, const SceneIdentity& expected,
                                                   const std::vector<GpuCubeKey>& keys, const std::vector<int>& fixed_face_sizes = {}) {
    const std::vector<std::uint8_t> bytes = read_whole_file(path);
    return decode_gpu_cache<Texel>(bytes.data(), bytes.size(), expected, keys, fixed_face_sizes, "cache file '" + path + "'");
}

// The face size of each loaded cube, in order: the sizes to place the GPU cubes at before write_gpu_cubes.
template <class Texel>
std::vector<int> loaded_face_sizes(const std::vector<LoadedCube<Texel>>& cubes) {
    std::vector<int> sizes;
    for (const LoadedCube<Texel>& c : cubes) sizes.push_back(c.cube->face_size());
    return sizes;
}

// Writes loaded cubes into a cleared texel buffer's contents (`words`, `word_count` words) and doubtful bits
// (`doubtful`, layout.doubtful_words words, cleared; null: marks dropped) and their tiles' origin boxes into
// the origin records (`origins`, layout.origin_words words; null: boxes dropped) where `layout` places them,
// cube k at layout.cubes[k]. Returns the texels written. Throws std::invalid_argument, before writing
// anything, when the layout has another number of cubes or other face sizes, or a cube does not fit.
template <class Texel>
std::size_t write_gpu_cubes(const std::vector<LoadedCube<Texel>>& cubes, const GpuBufferLayout& layout, std::uint32_t* words,
                            std::size_t word_count, std::uint32_t* doubtful, std::uint32_t* origins = nullptr) {
    if (cubes.size() != layout.cubes.size())
        throw std::invalid_argument("RayCache: write_gpu_cubes: " + std::to_string(cubes.size()) + " cubes for a layout of " +
                                    std::to_string(layout.cubes.size()));
    for (std::size_t k = 0; k < cubes.size(); ++k) detail::check_gpu_cube(*cubes[k].cube, layout.cubes[k], word_count); // all, first
    std::size_t written = 0;
    for (std::size_t k = 0; k < cubes.size(); ++k) {
        const CacheCube<Texel>& cube = *cubes[k].cube;
        const shared::raycache_gpu_cube& at = layout.cubes[k];
        write_gpu_words(cube, at, words, word_count);
        if (origins) write_gpu_origins(cube, at, origins, static_cast<std::size_t>(layout.origin_words));
        cube.for_each_valid_texel([&](const TexelAddress& t) {
            ++written;
            if (doubtful && cube.is_doubtful(t))
                set_gpu_doubtful(doubtful, gpu_element(at, t));
        });
    }
    return written;
}

} // namespace raycache
