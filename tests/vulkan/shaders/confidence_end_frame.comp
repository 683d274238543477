#version 450
// RayCache's two end-of-frame passes with the confidence test, default bindings (CCT 0, 1, CDCT 2, 3, frame 4,
// doubtful bits 5, 6, cube tables 7, 8). Push constant `pass`: 0 publishes the listed texels, 1 marks the
// doubtful ones among them and their neighbours at `threshold`; after a store-list overflow, 2 publishes
// every element (the sweep) and 3 runs the confidence test for every element. Compiled as is (the CCT only:
// no 64-bit feature) and with -DCONFIDENCE_CDCT (confidence_cdct.spv).
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_END_FRAME
#define RAYCACHE_CONFIDENCE
#ifdef CONFIDENCE_CDCT
#define RAYCACHE_CDCT
#endif
#include "raycache/end_frame.glsl"
layout(local_size_x = RAYCACHE_END_FRAME_GROUP_SIZE) in;
layout(push_constant) uniform Pass { uint pass; float threshold; };
void main() {
    uint element = gl_GlobalInvocationID.x;
    if (pass == 0u) {
        raycache_end_frame_pass();
    } else if (pass == 1u) {
        raycache_end_frame_mark_pass(threshold);
    } else if (pass == 2u) {
        raycache_cct_end_frame(element);
#ifdef RAYCACHE_CDCT
        raycache_cdct_end_frame(element);
#endif
    } else {
        raycache_mark_edges(false, element, threshold);
        raycache_mark_edges(true, element, threshold);
    }
}
