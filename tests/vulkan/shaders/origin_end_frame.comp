#version 450
// RayCache's three end-of-frame passes with the origin test and the confidence test, default bindings (CCT
// 0, 1, CDCT 2, 3 unused, frame 4, doubtful bits 5, 6, cube tables 7, 8, origin records 9). Push constant
// `pass`: 0 publishes the listed texels and tiles, 1 marks doubtful texels, 2 drops the stale tiles; after a
// store-list overflow, 3 publishes every element and every tile (the sweep), 4 marks every element, 5 drops
// every stale tile.
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_END_FRAME
#define RAYCACHE_CONFIDENCE
#define RAYCACHE_ORIGINS
#include "raycache/end_frame.glsl"
layout(local_size_x = RAYCACHE_END_FRAME_GROUP_SIZE) in;
layout(push_constant) uniform Pass { uint pass; float threshold; };
void main() {
    uint k = gl_GlobalInvocationID.x;
    if (pass == 0u) {
        raycache_end_frame_pass();
    } else if (pass == 1u) {
        raycache_end_frame_mark_pass(threshold);
    } else if (pass == 2u) {
        raycache_end_frame_drop_pass();
    } else if (pass == 3u) {
        raycache_cct_end_frame(k);
        raycache_cct_end_frame_tile(k);
    } else if (pass == 4u) {
        raycache_mark_edges(false, k, threshold);
    } else {
        raycache_cct_drop_tile(k);
    }
}
