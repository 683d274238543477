// Calls every public function of RayCache's GLSL include, so that the glsl test compiles them all for
// each shader stage (included by the wrappers that tests/vulkan/compile_glsl.cmake writes). The filtered
// lookup reads the CCT buffer through a fetch declared before the include and defined after it.
#include "raycache/shared/cube_face.h"
bool raycache_test_fetch(raycache_texel_address texel, out vec3 color);
#define RAYCACHE_FILTER_FETCH raycache_test_fetch
#define RAYCACHE_CDCT
#include "raycache/raycache.glsl"
#if (defined(RAYCACHE_CONFIDENCE) || defined(RAYCACHE_ORIGINS)) && defined(RAYCACHE_END_FRAME)
#include "raycache/end_frame.glsl"
#endif

layout(std430, set = 1, binding = 0) buffer raycache_test_sink { vec4 raycache_test_values[]; };

raycache_gpu_cube raycache_test_cube;

bool raycache_test_fetch(raycache_texel_address texel, out vec3 color) {
    color = vec3(0.0);
    uint i = raycache_test_cube.first_texel + raycache_texel_linear_index(texel, raycache_test_cube.face_size);
    if (i >= uint(raycache_cct_texels.length()) || !raycache_cct_is_valid(raycache_cct_texels[i])) return false;
    color = raycache_unpack_rgb9e5(raycache_cct_texels[i]);
    return true;
}

void raycache_test_use_all() {
    raycache_gpu_cube cube = raycache_make_gpu_cube(vec3(0.0), 1.0, 0u, 16);
    vec4 sum = vec4(0.0);
    raycache_cct_result c = raycache_cct_lookup(cube, vec3(1.0, 0.5, -0.25));
    sum += vec4(c.color, c.hit ? 1.0 : 0.0);
    c = raycache_cct_peek(cube, vec3(1.0, 0.5, -0.25));
    sum += vec4(c.color, c.hit ? 1.0 : 0.0);
    raycache_count_lookup(cube, true);
    sum.w += raycache_cube_rests(cube, vec3(0.0, 0.6, 0.8)) ? 1.0 : 0.0;
    raycache_relief_result f = raycache_relief_search(cube, vec3(0.1), vec3(0.0, 1.0, 0.0), raycache_default_relief_parameters());
    sum += vec4(f.color + f.point, f.distance + float(f.texels_read) + (f.hit ? 1.0 : 0.0));
    f = raycache_cdct_secant_search(cube, vec3(0.1), vec3(0.0, 1.0, 0.0), raycache_default_relief_parameters());
    sum += vec4(f.color + f.point, f.distance + float(f.texels_read) + (f.hit ? 1.0 : 0.0));
    f = raycache_cdct_search(cube, vec3(0.1), vec3(0.0, 0.0, 1.0), raycache_default_relief_parameters());
    sum += vec4(f.color + f.point, f.distance + float(f.texels_read) + (f.hit ? 1.0 : 0.0));
    sum.x += float(raycache_cube_texel(cube, vec3(0.0, 0.0, -1.0))) + float(raycache_gpu_cube_texel_count(16));
    raycache_test_cube = cube;
    raycache_filter_result b = raycache_filtered_value(vec3(1.0, 0.5, -0.25), cube.face_size, 0.0);
    sum += vec4(b.color, b.weight + (b.hit ? 1.0 : 0.0));
    raycache_filter_taps taps = raycache_filter_taps_of(vec3(1.0, 1.0, 1.0), 16);
    raycache_filter_sum partial = raycache_filter_sum_add(raycache_filter_sum_zero(), vec3(0.5), taps.weight[0]);
    sum.z += raycache_filter_result_of(partial, 0.5).weight + float(raycache_wrapped_texel(0, -1, 3, 16).face);
#ifndef RAYCACHE_READ_ONLY
    sum.y += raycache_cct_store(cube, vec3(1.0, 0.5, -0.25), vec3(0.5)) ? 1.0 : 0.0;
    sum.y += raycache_cdct_store_hit(cube, vec3(3.0), vec3(0.5), raycache_default_relief_parameters()) ? 1.0 : 0.0;
    sum.y += raycache_cdct_store_escape(cube, vec3(0.0, 0.0, 1.0), vec3(0.5), raycache_default_relief_parameters()) ? 1.0 : 0.0;
    sum.y += raycache_cdct_store(cube, vec3(0.0, 0.0, 1.0), vec3(0.5), 2.0) ? 1.0 : 0.0;
    sum.y += raycache_cdct_store_traced(cube, vec3(0.1), vec3(0.0, 1.0, 0.0), vec3(0.5), 2.0, raycache_default_relief_parameters()) ? 1.0 : 0.0;
#endif
#ifdef RAYCACHE_END_FRAME
    raycache_cct_end_frame(0u);
    raycache_cdct_end_frame(0u);
#endif
#ifdef RAYCACHE_ORIGINS
    raycache_origin_tolerance tolerance = raycache_origin_tolerance(0.1, 0.01);
    c = raycache_cct_lookup_from(cube, vec3(1.0, 0.5, -0.25), vec3(0.5), tolerance);
    sum += vec4(c.color, c.hit ? 1.0 : 0.0);
#ifndef RAYCACHE_READ_ONLY
    sum.y += raycache_cct_store_from(cube, vec3(1.0, 0.5, -0.25), vec3(0.5), vec3(0.5), 3.0, tolerance) ? 1.0 : 0.0;
#endif
#ifdef RAYCACHE_END_FRAME
    raycache_cct_end_frame_tile(0u);
    raycache_cct_drop_tile(1u);
    raycache_end_frame_drop_pass();
#endif
#endif
#ifdef RAYCACHE_CONFIDENCE
    sum.w += (raycache_cct_is_doubtful(1u) ? 1.0 : 0.0) + (raycache_cdct_is_doubtful(2u) ? 1.0 : 0.0);
#ifdef RAYCACHE_END_FRAME
    raycache_end_frame_pass();
    raycache_end_frame_mark_pass(0.1);
    raycache_mark_edges(false, 3u, 0.1);
    raycache_mark_edges(true, 4u, 0.1);
#endif
#endif
    raycache_test_values[0] = sum;
}
