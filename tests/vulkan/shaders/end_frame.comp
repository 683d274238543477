#version 450
// The end-frame pass: makes a frame's stores visible, for every element of RayCache's buffers. Compiled
// twice, with -DEND_FRAME_CCT (bindings 0, 1) and with -DEND_FRAME_CDCT (bindings 0, 1).
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_END_FRAME
#define RAYCACHE_CCT_BINDING 0
#define RAYCACHE_CCT_PENDING_BINDING 1
#define RAYCACHE_CDCT_BINDING 0
#define RAYCACHE_CDCT_PENDING_BINDING 1
#if defined(END_FRAME_CCT)
#include "raycache/cct.glsl"
#elif defined(END_FRAME_CDCT)
#include "raycache/cdct.glsl"
#else
#error "define END_FRAME_CCT or END_FRAME_CDCT"
#endif

layout(local_size_x = 64) in;

void main() {
    // A 2D grid of groups, so that buffers of more than 65535 * 64 elements are covered too.
    uint element = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
#if defined(END_FRAME_CCT)
    raycache_cct_end_frame(element);
#else
    raycache_cdct_end_frame(element);
#endif
}
