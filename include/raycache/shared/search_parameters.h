/* raycache/shared/search_parameters.h: what the CDCT's searches take and give, written once for C++ and
 * GLSL: the parameters (C++ raycache::ReliefParameters, GLSL raycache_relief_parameters: one struct, so a
 * std430 copy of the C++ struct's bytes, as a push constant or in a buffer, reads as the same parameters in
 * a shader), their defaults and limits, and the outcome of a search (raycache::ReliefResult, GLSL
 * raycache_relief_result).
 *
 * "Off" for max_gap is +infinity (RAYCACHE_NO_GAP_LIMIT), in both languages; 0 is not a valid max_gap.
 */
#ifndef RAYCACHE_SHARED_SEARCH_PARAMETERS_H
#define RAYCACHE_SHARED_SEARCH_PARAMETERS_H

#include "raycache/shared/ray_box.h"

/* Which search a CDCT lookup makes (the parameters' search field; raycache::DepthSearch in C++). */
#define RAYCACHE_DEPTH_SEARCH_SECANT 0
#define RAYCACHE_DEPTH_SEARCH_RELIEF 1

/* The most linear steps (or pyramid nodes) one relief search may take. max_steps above it is refused by
 * validate() and makes a search a miss without reading, in C++ and GLSL alike, so a search reads at most
 * 1 + RAYCACHE_MAX_RELIEF_STEPS + RAYCACHE_RELIEF_MAX_HALVINGS texels and its count fits an int. */
#define RAYCACHE_MAX_RELIEF_STEPS 16777216
/* Bisection steps after the relief walk's crossing, at most. */
#define RAYCACHE_RELIEF_MAX_HALVINGS 64
/* The most reads one secant search may take: max_reads above it is clamped to it. */
#define RAYCACHE_SECANT_MAX_READS 64

/* Defaults: step and epsilon are one of the thesis's (delta, epsilon) pairs. */
#define RAYCACHE_DEFAULT_RELIEF_STEP 0.2f
#define RAYCACHE_DEFAULT_EPSILON 0.02f
#define RAYCACHE_DEFAULT_MAX_STEPS 1024
#define RAYCACHE_DEFAULT_MAX_DEPTH 100.0f
#define RAYCACHE_NO_GAP_LIMIT RAYCACHE_INFINITY
#define RAYCACHE_DEFAULT_MAX_READS 8

#ifdef __cplusplus
#include <cstddef>
namespace raycache {

// How a CDCT lookup finds the ray's hit in the cube's depth image.
enum class DepthSearch : int {
    secant = RAYCACHE_DEPTH_SEARCH_SECANT, // a few reads: jump to the sphere of the distance read, then false
                                           // position (shared/depth_secant.h)
    relief = RAYCACHE_DEPTH_SEARCH_RELIEF, // the thesis's walk in steps of `step` (over a DepthPyramid when one
                                           // is given), then bisection (shared/relief_walk.h)
};

namespace shared {
#define RAYCACHE_SEARCH_FIELD DepthSearch
#define RAYCACHE_DEFAULT_SEARCH DepthSearch::secant
#else
#define RAYCACHE_SEARCH_FIELD int
#define RAYCACHE_DEFAULT_SEARCH RAYCACHE_DEPTH_SEARCH_SECANT
#endif

/* Tuning of the CDCT's searches (raycache::ReliefParameters in C++). */
struct raycache_relief_parameters {
    /* relief: delta, length of a linear step along the ray, world units, > 0 */
    float step RAYCACHE_DEFAULT(RAYCACHE_DEFAULT_RELIEF_STEP);
    /* relief: bisection stops when the bracket is shorter than this; secant: accept |f| <= epsilon or a
     * bracket this short; > 0 */
    float epsilon RAYCACHE_DEFAULT(RAYCACHE_DEFAULT_EPSILON);
    /* relief: linear steps, or pyramid nodes read, before giving up (a miss); 1..RAYCACHE_MAX_RELIEF_STEPS */
    int max_steps RAYCACHE_DEFAULT(RAYCACHE_DEFAULT_MAX_STEPS);
    /* distance at which rays that escaped to the environment are stored, and the most a hit is stored at */
    float max_depth RAYCACHE_DEFAULT(RAYCACHE_DEFAULT_MAX_DEPTH);
    /* A crossing where the ray ends up more than max_gap beyond the cached surface (|Q - C| - d, after
     * refinement) is a depth discontinuity: the ray passed behind an edge, where the cube saw nothing.
     * Such a crossing is a miss instead of the wrong surface. RAYCACHE_NO_GAP_LIMIT (infinity, the thesis)
     * accepts every crossing. > 0. */
    float max_gap RAYCACHE_DEFAULT(RAYCACHE_NO_GAP_LIMIT);
    /* the search a CDCT lookup makes (C++ relief_search and GLSL raycache_relief_search always walk) */
    RAYCACHE_SEARCH_FIELD search RAYCACHE_DEFAULT(RAYCACHE_DEFAULT_SEARCH);
    /* secant: reads before giving up (a miss), 1..RAYCACHE_SECANT_MAX_READS (clamped) */
    int max_reads RAYCACHE_DEFAULT(RAYCACHE_DEFAULT_MAX_READS);
};

/* Outcome of a search (raycache::ReliefResult in C++). On a hit, `point` is where the ray meets the cached
 * surface (within epsilon along the ray) and `color` the texel seen there; on a miss only texels_read is
 * set. */
struct raycache_relief_result {
    bool hit RAYCACHE_DEFAULT(false);
    vec3 color RAYCACHE_DEFAULT(vec3(0.0f));
    vec3 point RAYCACHE_DEFAULT(vec3(0.0f));     /* origin + distance * unit(direction) */
    float distance RAYCACHE_DEFAULT(0.0f);       /* along the unit ray direction, from the origin to point */
    int texels_read RAYCACHE_DEFAULT(0);         /* texels (and pyramid nodes) read, hit or miss */
};

/* The default parameters (what a default-made raycache::ReliefParameters holds). */
RAYCACHE_FN raycache_relief_parameters raycache_default_relief_parameters() {
    raycache_relief_parameters p;
    p.step = RAYCACHE_DEFAULT_RELIEF_STEP;
    p.epsilon = RAYCACHE_DEFAULT_EPSILON;
    p.max_steps = RAYCACHE_DEFAULT_MAX_STEPS;
    p.max_depth = RAYCACHE_DEFAULT_MAX_DEPTH;
    p.max_gap = RAYCACHE_NO_GAP_LIMIT;
    p.search = RAYCACHE_DEFAULT_SEARCH;
    p.max_reads = RAYCACHE_DEFAULT_MAX_READS;
    return p;
}

/* A search's outcome: a hit at distance t along unit d from origin seeing `color`, or a miss. */
RAYCACHE_FN raycache_relief_result raycache_search_result(bool hit, vec3 origin, vec3 d, float t, vec3 color,
                                                          int texels_read) {
    raycache_relief_result r;
    r.hit = hit;
    r.color = hit ? color : vec3(0.0f);
    r.point = hit ? raycache_ray_point(origin, d, t) : vec3(0.0f);
    r.distance = hit ? t : 0.0f;
    r.texels_read = texels_read;
    return r;
}

#ifdef __cplusplus
static_assert(sizeof(raycache_relief_parameters) == 28 && offsetof(raycache_relief_parameters, max_gap) == 16 &&
                  offsetof(raycache_relief_parameters, search) == 20 &&
                  offsetof(raycache_relief_parameters, max_reads) == 24 && sizeof(DepthSearch) == 4,
              "raycache_relief_parameters must keep GLSL's std430 layout: seven 4-byte fields");
} // namespace shared

// Tuning of the CDCT's search (fields and defaults above).
using ReliefParameters = shared::raycache_relief_parameters;
// Outcome of a relief or secant search.
using ReliefResult = shared::raycache_relief_result;
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_SEARCH_PARAMETERS_H */
