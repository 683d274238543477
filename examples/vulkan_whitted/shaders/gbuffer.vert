#version 450
// gbuffer.vert: the raster pass of the hybrid mode (thesis Table 5.1: primary visibility by rasterisation,
// secondary rays in compute). No vertex buffers: vertex k draws corner k % 36 of the bounding box of
// primitive k / 36 (12 triangles), so every pixel whose primary ray can hit the primitive is covered;
// the fragment shader then intersects that ray with the primitive exactly (gbuffer.frag).
#extension GL_GOOGLE_include_directive : require
#include "scene.glsl"

layout(location = 0) flat out int primitive;

const int corners[36] = int[36](0, 1, 3, 0, 3, 2,  4, 6, 7, 4, 7, 5,  0, 4, 5, 0, 5, 1,
                                2, 3, 7, 2, 7, 6,  0, 2, 6, 0, 6, 4,  1, 5, 7, 1, 7, 3);

void main() {
    primitive = gl_VertexIndex / 36;
    int corner = corners[gl_VertexIndex % 36];
    Prim p = prims[primitive];
    vec3 lo, hi;
    if (p.info.x == 0u) {
        lo = p.p0.xyz - vec3(p.p0.w);
        hi = p.p0.xyz + vec3(p.p0.w);
    } else {
        lo = min(p.p0.xyz, min(p.p1.xyz, p.p2.xyz));
        hi = max(p.p0.xyz, max(p.p1.xyz, p.p2.xyz));
    }
    // A little larger than the box, so that rounding never uncovers a pixel.
    vec3 pad = 1e-4 * max(vec3(1.0), max(abs(lo), abs(hi)));
    lo -= pad;
    hi += pad;
    vec3 world = vec3((corner & 1) != 0 ? hi.x : lo.x, (corner & 2) != 0 ? hi.y : lo.y, (corner & 4) != 0 ? hi.z : lo.z);
    // The tracer's pinhole camera: x right, y down (Vulkan), w = distance along the view direction.
    vec3 v = world - eye.xyz;
    float xc = dot(v, right.xyz), yc = dot(v, up.xyz), zc = dot(v, forward.xyz);
    float tan_half = light_intensity.w, aspect = environment.w;
    gl_Position = vec4(xc / (tan_half * aspect), -yc / tan_half, zc - 1e-3, zc);
}
