/* raycache/raycache.glsl: RayCache in GLSL (Vulkan): caching cubes read and written by shaders, bit for
 * bit the texels of the C++ library (same face table, texel rounding and encodings, one shared source).
 *
 * BEFORE THE FIRST FRAME, FILL EVERY TEXEL AND PENDING BUFFER WITH 0xFFFFFFFF (RAYCACHE_GPU_CLEAR_WORD:
 * vkCmdFillBuffer(cmd, buffer, 0, VK_WHOLE_SIZE, 0xFFFFFFFFu), or raycache::fill_gpu_words on the host,
 * raycache/gpu_buffers.hpp). A zero-filled buffer reads as valid black texels: every lookup hits black
 * and nothing is ever stored, with no error.
 *
 * How to use it, from a compute, fragment or ray-generation shader:
 *   #version 450
 *   #extension GL_GOOGLE_include_directive : require
 *   #define RAYCACHE_SET 0                      // options: set (0 by default), bindings, RAYCACHE_READ_ONLY (cube.glsl)
 *   #define RAYCACHE_CDCT                       // only for the CDCT (see below); the CCT needs nothing
 *   #include "raycache/raycache.glsl"           // or only raycache/cct.glsl or raycache/cdct.glsl
 *   layout(std430, binding = 10) readonly buffer MyCubes { raycache_gpu_cube my_cubes[]; }; // yours: upload
 *                              // raycache::gpu_buffer_layout(...).cubes there, at a binding RayCache leaves
 *                              // free (it takes 0 to 9 in its set: raycache/shared/gpu_layout.h)
 *   raycache_gpu_cube cube = my_cubes[object];  // descriptor: raycache/shared/gpu_layout.h, C++ too
 *   raycache_cct_result c = raycache_cct_lookup(cube, reflected);
 *   if (!c.hit) { c.color = trace(hit, reflected); raycache_cct_store(cube, reflected, c.color); }
 *   raycache_relief_result f = raycache_cdct_search(cube, hit, reflected, parameters); // CDCT: the
 *                              // secant search or the relief walk, as parameters.search says
 *   raycache_filter_result b = raycache_filtered_value(reflected, N, 0.0); // bilinear, over the texel
 *                              // fetch named by RAYCACHE_FILTER_FETCH before the include (filter.glsl)
 * The CCT and the filtered lookup need no device feature beyond Vulkan 1.1 (fragment shaders that store:
 * fragmentStoresAndAtomics). The CDCT (raycache/cdct.glsl, included here only when RAYCACHE_CDCT is defined)
 * stores with 64-bit atomics: its shaders declare the Int64 capability and the device must enable
 * shaderInt64 and shaderBufferInt64Atomics (RAYCACHE_READ_ONLY: neither).
 * Buffers (set RAYCACHE_SET, bindings from raycache/shared/gpu_layout.h): CCT texels 0, pending 1, CDCT
 * texels 2, pending 3 (declared only with RAYCACHE_CDCT), frame buffer 4 (counters and the store list,
 * raycache/frame.glsl; host side: raycache/gpu_frame.hpp, which also gives the words to write into it
 * before every frame). Barriers: README.md, "In your own Vulkan shaders", lists each one.
 * Between frames, the end-of-frame pass (raycache/end_frame.glsl, five lines, dispatched indirectly from
 * the frame buffer) makes the frame's stores visible, visiting only the texels stored.
 * The confidence test (C++'s raycache::mark_doubtful_edges): define RAYCACHE_CONFIDENCE in every shader of
 * the frame and bind the doubtful-bit buffers (CCT 5, CDCT 6); a second end-of-frame pass, the mark pass
 * (with the cube tables, CCT 7, CDCT 8), marks the texels whose colours differ from a neighbour's, and
 * lookups and searches then miss on them (raycache/shared/gpu_layout.h, raycache/end_frame.glsl).
 * Resting cubes (C++'s raycache/resting.hpp): ask raycache_cube_rests(cube, direction) before a lookup; true
 * means the host started the frame with the cube resting (raycache/gpu_resting.hpp decides) and the
 * direction is not one of its probes: trace the ray, neither look it up nor store it (cube.glsl).
 * The origin test (C++'s lookup and store with an OriginTolerance; CCT): define RAYCACHE_ORIGINS in every
 * shader of the frame, bind the origin records (9), look up and store with raycache_cct_lookup_from and
 * raycache_cct_store_from, and end frames with the drop pass too (raycache/shared/origin_rule.h,
 * raycache/end_frame.glsl).
 * glslangValidator --target-env vulkan1.1 -I <RayCache_GLSL_INCLUDE_DIR>, or raycache_add_glsl_shader().
 */
#ifndef RAYCACHE_RAYCACHE_GLSL
#define RAYCACHE_RAYCACHE_GLSL

#include "raycache/cct.glsl"
#ifdef RAYCACHE_CDCT
#include "raycache/cdct.glsl"
#endif
#include "raycache/filter.glsl"

#endif /* RAYCACHE_RAYCACHE_GLSL */
