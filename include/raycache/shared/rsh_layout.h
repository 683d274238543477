/* raycache/shared/rsh_layout.h: the ray-space hierarchy of Roger, Assarsson and Holzschuch ("Whitted
 * ray-tracing for dynamic scenes using a ray-space hierarchy on the GPU", EGSR 2007), the part that C++
 * and GLSL share: node, pair, ray, primitive and hit layouts, the node of one ray, the enclosing node of
 * four children, and the cone-sphere test of the paper's equation 1.
 *
 * The hierarchy is a complete 4-ary tree over an array of rays whose length is a power of 4: level L
 * (the leaves) holds one node per ray, level l - 1 one node per 4 consecutive nodes of level l, level 0
 * the root. Laid out in Morton order over the screen, 4 consecutive rays are a 2 x 2 block of pixels,
 * as in the paper; no links are stored: the children of node k of level l are 4k..4k+3 of level l + 1.
 * All levels live in one array, level l from raycache_rsh_level_first(l).
 *
 * A node is a cone-sphere (8 floats): the sphere (centre, radius) encloses the origins of its rays, and
 * every ray's direction is within `spread` radians of `direction` (unit). A node with no ray (a pixel
 * with no secondary ray, or padding) has radius < 0 and is never entered.
 */
#ifndef RAYCACHE_SHARED_RSH_LAYOUT_H
#define RAYCACHE_SHARED_RSH_LAYOUT_H

#include "raycache/shared/language.h"

#ifdef __cplusplus
#include <cstddef>
namespace raycache {
namespace shared {
using glm::vec4;
using glm::cross;
using std::atan2;
using std::cos;
using std::tan;
#define RAYCACHE_ATAN2(y, x) atan2(y, x)
#else
#define RAYCACHE_ATAN2(y, x) atan(y, x)
#endif

/* 32 bytes in C++ and in GLSL std430. */
struct raycache_rsh_node {
    vec3 centre;
    float radius;    /* < 0: empty node */
    vec3 direction;  /* unit */
    float spread;    /* radians, 0..pi */
};

/* One (node, primitive) pair of the stream: the primitive's bounding sphere meets the node. */
struct raycache_rsh_pair {
    uint node;       /* index into the node array (all levels) */
    uint primitive;
};

/* A ray to trace: hits count in (0, tmax]; tmax <= 0 marks a slot with no ray (an empty leaf). */
struct raycache_rsh_ray {
    vec3 origin;
    float tmax;
    vec3 direction;  /* unit */
    uint tag;        /* the caller's (the tracer stores the pixel here); the engine does not read it */
};

/* A primitive: kind.w == 0: triangle with vertices a, b, c (xyz); kind.w == 1: sphere, a = (centre,
 * radius). 48 bytes. */
struct raycache_rsh_primitive {
    vec4 a;
    vec4 b;
    vec4 c;          /* triangle: third vertex; w: kind */
};

/* The closest hit of a ray: the primitive, and t as float bits. Read as one little-endian 64-bit word,
 * t_bits is the high half: positive floats order as their bits, so a 64-bit atomicMin keeps the closest
 * hit, and of equally close ones the smallest primitive index. RAYCACHE_RSH_NO_HIT in both: no hit. */
struct raycache_rsh_hit {
    uint primitive;
    uint t_bits;
};

#define RAYCACHE_RSH_NO_HIT 0xFFFFFFFFu
#define RAYCACHE_RSH_PI 3.14159265358979f
/* Cones wider than this are treated as containing every direction in front of and beside their sphere:
 * equation 1 needs tan and 1/cos, which blow up towards pi/2; a test that always answers "meets" there is
 * merely looser. */
#define RAYCACHE_RSH_WIDE_CONE 1.5f
/* Slack of the cone-sphere test, relative to the distances involved: rounding never rejects a sphere. */
#define RAYCACHE_RSH_SLACK 1e-5f
/* Added to every enclosing radius and spread, so that rounding in the build never shrinks a node. */
#define RAYCACHE_RSH_ANGLE_MARGIN 1e-6f

/* First index of level l in the node array: (4^l - 1) / 3. */
RAYCACHE_FN uint raycache_rsh_level_first(int level) {
    return ((1u << uint(2 * level)) - 1u) / 3u;
}

RAYCACHE_FN raycache_rsh_node raycache_rsh_empty_node() {
    raycache_rsh_node n;
    n.centre = vec3(0.0f);
    n.radius = -1.0f;
    n.direction = vec3(0.0f, 0.0f, 1.0f);
    n.spread = 0.0f;
    return n;
}

/* The leaf of one ray: a sphere of radius 0 at its origin, a cone of spread 0 along its direction. */
RAYCACHE_FN raycache_rsh_node raycache_rsh_leaf(raycache_rsh_ray ray) {
    if (!(ray.tmax > 0.0f)) return raycache_rsh_empty_node();
    raycache_rsh_node n;
    n.centre = ray.origin;
    n.radius = 0.0f;
    n.direction = ray.direction;
    n.spread = 0.0f;
    return n;
}

/* The angle between unit vectors a and b, accurate near 0 (acos of a dot product is not). */
RAYCACHE_FN float raycache_rsh_angle(vec3 a, vec3 b) {
    return RAYCACHE_ATAN2(length(cross(a, b)), dot(a, b));
}

/* The node enclosing four children (paper Figure 2): the sphere around the bounding box of the children's
 * spheres, with a radius reaching every child sphere; the cone along the children's mean direction, with a
 * spread reaching every child cone. Empty children are ignored; four empty children make an empty node. */
RAYCACHE_FN raycache_rsh_node raycache_rsh_enclose(raycache_rsh_node c0, raycache_rsh_node c1, raycache_rsh_node c2,
                                                   raycache_rsh_node c3) {
    raycache_rsh_node c[4];
    c[0] = c0;
    c[1] = c1;
    c[2] = c2;
    c[3] = c3;
    vec3 lo = vec3(3.0e38f), hi = vec3(-3.0e38f), sum = vec3(0.0f);
    int count = 0;
    for (int i = 0; i < 4; ++i) {
        if (c[i].radius < 0.0f) continue;
        vec3 a = c[i].centre - vec3(c[i].radius), b = c[i].centre + vec3(c[i].radius);
        lo = vec3(min(lo.x, a.x), min(lo.y, a.y), min(lo.z, a.z));
        hi = vec3(max(hi.x, b.x), max(hi.y, b.y), max(hi.z, b.z));
        sum += c[i].direction;
        ++count;
    }
    if (count == 0) return raycache_rsh_empty_node();
    raycache_rsh_node n;
    n.centre = 0.5f * (lo + hi);
    float radius = 0.0f;
    float scale = max(max(abs(n.centre.x), abs(n.centre.y)), abs(n.centre.z));
    float len = length(sum);
    bool wide = len < 1e-3f;
    n.direction = wide ? vec3(0.0f, 0.0f, 1.0f) : sum / len;
    float spread = 0.0f;
    for (int i = 0; i < 4; ++i) {
        if (c[i].radius < 0.0f) continue;
        radius = max(radius, length(c[i].centre - n.centre) + c[i].radius);
        scale = max(scale, max(max(abs(c[i].centre.x), abs(c[i].centre.y)), abs(c[i].centre.z)));
        spread = max(spread, raycache_rsh_angle(n.direction, c[i].direction) + c[i].spread);
    }
    n.radius = radius * (1.0f + RAYCACHE_RSH_SLACK) + RAYCACHE_RSH_SLACK * 1e-2f * scale;
    n.spread = wide ? RAYCACHE_RSH_PI : min(spread + RAYCACHE_RSH_ANGLE_MARGIN, RAYCACHE_RSH_PI);
    return n;
}

/* Whether some ray of `node` may meet the sphere s (centre s.xyz, radius s.w): the paper's equation 1,
 * the cone of apex C = node.centre, direction d and spread alpha against the sphere of centre P = s.xyz and
 * radius s.w + node.radius, with H the projection of P on the axis:
 *     CH tan(alpha) + (d + r) / cos(alpha) >= HP.
 * This is the signed distance from P to the cone's boundary line (in the plane of the axis and P) being at
 * most the enlarged radius, so it never rejects a sphere that a ray of the node meets (behind the apex it
 * accepts a little more than the cone). Conservative: a slack covers rounding; cones wider than
 * RAYCACHE_RSH_WIDE_CONE always meet. */
RAYCACHE_FN bool raycache_rsh_cone_sphere(raycache_rsh_node node, vec4 s) {
    if (node.radius < 0.0f) return false;
    float r = s.w + node.radius;
    if (node.spread >= RAYCACHE_RSH_WIDE_CONE) return true;
    vec3 cp = vec3(s.x, s.y, s.z) - node.centre;
    float ch = dot(cp, node.direction);
    float hp = length(cp - ch * node.direction);
    float slack = RAYCACHE_RSH_SLACK * (length(cp) + r);
    return ch * tan(node.spread) + r / cos(node.spread) + slack >= hp;
}

/* The bounding sphere of a primitive: a sphere is its own; a triangle's is centred on its centroid. */
RAYCACHE_FN vec4 raycache_rsh_bounding_sphere(raycache_rsh_primitive p) {
    if (p.c.w != 0.0f) return p.a;
    vec3 a = vec3(p.a.x, p.a.y, p.a.z), b = vec3(p.b.x, p.b.y, p.b.z), c = vec3(p.c.x, p.c.y, p.c.z);
    vec3 m = (a + b + c) / 3.0f;
    float r = max(length(a - m), max(length(b - m), length(c - m)));
    return vec4(m.x, m.y, m.z, r);
}

#ifdef __cplusplus
static_assert(sizeof(raycache_rsh_node) == 32 && offsetof(raycache_rsh_node, radius) == 12 &&
                  offsetof(raycache_rsh_node, direction) == 16 && offsetof(raycache_rsh_node, spread) == 28,
              "raycache_rsh_node must match GLSL std430");
static_assert(sizeof(raycache_rsh_pair) == 8 && sizeof(raycache_rsh_hit) == 8, "pair and hit: two uints");
static_assert(sizeof(raycache_rsh_ray) == 32 && offsetof(raycache_rsh_ray, tmax) == 12 &&
                  offsetof(raycache_rsh_ray, direction) == 16 && offsetof(raycache_rsh_ray, tag) == 28,
              "raycache_rsh_ray must match GLSL std430");
static_assert(sizeof(raycache_rsh_primitive) == 48, "raycache_rsh_primitive must match GLSL std430");
} // namespace shared
} // namespace raycache
#endif

#endif /* RAYCACHE_SHARED_RSH_LAYOUT_H */
