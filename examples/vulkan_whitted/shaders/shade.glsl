// shade.glsl: the Whitted shading of examples/embree_whitted/tracer.cpp, shared by the BVH tracer
// (whitted.comp, which traces the shadow ray at once) and the ray-space hierarchy's wavefront passes
// (rsh_whitted.comp, which trace all shadow rays of a generation together): surface_at() computes all a
// hit needs but the shadow ray's answer, children_of() the reflected and refracted rays. Needs scene.glsl.
#ifndef WHITTED_SHADE_GLSL
#define WHITTED_SHADE_GLSL

float surface_epsilon(vec3 p) {
    vec3 a = abs(p);
    return 1e-4 * max(1.0, max(a.x, max(a.y, a.z)));
}

float schlick(float n1, float n2, float cos_i, float cos_t) {
    precise float r0 = (n1 - n2) / (n1 + n2);
    float c = n1 <= n2 ? cos_i : cos_t;
    precise float x = 1.0 - c;
    precise float r = r0 * r0 + (1.0 - r0 * r0) * x * x * x * x * x;
    return r;
}

// A ray spawned by a hit: its weight in the parent's colour; leaving: it leaves the (cached) object.
struct Child {
    vec3 o;
    vec3 d;
    vec3 w;
    bool leaving;
};

// A hit, shaded but for its shadow ray: colour = ambient (+ diffuse (+ specular) when the light is seen).
struct Surface {
    uint object;
    bool inside;
    vec3 n;
    float eps;
    vec3 above, below;
    vec3 ambient, diffuse, specular;
    bool lit;          // the light is in front of the surface: a shadow ray from `above` decides
    bool shiny;        // specular counts when lit
    vec3 l;            // unit, towards the light
    float distance;    // to the light
    float reflectivity, transparency, ior;
};

// tracer.cpp's shade() up to the shadow ray.
Surface surface_at(Hit h, vec3 origin, vec3 d) {
    Surface s;
    Prim prim = prims[h.prim];
    s.object = prim.info.y;
    Object m = objects[s.object];
    precise vec3 p = origin + h.t * d;
    vec3 ng, ns;
    if (prim.info.x == 0u) {
        ng = ns = pnormalize(p - prim.p0.xyz);
    } else {
        precise vec3 interp = (1.0 - h.u - h.v) * prim.n0.xyz + h.u * prim.n1.xyz + h.v * prim.n2.xyz;
        ns = pnormalize(interp);
        ng = pcross(prim.p1.xyz - prim.p0.xyz, prim.p2.xyz - prim.p0.xyz);
        ng = pnormalize(pdot(ng, ns) < 0.0 ? -ng : ng);
    }
    s.inside = pdot(d, ng) > 0.0;
    vec3 nf = s.inside ? -ng : ng;
    vec3 n = s.inside ? -ns : ns;
    if (pdot(n, d) >= 0.0) n = nf;
    s.n = n;
    s.eps = surface_epsilon(p);
    precise vec3 above = p + s.eps * nf;
    precise vec3 below = p - s.eps * nf;
    s.above = above;
    s.below = below;

    vec3 base = m.m0.xyz;
    if (m.m3.x != 0.0) {
        float sc = m.m2.w > 0.0 ? m.m2.w : 1.0;
        int cell = int(floor(p.x / sc)) + int(floor(p.z / sc));
        if ((cell & 1) != 0) base = m.m1.xyz;
    }
    s.reflectivity = m.m2.x;
    s.transparency = m.m2.y;
    s.ior = m.m2.z;
    float local = max(0.0, 1.0 - s.reflectivity - s.transparency);

    s.ambient = vec3(0.0);
    s.diffuse = vec3(0.0);
    s.specular = vec3(0.0);
    s.lit = false;
    s.shiny = false;
    s.l = vec3(0.0, 1.0, 0.0);
    s.distance = 0.0;
    if (!s.inside) {
        s.ambient = vec3(0.0) + light_position.w * local * base;
        precise vec3 to_light = light_position.xyz - p;
        s.distance = raycache_length(to_light);
        precise vec3 l = to_light / s.distance;
        s.l = l;
        float n_dot_l = pdot(n, l);
        s.lit = n_dot_l > 0.0 && pdot(nf, l) > 0.0;
        if (s.lit) {
            s.diffuse = light_intensity.xyz * (local * n_dot_l) * base;
            if (m.m0.w > 0.0) {
                precise vec3 refl = -l - 2.0 * pdot(n, -l) * n;
                float r_dot_v = pdot(refl, -d);
                s.shiny = r_dot_v > 0.0;
                if (s.shiny) s.specular = light_intensity.xyz * (m.m0.w * pow(r_dot_v, m.m1.w));
            }
        }
    }
    return s;
}

// The colour of a shaded surface, given whether its shadow ray reached the light.
vec3 surface_color(Surface s, bool light_seen) {
    vec3 color = s.ambient;
    if (s.lit && light_seen) {
        color += s.diffuse;
        if (s.shiny) color += s.specular;
    }
    return color;
}

// tracer.cpp's reflected and refracted rays of a hit (the caller checks the depth limit).
int children_of(Surface s, vec3 d, out Child children[3]) {
    int count = 0;
    vec3 n = s.n;
    float cos_i = -pdot(d, n);
    precise vec3 mirrored = pnormalize(d + 2.0 * cos_i * n);
    if (s.reflectivity > 0.0 && !s.inside) children[count++] = Child(s.above, mirrored, vec3(s.reflectivity), true);
    if (s.transparency > 0.0) {
        float n1 = s.inside ? s.ior : 1.0, n2 = s.inside ? 1.0 : s.ior;
        precise float eta = n1 / n2;
        precise float sin2_t = eta * eta * (1.0 - cos_i * cos_i);
        float fresnel = 1.0;
        if (sin2_t < 1.0) {
            precise float cos_t = sqrt(1.0 - sin2_t);
            fresnel = schlick(n1, n2, cos_i, cos_t);
            precise vec3 t_dir = pnormalize(eta * d + (eta * cos_i - cos_t) * n);
            children[count++] = Child(s.below, t_dir, vec3(s.transparency * (1.0 - fresnel)), s.inside);
        }
        if (fresnel > 0.0) children[count++] = Child(s.above, mirrored, vec3(s.transparency * fresnel), !s.inside);
    }
    return count;
}

#endif /* WHITTED_SHADE_GLSL */
