/* raycache/shared/cube_face.h: the caching cube's face table and texel addressing, shared by C++ and GLSL.
 *
 * Convention: OpenGL/Vulkan cube maps (thesis Table 3.1, eq. 3.6). Face i is
 * GL_TEXTURE_CUBE_MAP_POSITIVE_X + i and Vulkan cube layer i:
 *
 *   face   major axis   sc (-> column)   tc (-> row)
 *   +X 0   s.x > 0        -s.z             -s.y
 *   -X 1   s.x < 0        +s.z             -s.y
 *   +Y 2   s.y > 0        +s.x             +s.z
 *   -Y 3   s.y < 0        +s.x             -s.z
 *   +Z 4   s.z > 0        +s.x             -s.y
 *   -Z 5   s.z < 0        -s.x             -s.y
 *
 * tu = sc * (0.5 / |m|) + 0.5 in single precision, in exactly this order and without FMA: that is what
 * Mesa's samplers evaluate, and it picks the same texel as the driver at texel edges where the thesis's
 * (sc / |m| + 1) / 2 does not. column = clamp(floor(tu * N), 0, N - 1); row likewise from tc.
 *
 * Texel (face, column, row) of an N x N face has linear index (face * N + row) * N + column.
 */
#ifndef RAYCACHE_SHARED_CUBE_FACE_H
#define RAYCACHE_SHARED_CUBE_FACE_H

#include "raycache/shared/language.h"
#include "raycache/shared/rounding.h"

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

#define RAYCACHE_FACE_POSITIVE_X 0
#define RAYCACHE_FACE_NEGATIVE_X 1
#define RAYCACHE_FACE_POSITIVE_Y 2
#define RAYCACHE_FACE_NEGATIVE_Y 3
#define RAYCACHE_FACE_POSITIVE_Z 4
#define RAYCACHE_FACE_NEGATIVE_Z 5
#define RAYCACHE_FACE_COUNT 6
/* Returned instead of a face for a vector that is not a direction. */
#define RAYCACHE_NO_FACE (-1)

/* Face sizes a cube accepts, in texels along one edge. */
#define RAYCACHE_MIN_FACE_SIZE 1
#define RAYCACHE_MAX_FACE_SIZE 4096

/* A vector is a direction when its components are finite and its largest magnitude lies in
 * [2^-64, 2^64]. There 0.5/|m| is rounded alike on every device (raycache/shared/rounding.h), and a
 * subnormal component, which GPUs flush to zero, moves no texel: times 0.5/|m| it stays below 2^-27,
 * which vanishes when 0.5 is added. */
#define RAYCACHE_MIN_MAJOR_MAGNITUDE 5.42101086e-20 /* 2^-64 */
#define RAYCACHE_MAX_MAJOR_MAGNITUDE 1.84467441e+19 /* 2^64 */

/* A texel of the cube; face == RAYCACHE_NO_FACE when the vector it came from was not a direction. */
struct raycache_texel_address {
    int face;
    int column;
    int row;
};

/* True when x is neither infinite nor NaN (tested on the bits, so fast-math cannot remove it). */
RAYCACHE_FN bool raycache_is_finite(float x) {
    return (floatBitsToUint(x) & 0x7F800000u) != 0x7F800000u;
}

/* True when the sign bit of x is set (so -0.0 counts as negative, as the sampler's face choice does). */
RAYCACHE_FN bool raycache_sign_bit(float x) {
    return (floatBitsToUint(x) & 0x80000000u) != 0u;
}

/* True when s can be looked up: finite, and its major magnitude in the range above. */
RAYCACHE_FN bool raycache_is_direction(vec3 s) {
    if (!raycache_is_finite(s.x) || !raycache_is_finite(s.y) || !raycache_is_finite(s.z)) return false;
    float m = max(abs(s.x), max(abs(s.y), abs(s.z)));
    return m >= float(RAYCACHE_MIN_MAJOR_MAGNITUDE) && m <= float(RAYCACHE_MAX_MAJOR_MAGNITUDE);
}

/* Face of a direction. Ties between equal magnitudes go z over y over x, the order of the Vulkan
 * specification's face-selection rule and of Mesa's samplers; the face's sign is the major component's
 * sign bit. Returns RAYCACHE_NO_FACE when s is not a direction. */
RAYCACHE_FN int raycache_face_of(vec3 s) {
    if (!raycache_is_direction(s)) return RAYCACHE_NO_FACE;
    float ax = abs(s.x);
    float ay = abs(s.y);
    float az = abs(s.z);
    if (az >= ay && az >= ax) return raycache_sign_bit(s.z) ? RAYCACHE_FACE_NEGATIVE_Z : RAYCACHE_FACE_POSITIVE_Z;
    if (ay >= ax) return raycache_sign_bit(s.y) ? RAYCACHE_FACE_NEGATIVE_Y : RAYCACHE_FACE_POSITIVE_Y;
    return raycache_sign_bit(s.x) ? RAYCACHE_FACE_NEGATIVE_X : RAYCACHE_FACE_POSITIVE_X;
}

/* (sc, tc) of the table above for s on the given face, before division by |m|. */
RAYCACHE_FN vec2 raycache_face_coordinates(vec3 s, int face) {
    if (face == RAYCACHE_FACE_POSITIVE_X) return vec2(-s.z, -s.y);
    if (face == RAYCACHE_FACE_NEGATIVE_X) return vec2(s.z, -s.y);
    if (face == RAYCACHE_FACE_POSITIVE_Y) return vec2(s.x, s.z);
    if (face == RAYCACHE_FACE_NEGATIVE_Y) return vec2(s.x, -s.z);
    if (face == RAYCACHE_FACE_POSITIVE_Z) return vec2(s.x, -s.y);
    return vec2(-s.x, -s.y);
}

/* Magnitude of the major component of s on the given face. */
RAYCACHE_FN float raycache_major_magnitude(vec3 s, int face) {
    if (face <= RAYCACHE_FACE_NEGATIVE_X) return abs(s.x);
    if (face <= RAYCACHE_FACE_NEGATIVE_Y) return abs(s.y);
    return abs(s.z);
}

/* Position along one edge of a face, in texels (0 at the face's low edge, N at its high edge), for a
 * face coordinate sc and scale = 0.5 / |m|, in the driver's order: t = sc * scale + 0.5 (no FMA), t * N.
 * Nearest and linear filtering both start from it. */
RAYCACHE_FN float raycache_texel_position(float sc, float scale, int face_size) {
    RAYCACHE_PRECISE float scaled = raycache_no_fma(sc * scale);
    RAYCACHE_PRECISE float t = scaled + 0.5f;
    RAYCACHE_PRECISE float texels = raycache_no_fma(t * float(face_size));
    return texels;
}

/* Texel index along one edge: clamp(floor(t * N), 0, N - 1) of raycache_texel_position. The conversion
 * truncates instead of taking floor(): the two differ only for negative positions, which the clamp sends
 * to 0 either way, and without SSE4.1 a floor() is a dozen dependent instructions on every lookup. */
RAYCACHE_FN int raycache_texel_index(float sc, float scale, int face_size) {
    return clamp(int(raycache_texel_position(sc, scale, face_size)), 0, face_size - 1);
}

/* The texel a direction s falls in, on a cube of face_size x face_size texels per face.
 * s need not be unit length; a non-direction gives face RAYCACHE_NO_FACE, column and row 0. */
RAYCACHE_HOT_FN raycache_texel_address raycache_texel_of(vec3 s, int face_size) {
    raycache_texel_address address;
    address.face = raycache_face_of(s);
    address.column = 0;
    address.row = 0;
    if (address.face == RAYCACHE_NO_FACE) return address;
    vec2 st = raycache_face_coordinates(s, address.face);
    float scale = raycache_divide(0.5f, raycache_major_magnitude(s, address.face));
    address.column = raycache_texel_index(st.x, scale, face_size);
    address.row = raycache_texel_index(st.y, scale, face_size);
    return address;
}

/* Linear index of a texel in a cube stored face by face, row by row. */
RAYCACHE_FN uint raycache_texel_linear_index(raycache_texel_address a, int face_size) {
    return (uint(a.face) * uint(face_size) + uint(a.row)) * uint(face_size) + uint(a.column);
}

/* The table read backwards: the vector with major coordinate m along the face's axis and face
 * coordinates (sc, tc), so that raycache_face_coordinates gives (sc, tc) back. Linear in (m, sc, tc). */
RAYCACHE_FN vec3 raycache_face_point(int face, float m, float sc, float tc) {
    if (face == RAYCACHE_FACE_POSITIVE_X) return vec3(m, -tc, -sc);
    if (face == RAYCACHE_FACE_NEGATIVE_X) return vec3(-m, -tc, sc);
    if (face == RAYCACHE_FACE_POSITIVE_Y) return vec3(sc, m, tc);
    if (face == RAYCACHE_FACE_NEGATIVE_Y) return vec3(sc, -m, -tc);
    if (face == RAYCACHE_FACE_POSITIVE_Z) return vec3(sc, -tc, m);
    return vec3(-sc, -tc, -m);
}

/* The direction through the centre of a texel, with major component +-1 (not unit length).
 * Inverse of raycache_texel_of: raycache_texel_of(raycache_texel_direction(a, N), N) == a. */
RAYCACHE_FN vec3 raycache_texel_direction(raycache_texel_address a, int face_size) {
    float sc = 2.0f * raycache_divide(float(a.column) + 0.5f, float(face_size)) - 1.0f;
    float tc = 2.0f * raycache_divide(float(a.row) + 0.5f, float(face_size)) - 1.0f;
    return raycache_face_point(a.face, 1.0f, sc, tc);
}

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_CUBE_FACE_H */
