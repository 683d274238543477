/* raycache/shared/ray_box.h: the small geometry of the CDCT's searches that C++ and GLSL must evaluate
 * alike: a direction made unit length, a vector's length in glm's order, a ray's points, where a ray
 * leaves a cube's box, and which boxes can be searched. Products are rounded on their own (never fused
 * into an FMA), so both languages, and C++ built with or without FMA contraction, give the same bits.
 */
#ifndef RAYCACHE_SHARED_RAY_BOX_H
#define RAYCACHE_SHARED_RAY_BOX_H

#include "raycache/shared/cube_face.h"

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

/* True when no component of v is infinite or NaN. */
RAYCACHE_FN bool raycache_is_finite3(vec3 v) {
    return raycache_is_finite(v.x) && raycache_is_finite(v.y) && raycache_is_finite(v.z);
}

/* |v| as glm::length computes it: sqrt((x*x + y*y) + z*z). */
RAYCACHE_FN float raycache_length(vec3 v) {
    RAYCACHE_PRECISE float squared = (raycache_no_fma(v.x * v.x) + raycache_no_fma(v.y * v.y)) + raycache_no_fma(v.z * v.z);
    float length = raycache_sqrt(squared);
    return length;
}

/* The ray's point o + t d, each product rounded on its own (never fused into an FMA). */
RAYCACHE_FN vec3 raycache_ray_point(vec3 o, vec3 d, float t) {
    RAYCACHE_PRECISE vec3 p = o + vec3(raycache_no_fma(t * d.x), raycache_no_fma(t * d.y), raycache_no_fma(t * d.z));
    return p;
}

/* The ray's point at t seen from a cube's centre: (o + t d) - centre, without FMA. */
RAYCACHE_FN vec3 raycache_ray_from_centre(vec3 o, vec3 d, float t, vec3 centre) {
    RAYCACHE_PRECISE vec3 v = raycache_ray_point(o, d, t) - centre;
    return v;
}

/* Unit vector along a direction, divided by its major magnitude first, so its length cannot overflow.
 * `direction` must be a direction (raycache_is_direction). */
RAYCACHE_FN vec3 raycache_unit(vec3 direction) {
    vec3 a = abs(direction);
    float major = max(a.x, max(a.y, a.z));
    vec3 scaled = vec3(raycache_divide(direction.x, major), raycache_divide(direction.y, major), raycache_divide(direction.z, major));
    float length = raycache_length(scaled);
    vec3 unit = vec3(raycache_divide(scaled.x, length), raycache_divide(scaled.y, length), raycache_divide(scaled.z, length));
    return unit;
}

/* True when a cube's box can be searched: finite centre, finite half-size > 0. */
RAYCACHE_FN bool raycache_box_is_usable(vec3 centre, float half_size) {
    return raycache_is_finite3(centre) && half_size > 0.0f && raycache_is_finite(half_size);
}

/* Distance along unit d from o to where the ray leaves the box centre +- half_size (0 if that is
 * behind o). */
RAYCACHE_FN float raycache_box_exit_distance(vec3 o, vec3 d, vec3 centre, float half_size) {
    float exit = uintBitsToFloat(0x7F800000u); /* +infinity */
    for (int axis = 0; axis < 3; ++axis) {
        if (d[axis] == 0.0f) continue; /* parallel to this slab: it never bounds the exit */
        RAYCACHE_PRECISE float face = centre[axis] + (d[axis] > 0.0f ? half_size : -half_size);
        RAYCACHE_PRECISE float from_origin = face - o[axis];
        float t = raycache_divide(from_origin, d[axis]);
        exit = (t < exit) ? t : exit;
    }
    return (exit < 0.0f) ? 0.0f : exit;
}

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_RAY_BOX_H */
