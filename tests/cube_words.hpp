// cube_words.hpp: a C++ cube's texels as the 32- or 64-bit words of RayCache's GPU buffers, and back
// (raycache/shared/gpu_layout.h), for tests that hand cubes to GLSL or to another build.
#pragma once

#include <cstddef>
#include <vector>

#include <raycache/cache_cube.hpp>

namespace rcx_test {

// The words of a C++ cube in buffer order ((face * N + row) * N + column), read with CacheCube::load()
// and re-encoded; empty texels give Texel::invalid.
template <class Texel>
std::vector<typename Texel::Word> words_of(const raycache::CacheCube<Texel>& cube) {
    const int n = cube.face_size();
    std::vector<typename Texel::Word> words;
    words.reserve(cube.texel_count());
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column) {
                const auto value = cube.load(raycache::TexelAddress{face, column, row});
                words.push_back(value ? Texel::encode(*value) : Texel::invalid);
            }
    return words;
}

// Stores every valid word of words[first .. first + 6 N^2) into the same texel of `cube` (store_at with
// the decoded value); the caller ends the frame. Returns how many were valid.
template <class Texel>
std::size_t store_words(raycache::CacheCube<Texel>& cube, const typename Texel::Word* words) {
    const int n = cube.face_size();
    std::size_t valid = 0, i = 0;
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column, ++i)
                if (Texel::is_valid(words[i])) {
                    cube.store_at(raycache::TexelAddress{face, column, row}, Texel::decode(words[i]));
                    ++valid;
                }
    return valid;
}

} // namespace rcx_test
