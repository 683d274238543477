#version 450
// Maps directions to texels three ways, for the face-table cross-check (test_vulkan_face.cpp):
// RayCache's GLSL include (raycache_texel_of and raycache_cube_texel), and the device's own cube sampler
// reading an R32_UINT cube whose texels hold their own linear index.
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_READ_ONLY
#include "raycache/cube.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    int face_size;
    uint count;
};
layout(std430, binding = 0) readonly buffer Directions { float directions[]; }; // x, y, z per direction
layout(std430, binding = 1) writeonly buffer Texels { ivec4 texels[]; };        // face, column, row, -
layout(std430, binding = 2) writeonly buffer Linear { uvec2 linear[]; };        // include, sampler
layout(binding = 3) uniform usamplerCube addresses;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    vec3 s = vec3(directions[3 * i], directions[3 * i + 1], directions[3 * i + 2]);
    raycache_texel_address a = raycache_texel_of(s, face_size);
    texels[i] = ivec4(a.face, a.column, a.row, 0);
    raycache_gpu_cube cube = raycache_make_gpu_cube(vec3(0.0), 1.0, 0u, face_size);
    uint sampled = 0xFFFFFFFFu;
    if (raycache_is_direction(s)) sampled = textureLod(addresses, s, 0.0).r;
    linear[i] = uvec2(raycache_cube_texel(cube, s), sampled);
}
