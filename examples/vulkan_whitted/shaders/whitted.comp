#version 450
// whitted.comp: the Whitted tracer of examples/embree_whitted/tracer.cpp in a compute shader, one
// invocation per pixel: a stack-based traversal of a BVH built on the CPU (Embree's BVH builder),
// spheres and triangles as primitives, and the recursion replaced by an explicit stack of rays with
// throughput weights (colour is linear in the children's colours, so the sum is the same).
//
// Caching (Params.mode: 0 off, 1 cct, 2 cdct, 3 ceiling): a ray leaving a cached object, met on the way
// of a primary ray's tree, goes through the object's cube (RayCache's GLSL include, which counts the
// lookups and lists the stored texels for the end-of-frame pass, end_frame.comp); on a miss its subtree is
// traced with trace_subtree(), which does not consult caches again (GLSL has no recursion), and stored. Hybrid (mode + 16): the primary ray's hit is read from the G-buffer
// that the raster pass wrote (gbuffer.vert/.frag) instead of traced. Compiled twice: without
// WHITTED_CDCT (off, cct, ceiling: no 64-bit atomics needed) and with it (cdct).
#extension GL_GOOGLE_include_directive : require
// RayCache's confidence test: doubtful texels (marked by end_frame.comp's mark pass) read as empty.
#define RAYCACHE_CONFIDENCE
#define RAYCACHE_CCT_DOUBTFUL_BINDING 12
#define RAYCACHE_CDCT_DOUBTFUL_BINDING 13
#ifndef WHITTED_CDCT
// RayCache's origin test (CCT): a tile answers rays from near the origins it was stored from.
#define RAYCACHE_ORIGINS
#define RAYCACHE_CCT_ORIGINS_BINDING 14
#endif
#ifdef WHITTED_CDCT
#include "raycache/cdct.glsl"
#else
#include "raycache/cct.glsl"
#endif

layout(local_size_x = 8, local_size_y = 8) in;

#include "scene.glsl"

// RayCache's buffers take bindings 0..4 (raycache/shared/gpu_layout.h: CCT texels and pending, CDCT texels
// and pending, the frame buffer with its counters and store list), 12, 13 (doubtful bits, moved from
// their defaults 5, 6) and 14 (the CCT's origin records, moved from 9); the scene's 5..8 (scene.glsl).
layout(std430, binding = 9) writeonly buffer Output { vec4 pixels[]; };
layout(std430, binding = 10) readonly buffer Cubes { raycache_gpu_cube cubes[]; };
// Hybrid (Params.frame.z >= 16 adds it to the mode): the primary hit of each pixel from the raster pass,
// (t bits, primitive or ~0u for none, u bits, v bits).
layout(std430, binding = 11) readonly buffer GBuffer { uvec4 gbuffer[]; };

const int MODE_OFF = 0, MODE_CCT = 1, MODE_CDCT = 2, MODE_CEILING = 3;

#include "shade.glsl"

// tracer.cpp's shade(): the local colour of the hit, and the reflected/refracted rays (none at max depth).
vec3 shade(Hit h, vec3 origin, vec3 d, int depth, out Child children[3], out int count, out uint object) {
    Surface s = surface_at(h, origin, d);
    object = s.object;
    bool seen = s.lit && intersect(s.above, s.l, s.distance - s.eps, true).prim < 0;
    vec3 color = surface_color(s, seen);
    count = depth >= frame.w ? 0 : children_of(s, d, children);
    return color;
}

const int STACK = 24;

// The colour of the ray (o, d) at `depth` and its first hit distance (infinity: escaped); caches are not
// consulted (in ceiling mode cached leaving rays still get the constant).
vec4 trace_subtree(vec3 o0, vec3 d0, int depth0) {
    vec3 so[STACK], sd[STACK], sw[STACK];
    int sdepth[STACK];
    int top = 0;
    so[0] = o0; sd[0] = d0; sw[0] = vec3(1.0); sdepth[0] = depth0; top = 1;
    vec3 sum = vec3(0.0);
    float first_t = RAYCACHE_INFINITY;
    bool first = true;
    while (top > 0) {
        --top;
        vec3 o = so[top], d = sd[top], w = sw[top];
        int depth = sdepth[top];
        Hit h = intersect(o, d, RAYCACHE_INFINITY, false);
        if (first) first_t = h.prim < 0 ? RAYCACHE_INFINITY : h.t;
        first = false;
        if (h.prim < 0) { sum += w * environment.xyz; continue; }
        Child c[3];
        int count;
        uint object;
        sum += w * shade(h, o, d, depth, c, count, object);
        bool cached = objects[object].m3.y != 0.0;
        for (int i = count - 1; i >= 0; --i) {
            if (c[i].leaving && cached && (frame.z & 15) == MODE_CEILING) { sum += w * c[i].w * environment.xyz; continue; }
            if (top < STACK) { so[top] = c[i].o; sd[top] = c[i].d; sw[top] = w * c[i].w; sdepth[top] = depth + 1; ++top; }
        }
    }
    return vec4(sum, first_t);
}

// What a pixel's leaving rays met, or-ed into its alpha for the host's SIMD-group statistics
// (simd_groups.hpp): a lookup that hit, one that missed, a ray a resting cube let through.
const uint LOOKUP_HIT = 1u, LOOKUP_MISSED = 2u, LOOKUP_RESTED = 4u;

// The colour of a ray leaving cached object `object` from o in unit direction d (tracer.cpp's leaving()).
// A ray its resting cube lets through is traced alone, through the same call as a missed ray's: lanes of
// one SIMD group that take different calls would run both, one after the other (on lavapipe, with two
// calls, a resting cube's frame took 1.13 uncached ones, with 1 ray in 16 still probing).
vec3 leaving(uint object, vec3 o, vec3 d, int depth, inout uint outcome) {
    raycache_gpu_cube cube = cubes[object];
    bool rests = raycache_cube_rests(cube, d);
    outcome |= rests ? LOOKUP_RESTED : 0u;
#ifdef WHITTED_CDCT
    raycache_relief_parameters rp = raycache_relief_parameters(relief.x, relief.y, relief_i.x, relief.z, relief.w,
                                                               relief_i.y, relief_i.z);
    if (!rests) {
        raycache_relief_result f = raycache_cdct_search(cube, o, d, rp); // secant or relief walk, as rp.search says
        outcome |= f.hit ? LOOKUP_HIT : LOOKUP_MISSED;
        if (f.hit) return f.color;
    }
    vec4 r = trace_subtree(o, d, depth + 1);
    if (rests) return r.rgb;
    if (isinf(r.w)) {
        raycache_cdct_store_escape(cube, d, r.rgb, rp);
    } else {
        precise vec3 hit_point = o + r.w * d;
        raycache_cdct_store_hit(cube, hit_point, r.rgb, rp);
    }
    return r.rgb;
#else
    bool origins = origin_test.x >= 0.0;
    raycache_origin_tolerance tolerance = raycache_origin_tolerance(origin_test.x * cube.half_size, origin_test.y);
    if (!rests) {
        raycache_cct_result c = origins ? raycache_cct_lookup_from(cube, d, o, tolerance) : raycache_cct_lookup(cube, d);
        outcome |= c.hit ? LOOKUP_HIT : LOOKUP_MISSED;
        if (c.hit) return c.color;
    }
    vec4 r = trace_subtree(o, d, depth + 1);
    if (rests) return r.rgb;
    if (origins) raycache_cct_store_from(cube, d, r.rgb, o, r.w, tolerance);
    else raycache_cct_store(cube, d, r.rgb);
    return r.rgb;
#endif
}

// A primary ray's tree: as trace_subtree, but rays leaving cached objects go through their cubes (and
// their subtrees are summed separately in every mode); `outcome` gathers what their lookups met.
vec3 trace_primary(vec3 o0, vec3 d0, uint pixel, out uint outcome) {
    outcome = 0u;
    vec3 so[STACK], sd[STACK], sw[STACK];
    int sdepth[STACK];
    int top = 0;
    so[0] = o0; sd[0] = d0; sw[0] = vec3(1.0); sdepth[0] = 0; top = 1;
    vec3 sum = vec3(0.0);
    int mode = frame.z & 15;
    bool raster = frame.z >= 16;
    while (top > 0) {
        --top;
        vec3 o = so[top], d = sd[top], w = sw[top];
        int depth = sdepth[top];
        Hit h;
        if (raster && depth == 0) { // the primary ray: its hit comes from the raster pass
            uvec4 g = gbuffer[pixel];
            h.t = uintBitsToFloat(g.x);
            h.prim = g.y == 0xFFFFFFFFu ? -1 : int(g.y);
            h.u = uintBitsToFloat(g.z);
            h.v = uintBitsToFloat(g.w);
        } else {
            h = intersect(o, d, RAYCACHE_INFINITY, false);
        }
        if (h.prim < 0) { sum += w * environment.xyz; continue; }
        Child c[3];
        int count;
        uint object;
        sum += w * shade(h, o, d, depth, c, count, object);
        bool cached = objects[object].m3.y != 0.0;
        for (int i = count - 1; i >= 0; --i) {
            if (c[i].leaving && cached) {
                // With the cache off the leaving ray's subtree is summed on its own too, as leaving() sums
                // a miss, so that a cold cached frame equals the uncached frame bit for bit.
                if (mode == MODE_OFF) sum += w * c[i].w * trace_subtree(c[i].o, c[i].d, depth + 1).rgb;
                else if (mode == MODE_CEILING) sum += w * c[i].w * environment.xyz;
#ifdef WHITTED_CDCT
                else if (mode == MODE_CDCT)
#else
                else if (mode == MODE_CCT)
#endif
                    sum += w * c[i].w * leaving(object, c[i].o, c[i].d, depth, outcome);
                continue;
            }
            if (top < STACK) { so[top] = c[i].o; sd[top] = c[i].d; sw[top] = w * c[i].w; sdepth[top] = depth + 1; ++top; }
        }
    }
    return sum;
}

void main() {
    int width = frame.x, height = frame.y;
    // relief_i.w > 1: a warm-up pass, one invocation per stride-th pixel in x and y; < -1: the full pass
    // after a warm-up over every (-relief_i.w)-th pixel, whose pixels are final already.
    int stride = max(relief_i.w, 1);
    int done = relief_i.w < -1 ? -relief_i.w : 0;
    int x = int(gl_GlobalInvocationID.x) * stride, y = int(gl_GlobalInvocationID.y) * stride;
    if (x >= width || y >= height) return;
    if (done > 0 && x % done == 0 && y % done == 0) return;
    vec3 d = primary_direction(x, y);
    uint outcome;
    vec3 color = trace_primary(eye.xyz, d, uint(y * width + x), outcome);
    pixels[y * width + x] = vec4(color, float(outcome));
}
