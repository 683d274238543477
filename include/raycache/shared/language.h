/* raycache/shared/language.h: lets the files in raycache/shared/ compile as both C++17 (with GLM) and GLSL 4.50.
 *
 * Shared files use only the common subset of the two languages: vec3/uvec2/uint/int/float/bool,
 * if/else, for, ?:, bit operations, floatBitsToUint/uintBitsToFloat, abs/floor/min/max/clamp/sqrt/dot,
 * fixed-size arrays (also as struct members) filled element by element (no initializer lists).
 * Functions are declared RAYCACHE_FN; out-parameters are avoided (return values or structs instead).
 * Where a language must supply something (a texel fetch), the shared code is a state machine: the
 * language's loop reads what the state asks for and hands it back (see depth_secant.h, relief_walk.h).
 */
#ifndef RAYCACHE_SHARED_LANGUAGE_H
#define RAYCACHE_SHARED_LANGUAGE_H

#ifdef __cplusplus
#include <cstdint>
#include <cmath>
#include <algorithm>
#include <limits>
#include <glm/glm.hpp>

namespace raycache {
namespace shared {
using glm::vec2;
using glm::vec3;
using glm::ivec3;
using glm::uvec2;
using uint = std::uint32_t;
using glm::floatBitsToUint;
using glm::uintBitsToFloat;
using std::abs;
using std::floor;
using std::sqrt;
using glm::abs;
using glm::floor;
using glm::dot;
using glm::length;
using glm::normalize;
/* GLSL's scalar min/max/clamp; std::min would take (int, uint) mixes silently wrong, these do not. */
inline int min(int a, int b) { return a < b ? a : b; }
inline int max(int a, int b) { return a > b ? a : b; }
inline uint min(uint a, uint b) { return a < b ? a : b; }
inline uint max(uint a, uint b) { return a > b ? a : b; }
inline float min(float a, float b) { return b < a ? b : a; }
inline float max(float a, float b) { return a < b ? b : a; }
inline int clamp(int x, int lo, int hi) { return min(max(x, lo), hi); }
inline float clamp(float x, float lo, float hi) { return min(max(x, lo), hi); }

/* Returns x unchanged, but opaque to the optimiser, so that the product that produced x is rounded
 * on its own and never fused with a following addition into an FMA (which GCC does under
 * -ffp-contract=fast, its default for GNU C++ on FMA targets). GLSL gets the same from `precise`. */
inline float raycache_no_fma(float x) {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    __asm__("" : "+x"(x));
#elif defined(__GNUC__) && defined(__aarch64__)
    __asm__("" : "+w"(x));
#else
    volatile float opaque = x;
    x = opaque;
#endif
    return x;
}
} // namespace shared
} // namespace raycache

#define RAYCACHE_FN inline
/* RAYCACHE_FN for a function on every cached ray's path that returns a struct: inlined into its callers,
 * since as a call GCC builds the returned struct on the stack and reloads it in one wider load, which
 * stalls on store forwarding (a third of the face choice's time in a profile of the Embree tracer). */
#if defined(__GNUC__) || defined(__clang__)
#define RAYCACHE_HOT_FN inline __attribute__((always_inline))
#else
#define RAYCACHE_HOT_FN inline
#endif
/* GLSL `precise` keeps the compiler from fusing a*b+c into an FMA. C++ has no such qualifier:
 * see RAYCACHE_NO_FMA below, applied to the one product where it matters. */
#define RAYCACHE_PRECISE
#define RAYCACHE_CONST constexpr
/* A struct member's default value: C++ gives it (`float step RAYCACHE_DEFAULT(0.2f);`), GLSL has none
 * (its structs are built by a function that assigns the same macros). */
#define RAYCACHE_DEFAULT(value) = value
/* +infinity as a float expression. */
#define RAYCACHE_INFINITY (std::numeric_limits<float>::infinity())
/* A parameter the function updates in place: a reference in C++, `inout` in GLSL (for state that a loop
 * advances step by step, which copied in and out by value costs C++ more than the step itself). */
#define RAYCACHE_INOUT(type) type&
/* A struct parameter only read: a const reference in C++ (no copy), `in` in GLSL. */
#define RAYCACHE_IN(type) const type&

#else /* GLSL */

#define RAYCACHE_FN
#define RAYCACHE_HOT_FN
#define RAYCACHE_PRECISE precise
#define RAYCACHE_CONST const
#define raycache_no_fma(x) (x)
#define RAYCACHE_DEFAULT(value)
#define RAYCACHE_INFINITY uintBitsToFloat(0x7F800000u)
#define RAYCACHE_INOUT(type) inout type
#define RAYCACHE_IN(type) in type

#endif /* __cplusplus */

#endif /* RAYCACHE_SHARED_LANGUAGE_H */
