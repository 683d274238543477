#version 450
// end_frame.comp: RayCache's end-of-frame passes between two frames of the Vulkan tracer (raycache/end_frame.glsl):
// push constant `mark` 0: the texels stored this frame, and only those, become visible; 1 (after a barrier):
// the confidence test's mark pass over the same texels at `threshold`; 2 (after a barrier; CCT): the drop
// pass of the origin test, which empties the tiles a lookup met from too far. Default bindings (CCT 0, 1, CDCT 2, 3,
// frame buffer 4, doubtful bits 5, 6, cube tables 7, 8, origin records 9); compiled with WHITTED_CDCT for the CDCT (64-bit
// atomics), without it for the CCT.
#extension GL_GOOGLE_include_directive : require
#define RAYCACHE_END_FRAME
#define RAYCACHE_CONFIDENCE
#ifdef WHITTED_CDCT
#define RAYCACHE_CDCT
#else
#define RAYCACHE_ORIGINS // the CCT's origin test: tiles listed by stores and stale lookups (binding 9)
#endif
#include "raycache/end_frame.glsl"
layout(local_size_x = RAYCACHE_END_FRAME_GROUP_SIZE) in;
layout(push_constant) uniform Pass { uint mark; float threshold; };
void main() {
    if (mark == 0u) raycache_end_frame_pass();
    else if (mark == 1u) raycache_end_frame_mark_pass(threshold);
    else raycache_end_frame_drop_pass();
}
