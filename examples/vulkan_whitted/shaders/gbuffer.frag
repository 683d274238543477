#version 450
// gbuffer.frag: the primary ray of this pixel against the primitive being drawn, with the very tests the
// compute tracer uses; a miss is discarded, a hit writes (t, primitive, u, v) and a depth rising with t.
#extension GL_GOOGLE_include_directive : require
#include "scene.glsl"

layout(location = 0) flat in int primitive;
layout(location = 0) out uvec4 hit;

void main() {
    int x = int(gl_FragCoord.x), y = int(gl_FragCoord.y);
    vec3 d = primary_direction(x, y);
    vec3 o = eye.xyz;
    Prim p = prims[primitive];
    float t = 0.0, u = 0.0, v = 0.0;
    bool found = p.info.x == 0u ? hit_sphere(p.p0, o, d, RAYCACHE_INFINITY, t) : hit_triangle(p, o, d, RAYCACHE_INFINITY, t, u, v);
    if (!found) discard;
    hit = uvec4(floatBitsToUint(t), uint(primitive), floatBitsToUint(u), floatBitsToUint(v));
    gl_FragDepth = t / (t + 1.0);
}
