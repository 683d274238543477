// Calls every public function of RayCache's GLSL include, so that the glsl test compiles them all for
// each shader stage (included by the wrappers that tests/vulkan/compile_glsl.cmake writes).
#include "raycache/raycache.glsl"

layout(std430, set = 1, binding = 0) buffer raycache_test_sink { vec4 raycache_test_values[]; };

void raycache_test_use_all() {
    raycache_gpu_cube cube = raycache_make_gpu_cube(vec3(0.0), 1.0, 0u, 16);
    vec4 sum = vec4(0.0);
    raycache_cct_result c = raycache_cct_lookup(cube, vec3(1.0, 0.5, -0.25));
    sum += vec4(c.color, c.hit ? 1.0 : 0.0);
    raycache_relief_result f = raycache_relief_search(cube, vec3(0.1), vec3(0.0, 1.0, 0.0), raycache_default_relief_parameters());
    sum += vec4(f.color + f.point, f.distance + float(f.texels_read) + (f.hit ? 1.0 : 0.0));
    sum.x += float(raycache_cube_texel(cube, vec3(0.0, 0.0, -1.0))) + float(raycache_gpu_cube_texel_count(16));
#ifndef RAYCACHE_READ_ONLY
    sum.y += raycache_cct_store(cube, vec3(1.0, 0.5, -0.25), vec3(0.5)) ? 1.0 : 0.0;
    sum.y += raycache_cdct_store_hit(cube, vec3(3.0), vec3(0.5), raycache_default_relief_parameters()) ? 1.0 : 0.0;
    sum.y += raycache_cdct_store_escape(cube, vec3(0.0, 0.0, 1.0), vec3(0.5), raycache_default_relief_parameters()) ? 1.0 : 0.0;
    sum.y += raycache_cdct_store(cube, vec3(0.0, 0.0, 1.0), vec3(0.5), 2.0) ? 1.0 : 0.0;
#endif
#ifdef RAYCACHE_END_FRAME
    raycache_cct_end_frame(0u);
    raycache_cdct_end_frame(0u);
#endif
    raycache_test_values[0] = sum;
}
