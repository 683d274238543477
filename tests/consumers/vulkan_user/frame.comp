#version 450
// One frame of a ray tracer's secondary rays, reduced to its cache: ray k leaves the cached object in
// directions[k]; a hit answers it, a miss "traces" it (colour_of) and stores the colour.
#extension GL_GOOGLE_include_directive : require
#include "raycache/raycache.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 5) readonly buffer Cubes { raycache_gpu_cube cubes[]; };
layout(std430, set = 0, binding = 6) readonly buffer Directions { vec4 directions[]; };
layout(std430, set = 0, binding = 7) writeonly buffer Results { vec4 results[]; }; // colour, 1 = hit
layout(push_constant) uniform Push { uint ray_count; };

// The "trace": a colour that RGB9E5 holds exactly (eighths below 1).
vec3 colour_of(uint k) { return vec3(float(k % 8u), float((k / 8u) % 8u), 4.0) / 8.0; }

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= ray_count) return;
    vec3 d = directions[k].xyz;
    raycache_cct_result c = raycache_cct_lookup(cubes[0], d);
    if (!c.hit) {
        c.color = colour_of(k);
        raycache_cct_store(cubes[0], d, c.color);
    }
    results[k] = vec4(c.color, c.hit ? 1.0 : 0.0);
}
