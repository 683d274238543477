/* raycache/shared/cone_sphere.h: which cached texels a moved object can have changed, by cones and spheres.
 *
 * A cached texel answers rays that leave the object's box (or a smaller origin region) in the directions
 * of the texel. Those rays all lie in a cone: rays from any point of a ball (centre c, radius R) in any
 * direction within `spread` of `axis` meet a sphere (s, r) exactly when the cone from c itself (same axis
 * and spread) meets the grown sphere (s, r + R): move the ray by c - p, its point moves by at most R.
 * So one cone-sphere test, equation 1 of Roger, Assarsson and Holzschuch, "Whitted ray-tracing for
 * dynamic scenes using a ray-space hierarchy on the GPU" (EGSR 2007), decides a whole region of texels:
 *
 *     the sphere meets the cone  <=>  |s - c| <= r  or  angle(s - c, axis) <= spread + asin(r / |s - c|)
 *
 * (the directions from c to the sphere are a cap of angular radius asin(r / |s - c|); two caps meet when
 * their centres are at most the sum of their radii apart). Evaluated with cosines, no acos.
 *
 * Everything here errs on the side of "meets": spreads are widened by RAYCACHE_CONE_SLACK radians for the
 * texel choice's rounding and the comparison has a relative margin, so a texel can be dropped needlessly,
 * never kept wrongly. Spreads are at most 90 degrees (a cube face's cone is 54.7).
 *
 * Written in the language subset of raycache/shared/language.h; the C++ library uses it today (the GLSL
 * side has no invalidation yet: see the README, "Dynamic scenes").
 */
#ifndef RAYCACHE_SHARED_CONE_SPHERE_H
#define RAYCACHE_SHARED_CONE_SPHERE_H

#include "raycache/shared/cube_face.h"

/* Widening of every derived spread, radians: covers float rounding of the texel choice at region edges. */
#define RAYCACHE_CONE_SLACK 1.0e-4

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

/* A cone of directions: a unit axis and the cosine and sine of its half-angle (the spread). */
struct raycache_direction_cone {
    vec3 axis;
    float cos_spread;
    float sin_spread;
};

/* Roger et al. 2007, equation 1: true when the sphere (centre, radius) meets the infinite cone with apex
 * `apex`, unit axis and the given spread (<= 90 degrees). Conservative under rounding. */
RAYCACHE_FN bool raycache_cone_meets_sphere(vec3 apex, raycache_direction_cone cone, vec3 centre, float radius) {
    if (cone.cos_spread <= -1.0f) return true; /* every direction (raycache_cone_toward_ball) */
    vec3 v = centre - apex;
    float d2 = dot(v, v);
    if (d2 <= radius * radius) return true; /* the apex lies in the sphere */
    float d = sqrt(d2);
    float sin_cap = radius / d;
    float cos_cap = sqrt(max(0.0f, 1.0f - sin_cap * sin_cap));
    /* cos(spread + cap); spread + cap < 180 degrees, where cos decreases, so the angle test is this one. */
    float cos_sum = cone.cos_spread * cos_cap - cone.sin_spread * sin_cap;
    return dot(v, cone.axis) >= d * cos_sum - 1.0e-5f * d;
}

/* Rays leaving any point of the ball (ball_centre, ball_radius) in any direction of `cone` meet the sphere
 * (centre, radius) only if this is true (and whenever one does, it is: the Minkowski argument above). */
RAYCACHE_FN bool raycache_rays_from_ball_meet_sphere(vec3 ball_centre, float ball_radius, raycache_direction_cone cone,
                                                     vec3 centre, float radius) {
    return raycache_cone_meets_sphere(ball_centre, cone, centre, radius + ball_radius);
}

/* The cone of half-angle acos(spread_cos) around unit `axis` widened by RAYCACHE_CONE_SLACK, capped at 90 degrees. */
RAYCACHE_FN raycache_direction_cone raycache_widened_cone(vec3 axis, float spread_cos) {
    float c = clamp(spread_cos, 0.0f, 1.0f);
    float s = sqrt(max(0.0f, 1.0f - c * c));
    raycache_direction_cone cone;
    cone.axis = axis;
    /* cos(a + e) = cos a cos e - sin a sin e, with cos e = 1 in float for e = 1e-4 */
    cone.cos_spread = max(0.0f, c - s * float(RAYCACHE_CONE_SLACK));
    cone.sin_spread = sqrt(max(0.0f, 1.0f - cone.cos_spread * cone.cos_spread));
    return cone;
}

/* The cone around unit `axis` of half-angle a, given as cos a and sin a (both computed to float precision:
 * narrow cones' sines come from cross products, which keep their digits where cosines near 1 lose them),
 * widened by RAYCACHE_CONE_SLACK and capped at 90 degrees: cos(a + e) = cos a - e sin a and sin(a + e) =
 * sin a + e cos a (cos e = 1 in float for e = 1e-4), the cosine lowered by 2 ulps of 1 for its rounding. */
RAYCACHE_FN raycache_direction_cone raycache_widened_cone_of(vec3 axis, float spread_cos, float spread_sin) {
    float c = clamp(spread_cos, 0.0f, 1.0f);
    float s = clamp(spread_sin, 0.0f, 1.0f);
    raycache_direction_cone cone;
    cone.axis = axis;
    cone.cos_spread = max(0.0f, c - s * float(RAYCACHE_CONE_SLACK) - 1.2e-7f);
    cone.sin_spread = min(1.0f, s + c * float(RAYCACHE_CONE_SLACK));
    return cone;
}

/* The cone of every direction through texels [column0, column1) x [row0, row1) of `face` on faces of
 * face_size texels (a texel, a 16 x 16 tile, a whole face): its axis through the region's centre, its spread
 * to the farthest corner. The region is the central projection of a rectangle, so it is the geodesic hull of
 * its corners, and a cap of at most 90 degrees that holds the corners holds all of it.
 * Worked in the face's own coordinates (s, t, 1), which raycache_face_point turns by a signed permutation,
 * so angles are the same there. Every corner lies within 90 degrees of the axis (s sm + t tm + 1 > 0 for a
 * corner (s, t) and the centre (sm, tm) of a region of one face: s sm, t tm >= -1/8), so the farthest
 * corner is the one of largest sine, |(s, t, 1) x (sm, tm, 1)| / (|(s, t, 1)| |(sm, tm, 1)|), compared
 * squared without a square root per corner; the sine from the cross product keeps a narrow region's
 * spread, which its cosine (1 - ~1e-7 on faces of thousands of texels) would round away. */
RAYCACHE_FN float raycache_region_corner_cross2(float s, float t, float sm, float tm) {
    float x = t - tm;
    float y = sm - s;
    float z = s * tm - t * sm;
    return x * x + y * y + z * z;
}
RAYCACHE_FN float raycache_region_corner_norm2(float s, float t) { return s * s + t * t + 1.0f; }
RAYCACHE_FN raycache_direction_cone raycache_region_cone(int face, int column0, int row0, int column1, int row1,
                                                         int face_size) {
    float n = float(face_size);
    float s0 = 2.0f * (float(column0) / n) - 1.0f;
    float s1 = 2.0f * (float(column1) / n) - 1.0f;
    float t0 = 2.0f * (float(row0) / n) - 1.0f;
    float t1 = 2.0f * (float(row1) / n) - 1.0f;
    float sm = 0.5f * (s0 + s1);
    float tm = 0.5f * (t0 + t1);
    float inverse_length = 1.0f / sqrt(raycache_region_corner_norm2(sm, tm));
    /* The corner of largest cross^2 / norm^2: compared as cross_a norm_b > cross_b norm_a (norms positive). */
    float best_cross2 = raycache_region_corner_cross2(s0, t0, sm, tm);
    float best_norm2 = raycache_region_corner_norm2(s0, t0);
    float x = raycache_region_corner_cross2(s1, t0, sm, tm);
    float q = raycache_region_corner_norm2(s1, t0);
    if (x * best_norm2 > best_cross2 * q) { best_cross2 = x; best_norm2 = q; }
    x = raycache_region_corner_cross2(s0, t1, sm, tm);
    q = raycache_region_corner_norm2(s0, t1);
    if (x * best_norm2 > best_cross2 * q) { best_cross2 = x; best_norm2 = q; }
    x = raycache_region_corner_cross2(s1, t1, sm, tm);
    q = raycache_region_corner_norm2(s1, t1);
    if (x * best_norm2 > best_cross2 * q) { best_cross2 = x; best_norm2 = q; }
    /* Rounded up by a few ulps: the sine bounds the cone from outside. */
    float sine = min(1.0f, sqrt(best_cross2 / best_norm2) * inverse_length * 1.000001f);
    float cosine = sqrt(max(0.0f, 1.0f - sine * sine));
    return raycache_widened_cone_of(raycache_face_point(face, inverse_length, sm * inverse_length, tm * inverse_length), cosine, sine);
}

/* The cone of every direction through texel (column, row) of `face`, as raycache_region_cone of that one
 * texel but with one normalisation instead of five: its axis through the texel's centre point p on the
 * plane at distance 1, its spread a bound on the angle from there to any point q of the texel. Direction
 * changes with a point x of the plane at most |dx| / |x| (the projection's largest stretch), so the angle is
 * at most |q - p| / min |x| over the texel: at most sqrt(2) / n (the half-diagonal of a texel 2/n wide) over
 * sqrt(1 + r^2), r the distance from the face's centre to the texel's nearest point. cos(spread) is taken as
 * 1 - spread^2 / 2, which is never above it (a wider cone, conservative). At most ~15% wider than the
 * corners' cone on faces of 16 texels or more. */
RAYCACHE_FN raycache_direction_cone raycache_texel_cone(int face, int column, int row, int face_size) {
    float n = float(face_size);
    float sc = 2.0f * ((float(column) + 0.5f) / n) - 1.0f;
    float tc = 2.0f * ((float(row) + 0.5f) / n) - 1.0f;
    float near_s = max(0.0f, abs(sc) - 1.0f / n);
    float near_t = max(0.0f, abs(tc) - 1.0f / n);
    /* At least 1e-3 rad: floats near 1 resolve cosines only to ~6e-8, an angle of ~3.5e-4 (faces of more than
     * about 1400 texels). */
    float spread = max((1.41421356f / n) / sqrt(1.0f + near_s * near_s + near_t * near_t), 1.0e-3f);
    return raycache_widened_cone(normalize(raycache_face_point(face, 1.0f, sc, tc)), 1.0f - 0.5f * spread * spread);
}

/* The cone from `apex` that holds the ball (centre, radius): every segment from the apex to a point of the
 * ball lies in it (shadow rays from a region of hit points to a point light). When the apex lies in the
 * ball, a cone of every direction (cos_spread = -1), which meets every sphere. */
RAYCACHE_FN raycache_direction_cone raycache_cone_toward_ball(vec3 apex, vec3 centre, float radius) {
    vec3 v = centre - apex;
    float d = length(v);
    raycache_direction_cone cone;
    if (!(d > radius)) {
        cone.axis = vec3(0.0f, 1.0f, 0.0f);
        cone.cos_spread = -1.0f; /* a full sphere of directions: meets everything */
        cone.sin_spread = 0.0f;
        return cone;
    }
    float s = radius / d;
    return raycache_widened_cone_of(v / d, sqrt(max(0.0f, 1.0f - s * s)), s); /* the sine as it is: narrow cones keep it */
}

/* The cosine of the angle between unit `axis` and the direction of `corner`; -1 for a corner at (0, 0, 0). */
RAYCACHE_FN float raycache_corner_cos(vec3 axis, vec3 corner) {
    float l = length(corner);
    return l > 0.0f ? dot(axis, corner) / l : -1.0f;
}

/* A cone that holds every unit direction inside the box [lo, hi] (the componentwise bounds of a set of
 * unit directions: where a path's bounces escaped). The directions of a box form the convex cone over it,
 * and the angle from the axis is largest at one of its 8 corners while that cone stays within 90 degrees
 * (a cap of at most 90 degrees is convex): so the spread reaches the farthest corner. A box reaching 90
 * degrees or more from its centre's direction (one around (0, 0, 0) among them) gives every direction
 * (cos_spread = -1, which meets every sphere). */
RAYCACHE_FN raycache_direction_cone raycache_cone_of_direction_box(vec3 lo, vec3 hi) {
    raycache_direction_cone every;
    every.axis = vec3(0.0f, 1.0f, 0.0f);
    every.cos_spread = -1.0f;
    every.sin_spread = 0.0f;
    vec3 middle = 0.5f * (lo + hi);
    float l = length(middle);
    if (!(l > 0.0f)) return every;
    vec3 axis = middle / l;
    float c = 1.0f;
    c = min(c, raycache_corner_cos(axis, vec3(lo.x, lo.y, lo.z)));
    c = min(c, raycache_corner_cos(axis, vec3(hi.x, lo.y, lo.z)));
    c = min(c, raycache_corner_cos(axis, vec3(lo.x, hi.y, lo.z)));
    c = min(c, raycache_corner_cos(axis, vec3(hi.x, hi.y, lo.z)));
    c = min(c, raycache_corner_cos(axis, vec3(lo.x, lo.y, hi.z)));
    c = min(c, raycache_corner_cos(axis, vec3(hi.x, lo.y, hi.z)));
    c = min(c, raycache_corner_cos(axis, vec3(lo.x, hi.y, hi.z)));
    c = min(c, raycache_corner_cos(axis, vec3(hi.x, hi.y, hi.z)));
    /* 1e-5 below 0: a cap that reaches 90 degrees within rounding is not trusted to be convex. */
    if (!(c > 1.0e-5f)) return every;
    return raycache_widened_cone(axis, c - 1.0e-6f);
}

/* Rays leaving any point of the ball (ball_centre, ball_radius) in any unit direction inside the box
 * [lo, hi] meet the sphere (centre, radius) only if this is true: a direction that meets the sphere grown
 * by the ball lies within asin((radius + ball_radius) / |centre - ball_centre|) of a, the unit direction
 * to the centre, and the box's best alignment with a (each component from lo or hi) bounds dot(d, a) for
 * every d inside it. A second necessary condition beside raycache_cone_of_direction_box's cone: a box that
 * reaches 90 degrees from its centre's direction (whose cone is every direction) still rejects spheres on
 * the side that none of its directions face. */
RAYCACHE_FN bool raycache_direction_box_may_reach_sphere(vec3 ball_centre, float ball_radius, vec3 lo, vec3 hi, vec3 centre,
                                                         float radius) {
    vec3 v = centre - ball_centre;
    float d = length(v);
    float grown = radius + ball_radius;
    if (!(d > grown)) return true; /* the ball meets the sphere */
    vec3 a = v / d;
    float best = max(lo.x * a.x, hi.x * a.x) + max(lo.y * a.y, hi.y * a.y) + max(lo.z * a.z, hi.z * a.z);
    float s = grown / d;
    /* the cap's cosine, lowered by the cone slack and a margin for rounding (conservative) */
    float cos_cap = sqrt(max(0.0f, 1.0f - s * s)) - s * float(RAYCACHE_CONE_SLACK) - 1.0e-5f;
    return best >= cos_cap;
}

/* A ball: a centre and a radius. */
struct raycache_ball {
    vec3 centre;
    float radius;
};

/* A ball holding every point apex + r u with u a unit direction of `cone` and near_distance <= r <=
 * far_distance (0 <= near_distance <= far_distance, finite: where a CDCT texel's searches end). Its
 * centre lies on the axis at the middle distance m; |r u - m axis|^2 = (r - m)^2 + 2 r m (1 - cos(angle))
 * grows with the angle and, m being the middle, is largest at the far end: on the rim at far_distance.
 * Widened for rounding. */
RAYCACHE_FN raycache_ball raycache_cone_shell_ball(vec3 apex, raycache_direction_cone cone, float near_distance, float far_distance) {
    float m = 0.5f * (near_distance + far_distance);
    /* 1 - cos as sin^2 / (1 + cos) for cones under 90 degrees, which keeps narrow cones' digits */
    float c = max(cone.cos_spread, -1.0f);
    float one_minus_cos = (c > 0.0f) ? cone.sin_spread * cone.sin_spread / (1.0f + c) : 1.0f - c;
    float at_far = (far_distance - m) * (far_distance - m) + 2.0f * far_distance * m * one_minus_cos;
    raycache_ball ball;
    ball.centre = apex + m * cone.axis;
    ball.radius = sqrt(max(at_far, 0.0f)) * 1.0001f + 1.0e-5f * far_distance;
    return ball;
}

/* True when the sphere (centre, radius) meets the convex hull of the balls (a, ra) and (b, rb): when some
 * segment from a point of one ball to a point of the other can meet it (a CDCT texel answers rays from the
 * box's ball that end at its stored surface). Growing both balls by `radius` reduces this to whether the
 * centre lies in the hull of the grown balls (radii ga = ra + radius, gb = rb + radius), a round cone. In
 * the plane of its axis and the point (x along the axis from a, y >= 0 away from it), that hull is the two
 * discs and the quadrilateral a, T_a, T_b, b between them, T_a and T_b where the outer common tangent
 * touches: its normal is n = (sin, cos), sin = (ga - gb) / |b - a|, the tangent line n . q = ga, and along
 * it t = (cos, -sin), t . T_a = 0, t . T_b = cos |b - a|. Errs on the side of "meets" (radii and bounds
 * widened for rounding). */
RAYCACHE_FN bool raycache_ball_hull_meets_sphere(vec3 a, float ra, vec3 b, float rb, vec3 centre, float radius) {
    vec3 ab = b - a;
    vec3 ap = centre - a;
    vec3 bp = centre - b;
    float l = length(ab);
    float slack = 1.0e-5f * (l + length(ap) + ra + rb + radius) + 1.0e-6f;
    float ga = (ra + radius) * 1.00001f + slack;
    float gb = (rb + radius) * 1.00001f + slack;
    if (dot(ap, ap) <= ga * ga || dot(bp, bp) <= gb * gb) return true;
    if (!(l > abs(ga - gb))) return false; /* one ball holds the other: the hull is that ball, tested above */
    vec3 axis = ab / l;
    float x = dot(ap, axis);
    float y = length(ap - x * axis); /* not sqrt(|ap|^2 - x^2), which loses y near the axis */
    float s = (ga - gb) / l;
    float c = sqrt(max(0.0f, 1.0f - s * s));
    float along = c * x - s * y;
    float across = s * x + c * y;
    return along >= -slack && along <= c * l + slack && across <= ga;
}

/* True when the sphere (centre, radius) meets the box [lo, hi] (distance from the centre to the box). */
RAYCACHE_FN bool raycache_box_meets_sphere(vec3 lo, vec3 hi, vec3 centre, float radius) {
    vec3 nearest = vec3(clamp(centre.x, lo.x, hi.x), clamp(centre.y, lo.y, hi.y), clamp(centre.z, lo.z, hi.z));
    vec3 v = centre - nearest;
    return dot(v, v) <= radius * radius * (1.0f + 1.0e-5f) + 1.0e-12f;
}

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_CONE_SPHERE_H */
