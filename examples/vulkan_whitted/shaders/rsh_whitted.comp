#version 450
// rsh_whitted.comp: the Whitted tracer's shading as wavefront passes around the ray-space hierarchy
// engine (rsh_frame.cpp drives them; the engine, rsh_engine.cpp, finds the hits). Rays of a generation
// are an array in which each pixel's rays are contiguous (generation 0 in Morton order over the screen,
// later ones in their parents' order), so 4 neighbours are coherent and one invocation sums a pixel.
//   mode 0, generate: the primary ray of each Morton slot (empty outside the image), the image cleared;
//           hybrid: the primary hit copied from the raster pass's G-buffer into the hits instead.
//   mode 1, shade: each ray's hit shaded as shade.glsl does but for the shadow ray, which is written
//           reversed, from the light towards the surface (paper section 3.5.1), and the reflected and
//           refracted rays (section 3.5.2) written as 3 candidate slots a ray for the next generation.
//   mode 2, gather: the first ray of each pixel's run adds the run's colours (lit or not, as the shadow
//           rays found) to the image.
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

layout(push_constant) uniform Push {
    uint mode;
    uint count;   // rays of this generation (mode 0: Morton slots, side * side)
    uint side;    // Morton square side (mode 0)
    uint hybrid;  // mode 0: take primary hits from the G-buffer
} pc;

const uint NO_PIXEL = 0xFFFFFFFFu;

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
    rays[m] = raycache_rsh_ray(eye.xyz, RAYCACHE_INFINITY, primary_direction(x, y), pixel);
    states[m] = RayState(vec4(1.0), pixel, 0, 0u, 0u);
    if (pc.hybrid != 0u) {
        uvec4 g = gbuffer[pixel];
        hits[m] = g.y == 0xFFFFFFFFu ? raycache_rsh_hit(RAYCACHE_RSH_NO_HIT, RAYCACHE_RSH_NO_HIT) : raycache_rsh_hit(g.y, g.x);
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
    for (uint j = i; j < pc.count && states[j].pixel == pixel; ++j) {
        bool shadowed = shadow_rays[j].tmax > 0.0 && shadow_hits[j].primitive != RAYCACHE_RSH_NO_HIT;
        sum += local[2u * j + (shadowed ? 1u : 0u)].xyz;
    }
    image[pixel] += vec4(sum, 0.0);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    if (pc.mode == 0u) generate(i);
    else if (pc.mode == 1u) shade_ray(i);
    else gather(i);
}
