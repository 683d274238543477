/* raycache/end_frame.glsl: the end-of-frame pass of RayCache's GPU frame protocol, for both techniques: it
 * publishes the texels listed in the frame buffer's store list (raycache/frame.glsl) and nothing else, so
 * its cost follows the frame's stores, not the buffers' size. A whole compute shader is five lines:
 *
 *   #version 450
 *   #extension GL_GOOGLE_include_directive : require
 *   #define RAYCACHE_END_FRAME
 *   #define RAYCACHE_CDCT                      // only when CDCT cubes are in use (needs 64-bit atomics)
 *   #include "raycache/end_frame.glsl"
 *   layout(local_size_x = RAYCACHE_END_FRAME_GROUP_SIZE) in;
 *   void main() { raycache_end_frame_pass(); }
 *
 * Dispatch it with vkCmdDispatchIndirect on the frame buffer at byte offset 4 * RAYCACHE_FRAME_DISPATCH (the
 * stores keep that count), or directly with raycache::gpu_end_frame_groups(listed) groups; with the texel,
 * pending and frame buffers bound as in the frame, after a barrier that makes the frame's shader writes
 * visible to the indirect read and to this pass.
 */
#ifndef RAYCACHE_END_FRAME_GLSL
#define RAYCACHE_END_FRAME_GLSL

#include "raycache/cct.glsl"
#ifdef RAYCACHE_CDCT
#include "raycache/cdct.glsl"
#endif

#ifdef RAYCACHE_END_FRAME
/* Publishes one store-list entry (a CDCT entry is ignored unless RAYCACHE_CDCT is defined). */
void raycache_end_frame_entry(uint entry) {
    uint element = entry & ~RAYCACHE_FRAME_CDCT_ENTRY;
    if ((entry & RAYCACHE_FRAME_CDCT_ENTRY) == 0u) {
        raycache_cct_end_frame(element);
    } else {
#ifdef RAYCACHE_CDCT
        raycache_cdct_end_frame(element);
#endif
    }
}

/* The pass's body, for a 1D dispatch of raycache_end_frame_groups(listed) groups: invocation k publishes
 * entry k. No loop: on lavapipe a grid-stride loop here made the pass about 50 times slower, so the list
 * holds at most RAYCACHE_END_FRAME_MAX_ENTRIES (the host's capacity is capped there). */
void raycache_end_frame_pass() {
    uint listed = min(raycache_frame[RAYCACHE_FRAME_LIST_COUNT], raycache_frame[RAYCACHE_FRAME_LIST_CAPACITY]);
    uint k = gl_GlobalInvocationID.x;
    if (k >= listed) return;
    uint word = raycache_frame_list_word(raycache_frame[RAYCACHE_FRAME_CUBE_COUNT], k);
    if (word < uint(raycache_frame.length())) raycache_end_frame_entry(raycache_frame[word]);
}
#endif

#endif /* RAYCACHE_END_FRAME_GLSL */
