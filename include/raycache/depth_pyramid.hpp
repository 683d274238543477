// raycache/depth_pyramid.hpp: per-face pyramids of the smallest cached distance, so that the CDCT's
// relief search can step over whole blocks of texels that lie beyond the ray (empty-space skipping).
//
// Level 0 is the cube itself; level k >= 1 holds, for each block of 2^k x 2^k texels, the smallest
// distance in it, with an empty texel counting as 0 (so a search always descends to meet it). Update
// the pyramid from the texels stored in a frame just before that frame's CacheCube::begin_frame().
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "raycache/cache_cube.hpp"

namespace raycache {

class DepthPyramid {
public:
    // A pyramid for cubes of face_size texels per edge, every block 0 (nothing known yet).
    // Throws std::invalid_argument unless 1 <= face_size <= 4096.
    explicit DepthPyramid(int face_size) : face_size_(face_size) {
        if (!is_valid_face_size(face_size))
            throw std::invalid_argument("RayCache: DepthPyramid face size must be 1 to 4096 texels");
        values_.reserve(bytes_for(face_size) / sizeof(float));
        for (int size = face_size; size > 1;) {
            size = (size + 1) / 2;
            offsets_.push_back(values_.size());
            sizes_.push_back(size);
            values_.resize(values_.size() + std::size_t{RAYCACHE_FACE_COUNT} * size * size, 0.0f);
        }
    }

    int face_size() const noexcept { return face_size_; }
    // Stored levels (1..levels()); the top level has one block per face. 0 when face_size is 1.
    int levels() const noexcept { return static_cast<int>(sizes_.size()); }
    // Blocks along an edge at level k in 1..levels(); 0 for any other level.
    int blocks(int level) const noexcept {
        return level >= 1 && level <= levels() ? sizes_[static_cast<std::size_t>(level - 1)] : 0;
    }
    std::size_t bytes() const noexcept { return values_.size() * sizeof(float); }
    // bytes() of a pyramid for cubes of face_size (1..4096), without making one (0 for other sizes).
    static std::size_t bytes_for(int face_size) noexcept {
        if (!is_valid_face_size(face_size)) return 0;
        std::size_t values = 0;
        for (int size = face_size; size > 1;) {
            size = (size + 1) / 2;
            values += std::size_t{RAYCACHE_FACE_COUNT} * static_cast<std::size_t>(size) * static_cast<std::size_t>(size);
        }
        return values * sizeof(float);
    }

    // Smallest distance of block (column, row) of `face` at level k in 1..levels(). Anything else (level 0,
    // which is the cube itself, a level above levels(), a face or block off the pyramid) gives 0, the value
    // of a block holding an empty texel: a search that asks sends itself down to the texels, never past them.
    float min_distance(int face, int level, int column, int row) const noexcept {
        const int size = blocks(level);
        if (size == 0 || face < 0 || face >= RAYCACHE_FACE_COUNT || column < 0 || column >= size || row < 0 || row >= size)
            return 0.0f;
        return values_[index(face, level, column, row)];
    }

    // Recomputes every block from the cube's texels (after clear(), invalidate(), or a load).
    // Throws std::invalid_argument when the cube's face size is not the pyramid's.
    void rebuild(const CdctCube& cube) {
        check_face_size(cube);
        for (int level = 1; level <= levels(); ++level)
            for (int face = 0; face < RAYCACHE_FACE_COUNT; ++face)
                for (int row = 0; row < blocks(level); ++row)
                    for (int column = 0; column < blocks(level); ++column) recompute(cube, face, level, column, row);
    }

    // Recomputes the blocks above the texels stored in the cube's current frame. Call it between frames,
    // before the cube's begin_frame(). Cost: proportional to the texels stored, times levels().
    // Throws std::invalid_argument when the cube's face size is not the pyramid's (nothing is changed).
    void update(const CdctCube& cube) {
        cube.assert_between_frames();
        check_face_size(cube);
        std::vector<std::uint32_t> dirty; // (face, column, row) of blocks at the current level, packed
        cube.for_each_written_texel([&](const TexelAddress& t) { dirty.push_back(pack(t.face, t.column, t.row)); });
        for (int level = 1; level <= levels(); ++level) {
            for (std::uint32_t& key : dirty) key = pack(face_of(key), column_of(key) / 2, row_of(key) / 2);
            std::sort(dirty.begin(), dirty.end());
            dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
            for (std::uint32_t key : dirty) recompute(cube, face_of(key), level, column_of(key), row_of(key));
        }
    }

private:
    // A cube of another face size would address blocks outside this pyramid: refused in every build.
    void check_face_size(const CdctCube& cube) const {
        if (cube.face_size() != face_size_)
            throw std::invalid_argument("RayCache: a DepthPyramid of face size " + std::to_string(face_size_) +
                                        " cannot follow a cube of face size " + std::to_string(cube.face_size()));
    }

    static std::uint32_t pack(int face, int column, int row) {
        return static_cast<std::uint32_t>(face) << 26 | static_cast<std::uint32_t>(row) << 13 | static_cast<std::uint32_t>(column);
    }
    static int face_of(std::uint32_t key) { return static_cast<int>(key >> 26); }
    static int row_of(std::uint32_t key) { return static_cast<int>(key >> 13 & 0x1FFFu); }
    static int column_of(std::uint32_t key) { return static_cast<int>(key & 0x1FFFu); }

    std::size_t index(int face, int level, int column, int row) const noexcept {
        const std::size_t size = static_cast<std::size_t>(blocks(level));
        return offsets_[static_cast<std::size_t>(level - 1)] + (face * size + row) * size + column;
    }

    // Distance of a level-0 texel for the pyramid: 0 when empty.
    static float texel_distance(const CdctCube& cube, int face, int column, int row) {
        const std::optional<DepthSample> s = cube.load({face, column, row});
        return s ? s->distance : 0.0f;
    }

    void recompute(const CdctCube& cube, int face, int level, int column, int row) {
        const int below = level - 1;
        const int limit = below == 0 ? face_size_ : blocks(below);
        float smallest = 3.0e38f;
        for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) {
                const int c = 2 * column + dx, r = 2 * row + dy;
                if (c >= limit || r >= limit) continue;
                smallest = std::min(smallest, below == 0 ? texel_distance(cube, face, c, r) : min_distance(face, below, c, r));
            }
        values_[index(face, level, column, row)] = smallest;
    }

    int face_size_;
    std::vector<float> values_;        // every level of every face
    std::vector<std::size_t> offsets_; // start of level k at [k - 1]
    std::vector<int> sizes_;           // blocks per edge of level k at [k - 1]
};

} // namespace raycache
