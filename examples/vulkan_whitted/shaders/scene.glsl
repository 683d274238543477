// scene.glsl: what the tracing compute shader (whitted.comp) and the raster G-buffer pass (gbuffer.vert,
// gbuffer.frag) share: the scene buffers (bindings 5..8), glm-ordered float helpers, Embree's sphere and
// triangle tests, the BVH traversal, and the primary ray through a pixel's centre.
#ifndef WHITTED_SCENE_GLSL
#define WHITTED_SCENE_GLSL

#include "raycache/cube.glsl" // RAYCACHE_INFINITY, raycache_length (glm's order); declares no buffers
#include "primitives.glsl"   // pdot, pnormalize, pcross, hit_sphere, hit_triangle_vertices

struct Node {        // 32 bytes; leaf: b > 0 primitives from a; inner: b == 0, children a and a + 1
    vec3 lo;
    int a;
    vec3 hi;
    int b;
};
struct Prim {        // sphere: p0 = (centre, radius); triangle: p0..p2 vertices, n0..n2 vertex normals
    vec4 p0, p1, p2;
    vec4 n0, n1, n2;
    uvec4 info;      // x: 0 sphere, 1 triangle; y: object (= Embree geometry id: spheres, then meshes); z: triangle
                     // of its mesh; w: index in scene order (gpu_scene.hpp), the same in a BVH's leaf order
};
struct Object {
    vec4 m0;         // diffuse, specular
    vec4 m1;         // checker colour, shininess
    vec4 m2;         // reflectivity, transparency, ior, checker scale
    vec4 m3;         // checker (0/1), cached (0/1), is sphere (0/1), -
    vec4 m4;         // sphere: centre, radius
};

layout(std430, binding = 5) readonly buffer Nodes { Node nodes[]; };
layout(std430, binding = 6) readonly buffer Prims { Prim prims[]; };
layout(std430, binding = 7) readonly buffer Objects { Object objects[]; };
layout(std430, binding = 8) readonly buffer Params {
    vec4 eye;
    vec4 forward;
    vec4 right;
    vec4 up;
    vec4 light_position;  // w: ambient
    vec4 light_intensity; // w: tan(fov_y / 2)
    vec4 environment;     // w: aspect
    ivec4 frame;          // width, height, mode, max depth
    vec4 relief;          // step, epsilon, max depth, max gap
    ivec4 relief_i;       // max steps, search (RAYCACHE_DEPTH_SEARCH_*), max reads, pixel stride (whitted.comp:
                          // a warm-up pass traces pixels whose x and y are multiples of it; 0 or 1: every pixel;
                          // -S: every pixel but those of a warm-up over every S-th, final already)
    vec4 origin_test;     // CCT origin test: drift (x the cube's half-size; < 0: off), parallax (inf: none)
};

// ---- intersection ------------------------------------------------------------------------------------

bool hit_triangle(Prim p, vec3 o, vec3 d, float tfar, inout float t, inout float u, inout float v) {
    return hit_triangle_vertices(p.p0.xyz, p.p1.xyz, p.p2.xyz, o, d, tfar, t, u, v);
}

bool hit_box(vec3 lo, vec3 hi, vec3 o, vec3 inv, float tfar) {
    vec3 a = (lo - o) * inv;
    vec3 b = (hi - o) * inv;
    vec3 tmin = min(a, b), tmax = max(a, b);
    float t0 = max(max(tmin.x, tmin.y), max(tmin.z, 0.0));
    float t1 = min(min(tmax.x, tmax.y), min(tmax.z, tfar));
    return t0 <= t1 * 1.00000024; // a little slack: never miss a box by rounding
}

// The nearest hit in [0, tfar] (any: the first found, for shadow rays); prim -1 when none.
Hit intersect(vec3 o, vec3 d, float tfar, bool any) {
    Hit h;
    h.t = tfar;
    h.prim = -1;
    h.u = 0.0;
    h.v = 0.0;
    vec3 safe = vec3(abs(d.x) < 1e-30 ? 1e-30 : d.x, abs(d.y) < 1e-30 ? 1e-30 : d.y, abs(d.z) < 1e-30 ? 1e-30 : d.z);
    vec3 inv = 1.0 / safe;
    int stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        Node n = nodes[stack[--top]];
        if (!hit_box(n.lo, n.hi, o, inv, h.t)) continue;
        if (n.b > 0) {
            for (int i = n.a; i < n.a + n.b; ++i) {
                Prim p = prims[i];
                float t = 0.0, u = 0.0, v = 0.0;
                bool hit = p.info.x == 0u ? hit_sphere(p.p0, o, d, h.t, t) : hit_triangle(p, o, d, h.t, t, u, v);
                if (hit) {
                    h.t = t;
                    h.prim = i;
                    h.u = u;
                    h.v = v;
                    if (any) return h;
                }
            }
        } else if (top < 62) {
            stack[top++] = n.a + 1;
            stack[top++] = n.a;
        }
    }
    return h;
}

// The unit direction of the primary ray through the centre of pixel (x, y), row 0 at the top (as
// rcx::primary_direction, with the camera basis from rcx::camera_basis on the CPU).
vec3 primary_direction(int x, int y) {
    int width = frame.x, height = frame.y;
    float tan_half = light_intensity.w, aspect = environment.w;
    precise float sx = (2.0 * (float(x) + 0.5) / float(width) - 1.0) * tan_half * aspect;
    precise float sy = (1.0 - 2.0 * (float(y) + 0.5) / float(height)) * tan_half;
    precise vec3 dir = forward.xyz + sx * right.xyz + sy * up.xyz;
    return pnormalize(dir);
}

#endif /* WHITTED_SCENE_GLSL */
