/* raycache/filter.glsl: filtered (bilinear) lookups in GLSL, seamless across face edges and corners, over
 * any storage: the includer says how to read one texel, as a function it names before the include (a
 * bridge function, as in RTXDI), and gets the weighted mean of the footprint, bit for bit C++'s
 * raycache::filtered_value (footprint, corner rule and arithmetic: raycache/shared/cube_filter.h).
 *
 *   #include "raycache/shared/cube_face.h"                        // raycache_texel_address
 *   bool my_fetch(raycache_texel_address texel, out vec3 color);  // false: empty texel (define it here
 *   #define RAYCACHE_FILTER_FETCH my_fetch                        //  or, as a prototype, anywhere later)
 *   #include "raycache/filter.glsl"                               // or "raycache/raycache.glsl"
 *   raycache_filter_result f = raycache_filtered_value(direction, face_size, 0.0);
 *
 * The fetch reads texel (face, column, row); raycache_texel_linear_index gives its element in a cube's
 * buffer (plus the cube's first_texel). Without RAYCACHE_FILTER_FETCH only the footprint and the sum are
 * defined: loop over raycache_filter_taps_of yourself, e.g. to read several cubes from one shader.
 */
#ifndef RAYCACHE_FILTER_GLSL
#define RAYCACHE_FILTER_GLSL

#include "raycache/shared/cube_filter.h"

/* What a filtered lookup found: hit, and then the filtered colour and the weight of the taps found. */
struct raycache_filter_result {
    bool hit;
    vec3 color;
    float weight;
};

/* The lookup's answer from the sum of the taps found: a hit when they weigh more than 0 and at least
 * min_weight (0: any non-empty tap answers), colour their renormalised weighted mean. */
raycache_filter_result raycache_filter_result_of(raycache_filter_sum sum, float min_weight) {
    raycache_filter_result r;
    r.hit = raycache_filter_sum_found(sum, min_weight);
    r.color = r.hit ? raycache_filter_sum_mean(sum) : vec3(0.0);
    r.weight = sum.weight;
    return r;
}

#ifdef RAYCACHE_FILTER_FETCH
/* The filtered colour for `direction` (need not be unit length) on a cube of face_size texels per edge,
 * reading each tap with RAYCACHE_FILTER_FETCH, in footprint order. A miss when direction is not a
 * direction (the fetch is not called), every tap is empty, or the taps found weigh less than min_weight. */
raycache_filter_result raycache_filtered_value(vec3 direction, int face_size, float min_weight) {
    raycache_filter_taps taps = raycache_filter_taps_of(direction, face_size);
    raycache_filter_sum sum = raycache_filter_sum_zero();
    for (int k = 0; k < taps.count; ++k) {
        vec3 color;
        if (RAYCACHE_FILTER_FETCH(taps.texel[k], color)) sum = raycache_filter_sum_add(sum, color, taps.weight[k]);
    }
    return raycache_filter_result_of(sum, min_weight);
}
#endif

#endif /* RAYCACHE_FILTER_GLSL */
