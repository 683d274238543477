#version 450
// RayCache's two end-of-frame passes with the confidence test, default bindings (CCT 0, 1, CDCT 2, 3, frame 4,
// doubtful bits 5, 6, cube tables 7, 8): push constant `mark` 0 publishes the listed texels, 1 marks the
// doubtful ones at `threshold`. Compiled as is (the CCT only: no 64-bit feature) and with -DCONFIDENCE_CDCT
// (confidence_cdct.spv).
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_END_FRAME
#define RAYCACHE_CONFIDENCE
#ifdef CONFIDENCE_CDCT
#define RAYCACHE_CDCT
#endif
#include "raycache/end_frame.glsl"
layout(local_size_x = RAYCACHE_END_FRAME_GROUP_SIZE) in;
layout(push_constant) uniform Pass { uint mark; float threshold; };
void main() {
    if (mark == 0u) raycache_end_frame_pass();
    else raycache_end_frame_mark_pass(threshold);
}
