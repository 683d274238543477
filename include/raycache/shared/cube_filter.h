/* raycache/shared/cube_filter.h: filtered (bilinear) lookups in a caching cube, seamless across face edges
 * and corners, shared by C++ and GLSL: for a direction and a face size, which texels to read (at most 4)
 * and with what weights, and the weighted mean of what was read.
 *
 * The footprint is the Vulkan specification's LINEAR filtering of a cube map (sections "Cube Map Face
 * Selection and Transformations", "Unnormalized Texel Coordinate Operations", "Linear Filtering" and
 * "Cube Map Edge Handling"):
 *   - face and position in texels as raycache_texel_of: same tie rule, u = (sc * (0.5 / |m|) + 0.5) * N
 *     rounded step by step, no FMA (raycache_texel_position); likewise v from tc;
 *   - i0 = floor(u - 0.5), j0 = floor(v - 0.5), i1 = i0 + 1, j1 = j0 + 1, alpha = (u - 0.5) - i0,
 *     beta = (v - 0.5) - j0; weights (1 - alpha)(1 - beta), alpha (1 - beta), (1 - alpha) beta,
 *     alpha beta for (i0, j0), (i1, j0), (i0, j1), (i1, j1);
 *   - edges: a tap one texel past one edge of the face (i or j = -1 or N, the other inside) is the texel
 *     of the adjacent face that touches the same stretch of that edge (raycache_wrapped_texel);
 *   - corners: a tap past two edges at once has no texel (three faces meet there). Rule: its weight is
 *     shared equally by the other three taps, which is the fourth texel taken as the average of the other
 *     three, the method the specification recommends and Mesa's llvmpipe/lavapipe implements.
 * Taps whose weight is 0 are left out, so count is 1 to 4 for a direction and 0 for anything else
 * (zero, NaN, infinite, outside raycache_is_direction's range) or for a face size outside 1..4096.
 * The weights sum to 1 up to float rounding (a few units in the last place).
 *
 * Every sum is of values rounded on their own (precise / raycache_no_fma), so C++ and GLSL give the same
 * bits, with or without FMA contraction.
 */
#ifndef RAYCACHE_SHARED_CUBE_FILTER_H
#define RAYCACHE_SHARED_CUBE_FILTER_H

#include "raycache/shared/cube_face.h"

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

/* Texels a filtered lookup reads at most. */
#define RAYCACHE_FILTER_MAX_TAPS 4
/* 1/3 rounded to float: the share of a missing corner tap's weight that each of the other three gets. */
#define RAYCACHE_FILTER_CORNER_SHARE 0.333333343f

/* The texels of a filtered lookup and their weights: entries 0 .. count - 1 are used, in the order
 * (i0, j0), (i1, j0), (i0, j1), (i1, j1) less the taps left out. */
struct raycache_filter_taps {
    int count;
    raycache_texel_address texel[RAYCACHE_FILTER_MAX_TAPS];
    float weight[RAYCACHE_FILTER_MAX_TAPS];
};

/* The texel read for the tap (column, row) of `face` that lies one texel past exactly one edge of the
 * face (column or row is -1 or N, the other in 0 .. N-1): the texel of the adjacent face that touches the
 * same stretch of that edge. Worked on the face table in units of 1/N, where texel centres lie at the
 * integers 2k + 1 - N and the edges at +-N (all exact in float): the coordinate past the edge becomes the
 * adjacent face's major axis (+-N), and this face's axis becomes a coordinate of the adjacent face, at
 * its first texel in from the shared edge (N - 1). */
RAYCACHE_FN raycache_texel_address raycache_wrapped_texel(int face, int column, int row, int face_size) {
    float n = float(face_size);
    float sc = float(2 * column + 1 - face_size);
    float tc = float(2 * row + 1 - face_size);
    if (column < 0 || column >= face_size) {
        sc = (column < 0) ? -n : n;
    } else {
        tc = (row < 0) ? -n : n;
    }
    vec3 p = raycache_face_point(face, n - 1.0f, sc, tc);
    raycache_texel_address a;
    a.face = raycache_face_of(p);
    vec2 st = raycache_face_coordinates(p, a.face);
    a.column = (int(st.x) + face_size - 1) / 2;
    a.row = (int(st.y) + face_size - 1) / 2;
    return a;
}

/* The bilinear footprint of direction s (need not be unit length) on a cube of face_size texels per
 * edge: see the top of this file. */
RAYCACHE_FN raycache_filter_taps raycache_filter_taps_of(vec3 s, int face_size) {
    raycache_filter_taps taps;
    taps.count = 0;
    for (int k = 0; k < RAYCACHE_FILTER_MAX_TAPS; ++k) {
        taps.texel[k].face = RAYCACHE_NO_FACE;
        taps.texel[k].column = 0;
        taps.texel[k].row = 0;
        taps.weight[k] = 0.0f;
    }
    int face = raycache_face_of(s);
    if (face == RAYCACHE_NO_FACE || face_size < RAYCACHE_MIN_FACE_SIZE || face_size > RAYCACHE_MAX_FACE_SIZE)
        return taps;
    vec2 st = raycache_face_coordinates(s, face);
    float scale = raycache_divide(0.5f, raycache_major_magnitude(s, face));
    RAYCACHE_PRECISE float u = raycache_texel_position(st.x, scale, face_size) - 0.5f;
    RAYCACHE_PRECISE float v = raycache_texel_position(st.y, scale, face_size) - 0.5f;
    float u0 = floor(u);
    float v0 = floor(v);
    RAYCACHE_PRECISE float alpha = u - u0;
    RAYCACHE_PRECISE float beta = v - v0;
    RAYCACHE_PRECISE float alpha0 = 1.0f - alpha;
    RAYCACHE_PRECISE float beta0 = 1.0f - beta;
    RAYCACHE_PRECISE float w00 = raycache_no_fma(alpha0 * beta0);
    RAYCACHE_PRECISE float w10 = raycache_no_fma(alpha * beta0);
    RAYCACHE_PRECISE float w01 = raycache_no_fma(alpha0 * beta);
    RAYCACHE_PRECISE float w11 = raycache_no_fma(alpha * beta);
    float w[RAYCACHE_FILTER_MAX_TAPS];
    w[0] = w00;
    w[1] = w10;
    w[2] = w01;
    w[3] = w11;
    int i0 = int(u0);
    int j0 = int(v0);

    /* The corner tap, if one lies past two edges: its weight goes to the other three in equal shares. */
    int corner = -1;
    for (int k = 0; k < RAYCACHE_FILTER_MAX_TAPS; ++k) {
        int i = i0 + (k & 1);
        int j = j0 + (k >> 1);
        if ((i < 0 || i >= face_size) && (j < 0 || j >= face_size)) corner = k;
    }
    RAYCACHE_PRECISE float share = 0.0f;
    if (corner >= 0) share = raycache_no_fma(w[corner] * RAYCACHE_FILTER_CORNER_SHARE);

    for (int k = 0; k < RAYCACHE_FILTER_MAX_TAPS; ++k) {
        if (k == corner) { continue; } /* braces: clang reads the empty RAYCACHE_PRECISE below as misleading indentation */
        RAYCACHE_PRECISE float weight = w[k] + share;
        if (!(weight > 0.0f)) continue;
        int i = i0 + (k & 1);
        int j = j0 + (k >> 1);
        raycache_texel_address a;
        if (i < 0 || i >= face_size || j < 0 || j >= face_size) {
            a = raycache_wrapped_texel(face, i, j, face_size);
        } else {
            a.face = face;
            a.column = i;
            a.row = j;
        }
        taps.texel[taps.count] = a;
        taps.weight[taps.count] = weight;
        taps.count += 1;
    }
    return taps;
}

/* A running weighted sum of the texels a filtered lookup found (empty texels are not added). */
struct raycache_filter_sum {
    vec3 color;   /* sum of weight * colour */
    float weight; /* sum of the weights */
};

RAYCACHE_FN raycache_filter_sum raycache_filter_sum_zero() {
    raycache_filter_sum sum;
    sum.color = vec3(0.0f);
    sum.weight = 0.0f;
    return sum;
}

/* sum plus one texel's colour at the given weight, each product rounded on its own. */
RAYCACHE_FN raycache_filter_sum raycache_filter_sum_add(raycache_filter_sum sum, vec3 color, float weight) {
    RAYCACHE_PRECISE vec3 weighted = vec3(raycache_no_fma(color.x * weight), raycache_no_fma(color.y * weight),
                                          raycache_no_fma(color.z * weight));
    RAYCACHE_PRECISE vec3 total = sum.color + weighted;
    RAYCACHE_PRECISE float total_weight = sum.weight + weight;
    sum.color = total;
    sum.weight = total_weight;
    return sum;
}

/* True when the texels found weigh enough to answer the lookup: more than 0, and at least min_weight
 * (0: any non-empty tap answers; 1: only a full footprint does). */
RAYCACHE_FN bool raycache_filter_sum_found(raycache_filter_sum sum, float min_weight) {
    return sum.weight > 0.0f && sum.weight >= min_weight;
}

/* The filtered value: the weighted mean of the texels found, their weights renormalised to sum 1, so
 * that an empty tap does not darken it. Only for a sum that raycache_filter_sum_found accepts. */
RAYCACHE_FN vec3 raycache_filter_sum_mean(raycache_filter_sum sum) {
    vec3 mean = vec3(raycache_divide(sum.color.x, sum.weight), raycache_divide(sum.color.y, sum.weight),
                     raycache_divide(sum.color.z, sum.weight));
    return mean;
}

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_CUBE_FILTER_H */
