// primitives.glsl: the intersection tests every tracing shader shares (the BVH tracer's scene.glsl, the
// ray-space hierarchy's final pass rsh_final.comp): glm-ordered float helpers, Embree's sphere test and
// Moeller-Trumbore, with `precise` so that no compiler fuses a product into an FMA. Declares no buffers.
#ifndef WHITTED_PRIMITIVES_GLSL
#define WHITTED_PRIMITIVES_GLSL

// glm's order of operations, never fused.
float pdot(vec3 a, vec3 b) {
    precise float r = (a.x * b.x + a.y * b.y) + a.z * b.z;
    return r;
}
vec3 pnormalize(vec3 v) {
    precise float s = 1.0 / sqrt(pdot(v, v));
    precise vec3 r = v * s;
    return r;
}
vec3 pcross(vec3 x, vec3 y) {
    precise vec3 r = vec3(x.y * y.z - y.y * x.z, x.z * y.x - y.z * x.x, x.x * y.y - y.x * x.y);
    return r;
}

struct Hit {
    float t;
    int prim;
    float u, v;
};

// Embree's sphere test (SphereIntersector1): front hit if in [tnear, tfar], else the back hit.
bool hit_sphere(vec4 s, vec3 o, vec3 d, float tfar, inout float t) {
    precise vec3 c0 = s.xyz - o;
    precise float rd2 = 1.0 / pdot(d, d);
    precise float proj = pdot(c0, d) * rd2;
    precise vec3 perp = c0 - proj * d;
    precise float l2 = pdot(perp, perp);
    precise float r2 = s.w * s.w;
    if (!(l2 <= r2)) return false;
    precise float td = sqrt((r2 - l2) * rd2);
    precise float t_front = proj - td;
    precise float t_back = proj + td;
    if (0.0 <= t_front && t_front <= tfar) { t = t_front; return true; }
    if (0.0 <= t_back && t_back <= tfar) { t = t_back; return true; }
    return false;
}

// Embree's Moeller-Trumbore test: e1 = v0 - v1, e2 = v2 - v0, Ng = e2 x e1; u weighs v1, v weighs v2.
bool hit_triangle_vertices(vec3 v0, vec3 v1, vec3 v2, vec3 o, vec3 d, float tfar, inout float t, inout float u,
                           inout float v) {
    precise vec3 e1 = v0 - v1;
    precise vec3 e2 = v2 - v0;
    vec3 ng = pcross(e2, e1);
    precise vec3 c = v0 - o;
    vec3 r = pcross(c, d);
    float den = pdot(ng, d);
    float abs_den = abs(den);
    float sgn = den < 0.0 ? -1.0 : 1.0;
    float U = pdot(r, e2) * sgn;
    float V = pdot(r, e1) * sgn;
    if (!(den != 0.0 && U >= 0.0 && V >= 0.0 && U + V <= abs_den)) return false;
    float T = pdot(ng, c) * sgn;
    if (!(0.0 < T && T <= abs_den * tfar)) return false;
    precise float rcp = 1.0 / abs_den;
    t = T * rcp;
    u = U * rcp;
    v = V * rcp;
    return true;
}

#endif /* WHITTED_PRIMITIVES_GLSL */
