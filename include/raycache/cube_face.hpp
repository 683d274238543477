// raycache/cube_face.hpp: directions to texels of a caching cube and back (C++ face of shared/cube_face.h).
//
// The face table, tie rule and rounding are defined once, in shared/cube_face.h, which GLSL includes too.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <optional>

#include <glm/glm.hpp>

#include "raycache/assert.hpp"
#include "raycache/shared/cube_face.h"

namespace raycache {

// The six faces, in GL_TEXTURE_CUBE_MAP_POSITIVE_X + i / Vulkan cube-layer order.
enum class Face : int {
    positive_x = RAYCACHE_FACE_POSITIVE_X,
    negative_x = RAYCACHE_FACE_NEGATIVE_X,
    positive_y = RAYCACHE_FACE_POSITIVE_Y,
    negative_y = RAYCACHE_FACE_NEGATIVE_Y,
    positive_z = RAYCACHE_FACE_POSITIVE_Z,
    negative_z = RAYCACHE_FACE_NEGATIVE_Z,
};

// One texel of a cube: face 0..5, column and row 0..N-1.
struct TexelAddress {
    int face = 0;
    int column = 0;
    int row = 0;
    friend bool operator==(const TexelAddress& a, const TexelAddress& b) {
        return a.face == b.face && a.column == b.column && a.row == b.row;
    }
    friend bool operator!=(const TexelAddress& a, const TexelAddress& b) { return !(a == b); }
};

// True when `direction` can be looked up: finite components, largest magnitude in [2^-64, 2^64].
inline bool is_direction(const glm::vec3& direction) noexcept { return shared::raycache_is_direction(direction); }

// True when `face_size` is a valid number of texels along a face's edge (1..4096).
inline bool is_valid_face_size(int face_size) noexcept {
    return face_size >= RAYCACHE_MIN_FACE_SIZE && face_size <= RAYCACHE_MAX_FACE_SIZE;
}

// True when `texel` lies on a cube with `face_size` texels along each edge.
inline bool is_on_cube(const TexelAddress& texel, int face_size) noexcept {
    return texel.face >= 0 && texel.face < RAYCACHE_FACE_COUNT && texel.column >= 0 && texel.column < face_size &&
           texel.row >= 0 && texel.row < face_size;
}

// The texel that `direction` falls in on a cube with `face_size` texels along each edge.
// direction need not be unit length; std::nullopt when it is not a direction (zero, NaN, infinite).
// face_size must be valid (asserted).
inline std::optional<TexelAddress> texel_of(const glm::vec3& direction, int face_size) noexcept {
    RAYCACHE_ASSERT(is_valid_face_size(face_size));
    const shared::raycache_texel_address a = shared::raycache_texel_of(direction, face_size);
    if (a.face == RAYCACHE_NO_FACE) return std::nullopt;
    return TexelAddress{a.face, a.column, a.row};
}

// The direction through the centre of `texel` (major component +-1, not unit length).
// texel_of(texel_direction(t, N), N) == t for every texel t; `texel` must lie on the cube (asserted).
inline glm::vec3 texel_direction(const TexelAddress& texel, int face_size) noexcept {
    RAYCACHE_ASSERT(is_valid_face_size(face_size));
    RAYCACHE_ASSERT(is_on_cube(texel, face_size));
    return shared::raycache_texel_direction(shared::raycache_texel_address{texel.face, texel.column, texel.row},
                                            face_size);
}

// Index of `texel` in a cube stored face by face, row by row: (face * N + row) * N + column.
// (At most 6 * 4096^2 - 1, so the shared 32-bit formula cannot overflow.)
inline std::size_t texel_linear_index(const TexelAddress& texel, int face_size) noexcept {
    return shared::raycache_texel_linear_index(shared::raycache_texel_address{texel.face, texel.column, texel.row},
                                               face_size);
}

// The texel at `index` of that order (texel_linear_index's inverse); `index` < 6 N^2.
inline TexelAddress texel_at_linear_index(std::size_t index, int face_size) noexcept {
    const std::size_t n = static_cast<std::size_t>(face_size);
    return TexelAddress{static_cast<int>(index / (n * n)), static_cast<int>(index % n), static_cast<int>(index / n % n)};
}

} // namespace raycache
