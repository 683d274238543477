// raycache/direction_cells.hpp: the sphere of directions cut into 54 coarse cells, 3 x 3 on each cube face
// (one bit each of a 64-bit mask), for exact invalidation's transitive step (raycache/invalidation.hpp):
// which directions of a cached object's cube lost texels to a move, and which directions of that cube a
// path's cached answers read (PathRecord::cached_reads). A path that read a changed cube only in
// directions that kept their texels still holds what it saw.
//
// The cells are those of a direction's face (the face table of raycache/shared/cube_face.h) in its face
// coordinates u = sc / |m|, v = tc / |m| (each in [-1, 1]), cut at -1/3 and 1/3: bit face * 9 + row * 3 +
// column, column and row 0 at u or v = -1. They are the same for every cube whatever its face size.
// Both functions below are conservative: they may name a cell the directions only come near (edges count
// on both sides, with a margin for rounding), never leave one out that a direction of theirs falls in.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include "raycache/shared/cube_face.h"
#include "raycache/shared/ray_box.h" // raycache_is_finite3

namespace raycache {

inline constexpr int direction_cells_per_side = 3;
inline constexpr int direction_cells_per_face = direction_cells_per_side * direction_cells_per_side;
inline constexpr int direction_cell_count = RAYCACHE_FACE_COUNT * direction_cells_per_face; // 54
inline constexpr std::uint64_t every_direction_cell = (std::uint64_t{1} << direction_cell_count) - 1u;

// The bit of cell (column, row) of `face`.
inline constexpr std::uint64_t direction_cell_bit(int face, int column, int row) noexcept {
    return std::uint64_t{1} << (face * direction_cells_per_face + row * direction_cells_per_side + column);
}

namespace detail {

// The cells along one face coordinate that [lo, hi] (within [-1, 1] after the caller's clipping) meets.
inline void direction_cell_span(float lo, float hi, int& first, int& last) noexcept {
    auto cell = [](float u) {
        const float position = (u + 1.0f) * (0.5f * static_cast<float>(direction_cells_per_side));
        return std::clamp(static_cast<int>(std::floor(position)), 0, direction_cells_per_side - 1);
    };
    first = cell(lo);
    last = cell(hi);
}

// The cells of `face` that the face coordinates [u_lo, u_hi] x [v_lo, v_hi] meet, each range widened by a
// margin for rounding (the face table's own divisions round differently near cell edges); none when they
// miss the face's [-1, 1] x [-1, 1].
inline std::uint64_t face_cells(int face, float u_lo, float u_hi, float v_lo, float v_hi) noexcept {
    constexpr float margin = 1e-5f;
    u_lo -= margin * std::max(1.0f, std::abs(u_lo)), u_hi += margin * std::max(1.0f, std::abs(u_hi));
    v_lo -= margin * std::max(1.0f, std::abs(v_lo)), v_hi += margin * std::max(1.0f, std::abs(v_hi));
    if (u_lo > 1.0f || u_hi < -1.0f || v_lo > 1.0f || v_hi < -1.0f) return 0;
    int c0, c1, r0, r1;
    direction_cell_span(std::max(u_lo, -1.0f), std::min(u_hi, 1.0f), c0, c1);
    direction_cell_span(std::max(v_lo, -1.0f), std::min(v_hi, 1.0f), r0, r1);
    std::uint64_t cells = 0;
    for (int row = r0; row <= r1; ++row)
        for (int column = c0; column <= c1; ++column) cells |= direction_cell_bit(face, column, row);
    return cells;
}

// The cells of `face` that the texel edges [lo, hi] x [row_lo, row_hi] (columns, then rows, in texels of a
// face of `n`) span, for spans clear of the face's edges: face_cells() of their face coordinates, from
// integers. Texel edge i lies at 3 i / n in cells; one exactly on a cell edge names both cells, as
// face_cells()'s margin makes it, and every other texel edge lies at least 1 / n of a cell from a cell
// edge, far wider than that margin for any face size up to 4096.
inline std::uint64_t interior_face_cells(int face, int lo, int hi, int row_lo, int row_hi, int n) noexcept {
    auto first = [n](int edge) { return 3 * edge <= n ? 0 : (3 * edge <= 2 * n ? 1 : 2); };
    auto last = [n](int edge) { return 3 * edge < n ? 0 : (3 * edge < 2 * n ? 1 : 2); };
    const unsigned columns = (2u << last(hi)) - (1u << first(lo)); // bits first..last
    std::uint64_t cells = 0;
    for (int row = first(row_lo); row <= last(row_hi); ++row) cells |= std::uint64_t{columns} << (row * direction_cells_per_side);
    return cells << (face * direction_cells_per_face);
}

// [a, b] / [m_lo, m_hi] for 0 < m_lo <= m_hi: the range of x / m over the two intervals.
inline void divide_interval(float a, float b, float m_lo, float m_hi, float& lo, float& hi) noexcept {
    lo = std::min(a / m_lo, a / m_hi);
    hi = std::max(b / m_lo, b / m_hi);
}

} // namespace detail

// The cells holding some positive multiple of a point of the box [lo, hi] (a box of direction vectors of
// any length: the cone of rays through it). A box with a NaN or infinite corner names every cell; an empty
// one (lo > hi on an axis) none.
inline std::uint64_t direction_cells_of_box(const glm::vec3& lo, const glm::vec3& hi) noexcept {
    if (!shared::raycache_is_finite3(lo) || !shared::raycache_is_finite3(hi)) return every_direction_cell;
    if (lo.x > hi.x || lo.y > hi.y || lo.z > hi.z) return 0;
    std::uint64_t cells = 0;
    for (int face = 0; face < RAYCACHE_FACE_COUNT; ++face) {
        const int axis = face / 2;
        const bool negative = (face % 2) != 0;
        // m, the major component along the face's axis, signed so that the face's directions have m > 0.
        float m_lo = negative ? -hi[axis] : lo[axis];
        const float m_hi = negative ? -lo[axis] : hi[axis];
        if (!(m_hi > 0.0f)) continue;
        // (sc, tc) are each one component of the direction, signed: their ranges over the box from its corners.
        const glm::vec2 a = shared::raycache_face_coordinates(lo, face), b = shared::raycache_face_coordinates(hi, face);
        const glm::vec2 s_lo = glm::min(a, b), s_hi = glm::max(a, b);
        // The face's own directions have m >= |sc| and m >= |tc|: over the box at least the distance of
        // either range from 0, which keeps a box straddling m = 0 to the part of it that can lie on the face.
        auto distance_from_zero = [](float l, float h) { return l > 0.0f ? l : (h < 0.0f ? -h : 0.0f); };
        m_lo = std::max(m_lo, std::max(distance_from_zero(s_lo.x, s_hi.x), distance_from_zero(s_lo.y, s_hi.y)));
        if (m_lo > m_hi) continue;
        float u_lo = -1.0f, u_hi = 1.0f, v_lo = -1.0f, v_hi = 1.0f;
        if (m_lo > 0.0f) {
            detail::divide_interval(s_lo.x, s_hi.x, m_lo, m_hi, u_lo, u_hi);
            detail::divide_interval(s_lo.y, s_hi.y, m_lo, m_hi, v_lo, v_hi);
        } // else the box holds directions arbitrarily near the face's axis at m -> 0: the whole face
        cells |= detail::face_cells(face, u_lo, u_hi, v_lo, v_hi);
    }
    return cells;
}

// The cells of the texels [column0, column1) x [row0, row1) of `face` on a cube of `face_size`, grown by
// one texel all round (into the neighbouring faces at the face's edges): what a filtered lookup near those
// texels may read, and a margin for the texel choice's rounding.
inline std::uint64_t direction_cells_of_texels(int face, int column0, int row0, int column1, int row1, int face_size) noexcept {
    const float n = static_cast<float>(face_size);
    auto coordinate = [n](int texel) { return 2.0f * static_cast<float>(texel) / n - 1.0f; };
    const float s0 = coordinate(column0 - 1), s1 = coordinate(column1 + 1);
    const float t0 = coordinate(row0 - 1), t1 = coordinate(row1 + 1);
    // Within the face, clear of its edges (most blocks): no other face's directions, and the face's own
    // cells are those of the coordinates' spans, as direction_cells_of_box finds them at |m| = 1.
    constexpr float inside = 1.0f - 1e-3f;
    if (s0 > -inside && s1 < inside && t0 > -inside && t1 < inside)
        return detail::interior_face_cells(face, column0 - 1, column1 + 1, row0 - 1, row1 + 1, face_size);
    // The rectangle lies in the plane |m| = 1 of the face's axis, so the box of its corners is the rectangle.
    const glm::vec3 a = shared::raycache_face_point(face, 1.0f, s0, t0), b = shared::raycache_face_point(face, 1.0f, s1, t1);
    return direction_cells_of_box(glm::min(a, b), glm::max(a, b));
}

} // namespace raycache
