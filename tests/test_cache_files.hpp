// test_cache_files.hpp: what the cache-file tests share: a scratch folder, cubes filled with random valid
// words (any valid word, not only what the encoder makes, so a bit lost on the way shows), texel-by-texel
// comparison of two cubes, and the message of the CacheFileError an operation throws.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

#include "raycache/raycache.hpp"
#include "test_random.hpp"

// A fresh folder under the system's temporary folder, removed with everything in it at the end.
struct ScratchFolder {
    std::filesystem::path path;
    explicit ScratchFolder(const std::string& name) {
        static int counter = 0;
        path = std::filesystem::temp_directory_path() /
               ("raycache-" + name + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
        std::filesystem::remove_all(path);
        std::filesystem::create_directories(path);
    }
    ~ScratchFolder() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    std::string file(const std::string& name) const { return (path / name).string(); }
};

// A random word that the texel type counts as valid (every bit pattern of one, not only encoder output).
inline std::uint32_t random_valid_word(Lcg& rng, raycache::CctTexel) {
    for (;;) {
        const std::uint32_t w = rng.next();
        if (raycache::CctTexel::is_valid(w)) return w;
    }
}
inline std::uint64_t random_valid_word(Lcg& rng, raycache::CdctTexel) {
    const std::uint64_t colour = rng.next();
    const std::uint64_t distance = rng.next() % 0x7F800000u; // a non-negative finite float's bits
    return distance << 32 | colour;
}

// Stores random valid words into about `per_mille` / 1000 of the cube's texels; returns how many.
template <class Texel>
std::size_t fill_randomly(raycache::CacheCube<Texel>& cube, Lcg& rng, unsigned per_mille) {
    std::size_t stored = 0;
    const int n = cube.face_size();
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column)
                if (rng.next() % 1000 < per_mille)
                    stored += cube.store_word_at(raycache::TexelAddress{face, column, row}, random_valid_word(rng, Texel{}));
    return stored;
}

// True when both cubes have one face size and every texel holds the same word.
template <class Texel>
bool same_texels(const raycache::CacheCube<Texel>& a, const raycache::CacheCube<Texel>& b) {
    if (a.face_size() != b.face_size()) return false;
    const int n = a.face_size();
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column)
                if (a.load_word({face, column, row}) != b.load_word({face, column, row})) return false;
    return true;
}

// True when every texel holding a value in `a` has the same doubtful mark in `b`, and its tile the same
// origin box (or none in both).
template <class Texel>
bool same_marks_and_origins(const raycache::CacheCube<Texel>& a, const raycache::CacheCube<Texel>& b) {
    bool same = true;
    a.for_each_valid_texel([&](const raycache::TexelAddress& t) {
        same = same && a.is_doubtful(t) == b.is_doubtful(t) && a.origin_box(t) == b.origin_box(t) &&
               a.nearest_hit(t) == b.nearest_hit(t);
    });
    return same;
}

// The message of the CacheFileError that f() throws; "" when it throws none (other exceptions propagate).
template <class F>
std::string cache_file_error(F&& f) {
    try {
        f();
    } catch (const raycache::CacheFileError& e) {
        return e.what();
    }
    return "";
}

inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }
