#version 450
// rsh_whitted.comp: the Whitted tracer's shading as wavefront passes around the ray-space hierarchy
// engine (rsh_frame.cpp records them, with the engine's traces, into one submission a frame; the engine,
// rsh_engine.cpp, finds the hits). Rays of a generation are an array in which each pixel's rays are
// contiguous (generation 0 in Morton order over the screen, later ones in their parents' order), so 4
// neighbours are coherent and one invocation sums a pixel. Generation g has frame_control[g] rays, a count
// the plan pass (mode 4) writes on the device; the passes of a generation run as many groups as its
// indirect arguments (frame_control[FC_ARGS + 6 g ..]) say.
//   mode 0, generate: the primary ray of each Morton slot (empty outside the image), the image cleared,
//           and its hit: traced through the scene's BVH (scene.glsl's intersect(), as whitted.comp
//           traces primary rays; this dispatch binds the BVH's nodes and primitives, whose info.w is the
//           primitive's index in scene order) or, hybrid, copied from the raster pass's G-buffer.
//   mode 1, shade: each ray's hit shaded as shade.glsl does but for the shadow ray, which is written
//           reversed, from the light towards the surface (paper section 3.5.1), and the reflected and
//           refracted rays (section 3.5.2) written as 3 candidate slots a ray for the next generation.
//   mode 2, gather: the first ray of each pixel's run adds the run's colours (lit or not, as the shadow
//           rays found) to the image.
//   mode 3, flag: 1 for each candidate slot that holds a ray, for the engine's prefix sum.
//   mode 4, plan (one invocation): the next generation's count (the prefix sum's total, at most the ray
//           capacity; a larger total is reported, for the host to render the frame again with more room)
//           and its dispatch arguments.
//   mode 5, scatter: each candidate that holds a ray to its prefix-sum slot of the next generation.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;

#include "raycache/shared/rsh_layout.h"
#include "scene.glsl"
#include "shade.glsl"

struct RayState {
    vec4 weight;  // xyz: the ray's weight in its pixel's colour
    uint pixel;   // 0xFFFFFFFF: no pixel (empty slot)
    int depth;
    uint pad0, pad1;
};
struct Candidate {
    raycache_rsh_ray ray;
    RayState state;
};

layout(std430, binding = 0) buffer Rays { raycache_rsh_ray rays[]; };
layout(std430, binding = 1) buffer Hits { raycache_rsh_hit hits[]; };
layout(std430, binding = 2) buffer States { RayState states[]; };
layout(std430, binding = 3) buffer ShadowRays { raycache_rsh_ray shadow_rays[]; };
layout(std430, binding = 4) buffer ShadowHits { raycache_rsh_hit shadow_hits[]; };
layout(std430, binding = 9) buffer Local { vec4 local[]; };        // 2 per ray: colour if lit, if shadowed
layout(std430, binding = 10) buffer Candidates { Candidate candidates[]; };
layout(std430, binding = 11) buffer Image { vec4 image[]; };
layout(std430, binding = 12) readonly buffer GBuffer { uvec4 gbuffer[]; };
layout(std430, binding = 13) buffer FrameControl { uint frame_control[]; };
layout(std430, binding = 14) buffer Flags { uint flags[]; };         // one per candidate slot (mode 3)
layout(std430, binding = 15) readonly buffer Sums { uint sums[]; };  // their exclusive prefix sums

layout(push_constant) uniform Push {
    uint mode;
    uint generation;  // g: this generation's count is frame_control[FC_COUNTS + g]
    uint side;        // Morton square side (mode 0)
    uint hybrid;      // mode 0: take primary hits from the G-buffer
    uint capacity;    // rays a generation may hold (mode 4)
    uint total_word;  // where in `sums` the prefix sum's total is (mode 4)
} pc;

// Frame control words (rsh_frame.cpp): per generation its ray count and 6 indirect dispatch arguments
// (groups over its rays, groups over its candidate slots); the largest count that exceeded the capacity;
// the shadow rays written.
const uint FC_COUNTS = 0u, FC_OVERFLOW = 32u, FC_SHADOW = 33u, FC_ARGS = 64u;

const uint NO_PIXEL = 0xFFFFFFFFu;

uint generation_count() { return frame_control[FC_COUNTS + pc.generation]; }

raycache_rsh_ray empty_ray() {
    return raycache_rsh_ray(vec3(0.0), 0.0, vec3(0.0, 0.0, 1.0), 0u);
}

uint morton_compact(uint m) { // every other bit of m, from bit 0
    m &= 0x55555555u;
    m = (m | (m >> 1u)) & 0x33333333u;
    m = (m | (m >> 2u)) & 0x0F0F0F0Fu;
    m = (m | (m >> 4u)) & 0x00FF00FFu;
    m = (m | (m >> 8u)) & 0x0000FFFFu;
    return m;
}

void generate(uint m) {
    int x = int(morton_compact(m)), y = int(morton_compact(m >> 1u));
    if (x >= frame.x || y >= frame.y) {
        rays[m] = empty_ray();
        states[m] = RayState(vec4(0.0), NO_PIXEL, 0, 0u, 0u);
        hits[m] = raycache_rsh_hit(RAYCACHE_RSH_NO_HIT, RAYCACHE_RSH_NO_HIT);
        return;
    }
    uint pixel = uint(y * frame.x + x);
    image[pixel] = vec4(0.0, 0.0, 0.0, 1.0);
    vec3 d = primary_direction(x, y);
    rays[m] = raycache_rsh_ray(eye.xyz, RAYCACHE_INFINITY, d, pixel);
    states[m] = RayState(vec4(1.0), pixel, 0, 0u, 0u);
    if (pc.hybrid != 0u) {
        uvec4 g = gbuffer[pixel];
        hits[m] = g.y == 0xFFFFFFFFu ? raycache_rsh_hit(RAYCACHE_RSH_NO_HIT, RAYCACHE_RSH_NO_HIT) : raycache_rsh_hit(g.y, g.x);
    } else {
        Hit h = intersect(eye.xyz, d, RAYCACHE_INFINITY, false);
        hits[m] = h.prim < 0 ? raycache_rsh_hit(RAYCACHE_RSH_NO_HIT, RAYCACHE_RSH_NO_HIT)
                             : raycache_rsh_hit(prims[h.prim].info.w, floatBitsToUint(h.t));
    }
}

void shade_ray(uint i) {
    raycache_rsh_ray r = rays[i];
    RayState st = states[i];
    shadow_rays[i] = empty_ray();
    for (int k = 0; k < 3; ++k) candidates[3u * i + uint(k)].ray = empty_ray();
    local[2u * i] = vec4(0.0);
    local[2u * i + 1u] = vec4(0.0);
    if (!(r.tmax > 0.0)) return;
    raycache_rsh_hit rh = hits[i];
    vec3 w = st.weight.xyz;
    if (rh.primitive == RAYCACHE_RSH_NO_HIT) {
        local[2u * i] = local[2u * i + 1u] = vec4(w * environment.xyz, 0.0);
        return;
    }
    Hit h;
    h.prim = int(rh.primitive);
    h.t = uintBitsToFloat(rh.t_bits);
    h.u = 0.0;
    h.v = 0.0;
    Prim p = prims[h.prim];
    if (p.info.x != 0u) { // the barycentrics of the hit, from the same test that found it
        float t = 0.0;
        hit_triangle(p, r.origin, r.direction, RAYCACHE_INFINITY, t, h.u, h.v);
    }
    Surface s = surface_at(h, r.origin, r.direction);
    local[2u * i] = vec4(w * surface_color(s, true), 0.0);
    local[2u * i + 1u] = vec4(w * surface_color(s, false), 0.0);
    if (s.lit) { // reversed: from the light to just above the surface
        precise vec3 back = s.above - light_position.xyz;
        float len = raycache_length(back);
        shadow_rays[i] = raycache_rsh_ray(light_position.xyz, len, back / len, i);
        atomicAdd(frame_control[FC_SHADOW], 1u);
    }
    if (st.depth >= frame.w) return;
    Child c[3];
    int count = children_of(s, r.direction, c);
    for (int k = 0; k < count; ++k)
        candidates[3u * i + uint(k)] = Candidate(raycache_rsh_ray(c[k].o, RAYCACHE_INFINITY, c[k].d, st.pixel),
                                                  RayState(vec4(w * c[k].w, 0.0), st.pixel, st.depth + 1, 0u, 0u));
}

void gather(uint i) {
    uint pixel = states[i].pixel;
    if (pixel == NO_PIXEL || (i > 0u && states[i - 1u].pixel == pixel)) return;
    vec3 sum = vec3(0.0);
    uint count = generation_count();
    for (uint j = i; j < count && states[j].pixel == pixel; ++j) {
        bool shadowed = shadow_rays[j].tmax > 0.0 && shadow_hits[j].primitive != RAYCACHE_RSH_NO_HIT;
        sum += local[2u * j + (shadowed ? 1u : 0u)].xyz;
    }
    image[pixel] += vec4(sum, 0.0);
}

void args(uint at, uint groups) {
    frame_control[at] = groups;
    frame_control[at + 1u] = 1u;
    frame_control[at + 2u] = 1u;
}

void plan() {
    uint total = sums[pc.total_word];
    if (total > pc.capacity) frame_control[FC_OVERFLOW] = max(frame_control[FC_OVERFLOW], total);
    uint next = min(total, pc.capacity);
    uint g = pc.generation + 1u;
    frame_control[FC_COUNTS + g] = next;
    args(FC_ARGS + 6u * g, (next + 63u) / 64u);
    args(FC_ARGS + 6u * g + 3u, (3u * next + 63u) / 64u);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (pc.mode == 4u) {
        if (i == 0u) plan();
        return;
    }
    if (pc.mode == 0u) {
        if (i < pc.side * pc.side) generate(i);
        return;
    }
    if (pc.mode == 3u || pc.mode == 5u) { // candidate slots
        if (i >= 3u * generation_count()) return;
        if (pc.mode == 3u) flags[i] = candidates[i].ray.tmax > 0.0 ? 1u : 0u;
        else if (flags[i] != 0u && sums[i] < pc.capacity) {
            uint at = sums[i];
            rays[at] = candidates[i].ray;
            states[at] = candidates[i].state;
        }
        return;
    }
    if (i >= generation_count()) return;
    if (pc.mode == 1u) shade_ray(i);
    else gather(i);
}
