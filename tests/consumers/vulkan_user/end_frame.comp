#version 450
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_END_FRAME
#include "raycache/end_frame.glsl"
layout(local_size_x = RAYCACHE_END_FRAME_GROUP_SIZE) in;
void main() { raycache_end_frame_pass(); }
