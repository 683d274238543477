/* raycache/shared/cdct_store.h: what the CDCT stores, written once for C++ and GLSL.
 *
 * A traced ray's colour goes into the texel of a key (a vector from the cube's centre) at a distance:
 *   hit at point P      key P - centre, distance |P - centre| clamped to max_depth
 *   escaped (infinite   key the ray's direction, distance max_depth
 *   or NaN distance)
 *   negative distance   nothing (the hit lies behind the ray's origin; the colour is used, the cube left alone)
 * and a (colour, distance) pair becomes the texel uvec2(RGB9E5 colour, distance bits), refused for a
 * negative, NaN or infinite distance (-0 is stored as +0). The language supplies the write (C++:
 * CacheCube::store, GLSL: a 64-bit atomicMin into the pending buffer), where the nearest distance, then the
 * smaller colour word, wins among one frame's stores into a texel.
 */
#ifndef RAYCACHE_SHARED_CDCT_STORE_H
#define RAYCACHE_SHARED_CDCT_STORE_H

#include "raycache/shared/ray_box.h"
#include "raycache/shared/texel_encoding.h"

#ifdef __cplusplus
namespace raycache {
namespace shared {
#endif

/* Where a store goes. A key with no texel ((0, 0, 0), for a bad hit point or box) makes a store that is
 * refused; store false makes none at all. */
struct raycache_cdct_store_key {
    bool store;
    vec3 key;
    float distance;
};

RAYCACHE_FN raycache_cdct_store_key raycache_cdct_make_store_key(bool store, vec3 key, float distance) {
    raycache_cdct_store_key k;
    k.store = store;
    k.key = key;
    k.distance = distance;
    return k;
}

/* A hit at hit_point, for the cube of box centre +- half_size. */
RAYCACHE_FN raycache_cdct_store_key raycache_cdct_hit_store(vec3 hit_point, vec3 centre, float half_size, float max_depth) {
    if (!raycache_is_finite3(hit_point) || !raycache_box_is_usable(centre, half_size))
        return raycache_cdct_make_store_key(true, vec3(0.0f), -1.0f);
    RAYCACHE_PRECISE vec3 from_centre = hit_point - centre;
    float length = raycache_length(from_centre);
    return raycache_cdct_make_store_key(true, from_centre, (max_depth < length) ? max_depth : length);
}

/* A ray that escaped to the environment in `direction`: stored as far away as the cube stores anything. */
RAYCACHE_FN raycache_cdct_store_key raycache_cdct_escape_store(vec3 direction, float max_depth) {
    return raycache_cdct_make_store_key(true, direction, max_depth);
}

/* A ray traced from origin along direction that reported `distance` along its unit direction to its hit
 * (infinity or NaN: it escaped). Nothing is stored for a negative distance or a direction that is not one. */
RAYCACHE_FN raycache_cdct_store_key raycache_cdct_traced_store(vec3 origin, vec3 direction, float distance, vec3 centre,
                                                               float half_size, float max_depth) {
    if (!raycache_is_direction(direction) || distance < 0.0f) return raycache_cdct_make_store_key(false, vec3(0.0f), -1.0f);
    if (!raycache_is_finite(distance)) return raycache_cdct_escape_store(direction, max_depth);
    return raycache_cdct_hit_store(raycache_ray_point(origin, raycache_unit(direction), distance), centre, half_size,
                                   max_depth);
}

/* The texel a store of `color` at `distance` writes; the invalid texel (refused) unless the distance is a
 * finite number >= 0. Decided on the bits, so no float comparison can be folded away. */
RAYCACHE_FN uvec2 raycache_cdct_store_texel(vec3 color, float distance) {
    uint bits = floatBitsToUint(distance);
    if (bits == 0x80000000u) bits = 0u; /* -0 becomes +0 */
    if ((bits & 0x80000000u) != 0u || !raycache_is_finite(distance))
        return uvec2(RAYCACHE_CDCT_INVALID_COLOR, RAYCACHE_CDCT_INVALID_DISTANCE);
    return uvec2(raycache_pack_rgb9e5(color), bits);
}

#ifdef __cplusplus
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_CDCT_STORE_H */
