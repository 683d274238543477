#version 450
// end_frame.comp: RayCache's end-frame pass between two frames of the Vulkan tracer: every pending
// store of the frame moves into its (empty) texel and the pending word is emptied. Compiled without
// WHITTED_CDCT for the CCT buffers (bindings 0, 1) and with it for the CDCT buffers (bindings 2, 3).
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_END_FRAME
#ifdef WHITTED_CDCT
#include "raycache/cdct.glsl"
#else
#include "raycache/cct.glsl"
#endif

// Only the blocks of 1024 elements that this frame stored into (listed by the host from the tracer's
// dirty flags): invocation k handles element blocks[k / 1024] * 1024 + k % 1024.
layout(std430, binding = 4) readonly buffer Blocks { uint blocks[]; };

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { uint count; };

void main() {
    uint k = gl_GlobalInvocationID.y * 65535u * 256u + gl_GlobalInvocationID.x;
    if (k >= count) return;
    uint i = (blocks[k >> 10] << 10) + (k & 1023u);
#ifdef WHITTED_CDCT
    raycache_cdct_end_frame(i);
#else
    raycache_cct_end_frame(i);
#endif
}
