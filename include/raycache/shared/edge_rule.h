/* raycache/shared/edge_rule.h: the confidence test's rule, shared by C++ (raycache/edge_confidence.hpp)
 * and GLSL (the end-of-frame mark pass, raycache/end_frame.glsl), so that both mark the same texels.
 *
 * Two neighbouring texels' colours (linear radiance, as decoded from RGB9E5) differ when some channel
 * differs by more than the threshold. A threshold below 0, or NaN, turns the test off.
 */
#ifndef RAYCACHE_SHARED_EDGE_RULE_H
#define RAYCACHE_SHARED_EDGE_RULE_H

#include "raycache/shared/language.h"

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

/* True when the test runs at this threshold: threshold >= 0 (false for NaN). */
RAYCACHE_FN bool raycache_edge_test_enabled(float threshold) {
    return threshold >= 0.0f;
}

/* True when colours a and b differ by more than `threshold` in some channel. */
RAYCACHE_FN bool raycache_colours_differ(vec3 a, vec3 b, float threshold) {
    vec3 d = abs(a - b);
    return max(d.x, max(d.y, d.z)) > threshold;
}

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_EDGE_RULE_H */
