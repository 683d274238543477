#version 450
// end_frame.comp: RayCache's end-of-frame pass between two frames of the Vulkan tracer (raycache/end_frame.glsl):
// the texels stored this frame, and only those, become visible. Default bindings (CCT 0, 1, CDCT 2, 3, frame
// buffer 4); compiled with WHITTED_CDCT for the CDCT (64-bit atomics), without it for the CCT.
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_END_FRAME
#ifdef WHITTED_CDCT
#define RAYCACHE_CDCT
#endif
#include "raycache/end_frame.glsl"
layout(local_size_x = RAYCACHE_END_FRAME_GROUP_SIZE) in;
void main() { raycache_end_frame_pass(); }
