/* raycache/shared/texel_encoding.h: the bit layouts of the CCT and CDCT texels, shared by C++ and GLSL.
 *
 * Colour: RGB9E5 (three 9-bit mantissas, one shared 5-bit exponent, bias 15; the layout of
 * VK_FORMAT_E5B9G9R9_UFLOAT_PACK32 / GL_RGB9_E5). Channels are clamped to [0, RAYCACHE_RGB9E5_MAX];
 * NaN becomes 0, +inf the maximum. Worst-case error of a channel after a round trip: half a step of the
 * shared exponent, at most max(r, g, b) * 2^-9 * 1024/1023 (0.196 % of the brightest channel; the
 * 1024/1023 comes from colours just under a power of two, whose exponent rounds up), or 2^-25 absolute
 * for colours under 2^-16.
 *
 * CCT texel, 4 bytes: one RGB9E5 word. 0xFFFFFFFF (all mantissas 511 at exponent 31) never comes out of
 * the encoder, because channels are clamped to 510/512 * 2^16, so it marks an invalid texel.
 *
 * CDCT texel, 8 bytes: uvec2(x = RGB9E5 colour, y = distance from the cube's centre as float32 bits).
 * The texel is valid when the distance is a non-negative number; invalid texels hold (0, -1.0).
 * Distances are exact float32 (no extra error). In C++ the pair is one 64-bit word, x in the low half,
 * so on little-endian machines a C++ buffer of these words reads as uvec2 in GLSL and back.
 */
#ifndef RAYCACHE_SHARED_TEXEL_ENCODING_H
#define RAYCACHE_SHARED_TEXEL_ENCODING_H

#include "raycache/shared/cube_face.h"

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

/* Largest channel value stored: 510/512 * 2^16. */
#define RAYCACHE_RGB9E5_MAX 65280.0f
#define RAYCACHE_CCT_INVALID 0xFFFFFFFFu
#define RAYCACHE_CDCT_INVALID_COLOR 0u
#define RAYCACHE_CDCT_INVALID_DISTANCE 0xBF800000u /* -1.0f */

/* 2^e as a float, exact, for e in [-126, 127]. */
RAYCACHE_FN float raycache_exp2i(int e) {
    return uintBitsToFloat(uint(e + 127) << 23);
}

/* A colour channel made storable: NaN and negatives -> 0, above the maximum (and +inf) -> maximum. */
RAYCACHE_FN float raycache_storable_channel(float x) {
    if (!raycache_is_finite(x)) return (x > 0.0f) ? RAYCACHE_RGB9E5_MAX : 0.0f;
    return clamp(x, 0.0f, RAYCACHE_RGB9E5_MAX);
}

/* RGB -> RGB9E5 word, rounding each mantissa to nearest (EXT_texture_shared_exponent's algorithm,
 * with floor(log2(max)) read from the float's exponent bits instead of computed with log2). */
/* q rounded to the nearest whole number, halves up, for 0 <= q < 2^23. Not floor(q + 0.5): that sum rounds
 * to 1.0 in float for q = 0.5 - 2^-25, so values just under half a step would round up. q - floor(q) is
 * exact (Sterbenz), so comparing it with 0.5 is too. floor(q) is the truncating conversion, q being
 * non-negative (cheaper than floor() without SSE4.1). */
RAYCACHE_FN uint raycache_round_half_up(float q) {
    uint whole = uint(q);
    return whole + ((q - float(whole) >= 0.5f) ? 1u : 0u);
}

RAYCACHE_FN uint raycache_pack_rgb9e5(vec3 color) {
    float r = raycache_storable_channel(color.x);
    float g = raycache_storable_channel(color.y);
    float b = raycache_storable_channel(color.z);
    float brightest = max(r, max(g, b));
    int floor_log2 = int((floatBitsToUint(brightest) >> 23) & 0xFFu) - 127; /* -127 for 0 and subnormals */
    int shared_exponent = max(-16, floor_log2) + 16;                     /* biased, in [0, 31] */
    /* 1 / (one mantissa unit), a power of two: x * units is exactly x / unit, without a division. */
    float units = raycache_exp2i(24 - shared_exponent);
    if (raycache_round_half_up(brightest * units) == 512u) {
        shared_exponent += 1;
        units *= 0.5f;
    }
    uint rm = raycache_round_half_up(r * units);
    uint gm = raycache_round_half_up(g * units);
    uint bm = raycache_round_half_up(b * units);
    return rm | (gm << 9) | (bm << 18) | (uint(shared_exponent) << 27);
}

/* RGB9E5 word -> RGB. */
RAYCACHE_FN vec3 raycache_unpack_rgb9e5(uint word) {
    float step = raycache_exp2i(int(word >> 27) - 24);
    return vec3(float(word & 0x1FFu) * step, float((word >> 9) & 0x1FFu) * step, float((word >> 18) & 0x1FFu) * step);
}

RAYCACHE_FN bool raycache_cct_is_valid(uint word) {
    return word != RAYCACHE_CCT_INVALID;
}

/* A CDCT texel holding color at distance d (d must be >= 0 and finite to be valid). */
RAYCACHE_FN uvec2 raycache_cdct_pack(vec3 color, float distance) {
    return uvec2(raycache_pack_rgb9e5(color), floatBitsToUint(distance));
}

RAYCACHE_FN bool raycache_cdct_is_valid(uvec2 texel) {
    return (texel.y & 0x80000000u) == 0u && texel.y < 0x7F800000u; /* non-negative and finite */
}

RAYCACHE_FN float raycache_cdct_distance(uvec2 texel) {
    return uintBitsToFloat(texel.y);
}

RAYCACHE_FN vec3 raycache_cdct_color(uvec2 texel) {
    return raycache_unpack_rgb9e5(texel.x);
}

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_TEXEL_ENCODING_H */
