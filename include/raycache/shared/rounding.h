/* raycache/shared/rounding.h: division and square root rounded to nearest, as IEEE 754 (and so C++)
 * rounds them, in GLSL too.
 *
 * Vulkan lets a device divide within 2.5 ulp and take square roots less exactly still; lavapipe rounds
 * correctly, NVIDIA's driver does not. Shared code that must give C++'s bits on every device divides with
 * raycache_divide and takes roots with raycache_sqrt. In C++ they are the plain operators. In GLSL they
 * take the device's result and correct it with products and sums alone, which Vulkan rounds correctly
 * on every device (its fma may round twice, and does on lavapipe):
 *   1. one Newton step makes the result faithful (within one ulp) from a start within a few ulps;
 *   2. the residual of a faithful result, a - q b or x - s s, is a float (Boldo and Daumas), and
 *      Dekker's exact product gives it exactly;
 *   3. its size, against the exact half gap to the neighbour on its side, says which of the two is
 *      nearer. A quotient or a root of floats is never exactly halfway, so there is no tie to break.
 * Outside [2^-90, 2^90] (operands and results) a residual could underflow; there the device's result is
 * returned unchanged, and may differ from C++'s by the device's error. The texel choice never meets such
 * numbers (its scale 0.5 / |major axis| stays refinable for every unit direction); distances do only past
 * about 3.5e13 (a squared length over 2^90) and direction components under 2^-90 of the major one, where
 * C++ and GLSL agree only on devices that round correctly (lavapipe does).
 * The refinements are shared code, so C++ tests them from deliberately perturbed starts.
 */
#ifndef RAYCACHE_SHARED_ROUNDING_H
#define RAYCACHE_SHARED_ROUNDING_H

#include "raycache/shared/language.h"

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

#define RAYCACHE_REFINABLE_MIN 8.07793567e-28 /* 2^-90 */
#define RAYCACHE_REFINABLE_MAX 1.23794004e+27 /* 2^90 */

/* True when |v| lies in [2^-90, 2^90], where the refinements' residuals cannot underflow. */
RAYCACHE_FN bool raycache_refinable(float v) {
    float m = abs(v);
    return m >= float(RAYCACHE_REFINABLE_MIN) && m <= float(RAYCACHE_REFINABLE_MAX);
}

/* The float next to x (finite, not zero) towards +infinity when `up`, else towards -infinity. */
RAYCACHE_FN float raycache_next_float(float x, bool up) {
    uint bits = floatBitsToUint(x);
    return uintBitsToFloat(((x > 0.0f) == up) ? bits + 1u : bits - 1u);
}

/* a - q b, exactly when that is a float and q b lies within a factor 2 of a: q b = p + e by Dekker's
 * product (Veltkamp's split into 12-bit halves, every product exact or rounded on its own), a - p is
 * exact by Sterbenz's lemma, and so is the last difference, whose exact value is a float. */
RAYCACHE_FN float raycache_residual(float a, float q, float b) {
    RAYCACHE_PRECISE float cq = raycache_no_fma(4097.0f * q);
    RAYCACHE_PRECISE float q_hi = cq - (cq - q);
    RAYCACHE_PRECISE float q_lo = q - q_hi;
    RAYCACHE_PRECISE float cb = raycache_no_fma(4097.0f * b);
    RAYCACHE_PRECISE float b_hi = cb - (cb - b);
    RAYCACHE_PRECISE float b_lo = b - b_hi;
    RAYCACHE_PRECISE float p = raycache_no_fma(q * b);
    RAYCACHE_PRECISE float e = ((raycache_no_fma(q_hi * b_hi) - p) + raycache_no_fma(q_hi * b_lo) + raycache_no_fma(q_lo * b_hi)) +
                               raycache_no_fma(q_lo * b_lo);
    RAYCACHE_PRECISE float r = (a - p) - e;
    return r;
}

/* a / b rounded to nearest, from a quotient q0 and a reciprocal y of b each within a few ulps. */
RAYCACHE_FN float raycache_divide_refined(float a, float b, float q0, float y) {
    if (!raycache_refinable(a) || !raycache_refinable(b) || !raycache_refinable(q0)) return q0;
    RAYCACHE_PRECISE float q = q0 + raycache_no_fma(raycache_residual(a, q0, b) * y); /* faithful */
    float r = raycache_residual(a, q, b);                                            /* exactly a - q b */
    if (r == 0.0f) return q;
    float n = raycache_next_float(q, (r > 0.0f) == (b > 0.0f)); /* the neighbour on a / b's side */
    RAYCACHE_PRECISE float half_gap_b = (0.5f * abs(n - q)) * abs(b); /* exact: a power of two times b */
    return abs(r) > half_gap_b ? n : q;
}

/* sqrt(x) rounded to nearest, from a root s0 and h0 ~ 0.5 / s0 each within a few ulps. */
RAYCACHE_FN float raycache_sqrt_refined(float x, float s0, float h0) {
    if (!raycache_refinable(x) || !raycache_refinable(s0) || !(x > 0.0f)) return s0;
    RAYCACHE_PRECISE float s = s0 + raycache_no_fma(raycache_residual(x, s0, s0) * h0); /* faithful */
    float r = raycache_residual(x, s, s);                                               /* exactly x - s s */
    if (r == 0.0f) return s;
    float n = raycache_next_float(s, r > 0.0f);
    /* The midpoint m = s +- g/2 squares to s s +- s g + g g / 4; r and s g are multiples of ulp(s)^2 and
     * g g / 4 is smaller, so x lies beyond m exactly when r > s g (above) or r <= -s g (below). */
    RAYCACHE_PRECISE float s_gap = s * abs(n - s); /* exact: a power of two times s */
    return r > 0.0f ? (r > s_gap ? n : s) : (-r >= s_gap ? n : s);
}

#ifdef __cplusplus
/* IEEE 754 division and square root already round to nearest. */
RAYCACHE_FN float raycache_divide(float a, float b) { return a / b; }
RAYCACHE_FN float raycache_sqrt(float x) { return std::sqrt(x); }
#elif defined(RAYCACHE_NATIVE_ROUNDING)
/* The device's own division and root: for a device known to round them correctly (lavapipe), where the
 * refinement changes nothing and costs the CDCT's searches about 5%. */
float raycache_divide(float a, float b) { precise float q = a / b; return q; }
float raycache_sqrt(float x) { precise float s = sqrt(x); return s; }
#else
float raycache_divide(float a, float b) {
    precise float q0 = a / b;
    precise float y = 1.0 / b;
    return raycache_divide_refined(a, b, q0, y);
}
float raycache_sqrt(float x) {
    precise float s0 = sqrt(x);
    precise float h0 = 0.5 / s0;
    return raycache_sqrt_refined(x, s0, h0);
}
#endif

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_ROUNDING_H */
