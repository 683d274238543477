#version 450
// Filtered lookups three ways, for the filter cross-check (test_vulkan_filter.cpp): RayCache's GLSL
// footprint (raycache_filter_taps_of) and filtered value (raycache_filtered_value over a fetch from a
// buffer of texel colours), and the device's own LINEAR samplerCube over an R32_SFLOAT cube holding the
// same texels' red channel.
#extension GL_GOOGLE_include_directive : require
#include "raycache/shared/cube_face.h"
bool filter_cross_fetch(raycache_texel_address texel, out vec3 color);
#define RAYCACHE_FILTER_FETCH filter_cross_fetch
#include "raycache/filter.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    int face_size;
    uint count;
};
layout(std430, binding = 0) readonly buffer Directions { float directions[]; }; // x, y, z per direction
layout(std430, binding = 1) readonly buffer Texels { vec4 texel_colors[]; };    // rgb; a > 0: present
layout(std430, binding = 2) writeonly buffer Taps { uvec4 taps[]; };  // 5 per direction: (count, -, -, -),
                                                                      // then (face, column, row, weight bits)
layout(std430, binding = 3) writeonly buffer Values { vec4 values[]; }; // 2 per direction: (colour, hit),
                                                                        // (sampler red, weight found, -, -)
layout(binding = 4) uniform samplerCube cube;

bool filter_cross_fetch(raycache_texel_address texel, out vec3 color) {
    vec4 t = texel_colors[raycache_texel_linear_index(texel, face_size)];
    color = t.rgb;
    return t.a > 0.0;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    vec3 s = vec3(directions[3 * i], directions[3 * i + 1], directions[3 * i + 2]);
    raycache_filter_taps f = raycache_filter_taps_of(s, face_size);
    taps[5 * i] = uvec4(uint(f.count), 0u, 0u, 0u);
    for (int k = 0; k < RAYCACHE_FILTER_MAX_TAPS; ++k)
        taps[5 * i + 1 + uint(k)] = uvec4(uint(f.texel[k].face), uint(f.texel[k].column), uint(f.texel[k].row),
                                          floatBitsToUint(f.weight[k]));
    raycache_filter_result r = raycache_filtered_value(s, face_size, 0.0);
    values[2 * i] = vec4(r.color, r.hit ? 1.0 : 0.0);
    float sampled = 0.0;
    if (raycache_is_direction(s)) sampled = textureLod(cube, s, 0.0).r;
    values[2 * i + 1] = vec4(sampled, r.weight, 0.0, 0.0);
}
