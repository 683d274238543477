// raycache/pyramid_walk.hpp: the relief search's walk over a DepthPyramid (C++ only: GLSL has no pyramid).
// It replaces the linear steps of shared/relief_walk.h between the box exit and the first crossing, and
// hands the crossing back to that walk, which refines it as it refines a linear step's.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <limits>
#include <optional>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"
#include "raycache/depth_pyramid.hpp"
#include "raycache/shared/depth_secant.h" // raycache_dot_no_fma, raycache_sphere_exit
#include "raycache/shared/relief_walk.h"

namespace raycache {
namespace detail {

// For each face, the vectors whose dot product with v gives its major coordinate m, sc and tc: read once,
// at start-up, off the shared face table (sc and tc are linear in v; m points along the face's axis).
struct FaceAxes {
    glm::vec3 m{0.0f}, sc{0.0f}, tc{0.0f};
};
inline std::array<FaceAxes, RAYCACHE_FACE_COUNT> make_face_axes() {
    std::array<FaceAxes, RAYCACHE_FACE_COUNT> axes{};
    for (int f = 0; f < RAYCACHE_FACE_COUNT; ++f) {
        axes[static_cast<std::size_t>(f)].m[f / 2] = f % 2 == 0 ? 1.0f : -1.0f;
        for (int axis = 0; axis < 3; ++axis) {
            glm::vec3 e(0.0f);
            e[axis] = 1.0f;
            const glm::vec2 st = shared::raycache_face_coordinates(e, f);
            axes[static_cast<std::size_t>(f)].sc[axis] = st.x;
            axes[static_cast<std::size_t>(f)].tc[axis] = st.y;
        }
    }
    return axes;
}
inline const std::array<FaceAxes, RAYCACHE_FACE_COUNT> face_axes = make_face_axes();

// Where the ray of walk w, now at t inside block (a.column >> level, a.row >> level) of face a.face of a
// cube of face size n, leaves the block's cone from the centre. The block spans face coordinates sc/m in
// [u0, u1] and tc/m in [v0, v1]; each bound is a plane through the centre, so along the ray each test is
// linear in t.
inline float block_exit(const shared::raycache_relief_walk& w, float t, const shared::raycache_texel_address& a, int level,
                        int n) {
    const int first_column = (a.column >> level) << level, first_row = (a.row >> level) << level;
    const float u0 = 2.0f * first_column / n - 1.0f, u1 = 2.0f * std::min(first_column + (1 << level), n) / n - 1.0f;
    const float v0 = 2.0f * first_row / n - 1.0f, v1 = 2.0f * std::min(first_row + (1 << level), n) / n - 1.0f;
    const glm::vec3 p = shared::raycache_relief_point(w, t);
    // sc, tc and m as linear forms of the vector from the centre (the face table).
    const FaceAxes& axes = face_axes[static_cast<std::size_t>(a.face)];
    const glm::vec3 &m_axis = axes.m, &u_axis = axes.sc, &v_axis = axes.tc;
    float exit = std::numeric_limits<float>::infinity();
    auto leave = [&](const glm::vec3& normal) { // the ray stays where dot(normal, p) >= 0
        const float rate = shared::raycache_dot_no_fma(normal, w.d);
        if (rate < 0.0f) exit = std::min(exit, t + std::max(shared::raycache_dot_no_fma(normal, p), 0.0f) / -rate);
    };
    // (m_axis holds 0 and +-1: its products are exact, fused or not.)
    leave(u_axis - u0 * m_axis);
    leave(u1 * m_axis - u_axis);
    leave(v_axis - v0 * m_axis);
    leave(v1 * m_axis - v_axis);
    return exit;
}

// Walks on from a clear box exit (w.status == RAYCACHE_RELIEF_CALLER_WALK, w.t the box exit): at the ray's
// point, look at the block around its texel at some level; when the whole block lies beyond the point, jump
// to where the ray leaves the block or reaches the block's nearest distance and go up a level; otherwise go
// down one. A crossing read at level 0 is bracketed (raycache_relief_bracket: the walk reads on from there);
// an empty texel, a point without a face or w.max_steps nodes read without a crossing make a miss (the
// first two say why in `why`: the texel's state, or outside). Every texel and node read counts in w.reads.
inline shared::raycache_relief_walk pyramid_walk(const CdctCube& cube, const DepthPyramid& pyramid,
                                                 shared::raycache_relief_walk w, MissReason& why) noexcept {
    auto miss = [&w] {
        w.status = RAYCACHE_RELIEF_MISS;
        return w;
    };
    const int n = cube.face_size();
    float t = w.t;
    float safe = t; // the ray is before every surface on [start, safe]
    int level = std::min(1, pyramid.levels());
    for (int visits = 0; visits < w.max_steps; ++visits) {
        const glm::vec3 v = shared::raycache_relief_point(w, t);
        const shared::raycache_texel_address a = shared::raycache_texel_of(v, n);
        if (a.face == RAYCACHE_NO_FACE) {
            why = MissReason::outside;
            return miss();
        }
        ++w.reads;
        float nearest;
        if (level == 0) {
            const std::optional<DepthSample> texel = cube.peek(v, &why);
            if (!texel) return miss();
            if (shared::raycache_relief_crosses(w, t, texel->distance))
                return shared::raycache_relief_bracket(w, safe, t, texel->distance, texel->color);
            nearest = texel->distance;
        } else {
            nearest = pyramid.min_distance(a.face, level, a.column >> level, a.row >> level);
            if (!(shared::raycache_length(v) < nearest)) {
                --level;
                continue;
            }
        }
        // Safe up to where the ray leaves this block or comes within `nearest` of the centre (the far root
        // of that sphere; 0 when it lies behind the origin, which the walk treats as any point behind t).
        const float reach = shared::raycache_sphere_exit(w.origin - w.centre, w.d, nearest);
        const float next = std::min(block_exit(w, t, a, level, n), reach);
        safe = std::max(safe, next);
        t = std::max(next, t) + std::max(1e-3f * w.epsilon, 1e-6f * (1.0f + t));
        level = std::min(level + 1, pyramid.levels());
    }
    return miss();
}

} // namespace detail
} // namespace raycache
