#version 450
// RayCache's end-of-frame pass as a user writes it (raycache/end_frame.glsl), default bindings: CCT 0, 1,
// CDCT 2, 3, frame 4. Compiled as is (CCT) and with -DEND_FRAME_LISTED_CDCT (both techniques).
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_END_FRAME
#ifdef END_FRAME_LISTED_CDCT
#define RAYCACHE_CDCT
#endif
#include "raycache/end_frame.glsl"
layout(local_size_x = RAYCACHE_END_FRAME_GROUP_SIZE) in;
void main() { raycache_end_frame_pass(); }
