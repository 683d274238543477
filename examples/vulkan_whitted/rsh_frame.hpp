// rsh_frame.hpp: one Whitted frame with the secondary rays traced through the ray-space hierarchy
// (rsh_engine.hpp). Generation 0 is one primary ray per pixel in Morton order, its hits traced through the
// scene's BVH as the BVH tracer traces them (or, with --hybrid, read from the raster pass's G-buffer):
// the hierarchy traces only what follows. Each generation is shaded (shaders/rsh_whitted.comp:
// shade.glsl's shading), its shadow rays traced through the hierarchy reversed, from the light (paper
// section 3.5.1), its colours gathered into the pixels, and its reflected and refracted rays compacted on
// the device (the engine's work-efficient prefix sum over their flags, then a scatter) into the next
// generation (section 3.5.2), which is traced through the hierarchy, until the scene's depth limit. The
// generations' counts stay on the device and size their passes through indirect dispatch: the whole frame
// is one submission, read back once at its end (the image and the counters). It records as many
// generations as the last frame had rays in (all, up to the depth limit, the first time), with the
// compaction after the last to count what would follow. A frame whose rays outlive the generations
// recorded, outgrow the buffers (a generation above the ray capacity) or whose pair streams overflow is
// recorded again with all generations, more room or smaller batches (the image is only ever the complete
// one).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <rcx/vulkan.hpp>

#include "rsh_engine.hpp"

namespace rcx::gpu {

struct RshFrameStats {
    RshStats trace;                 // summed over every trace of the frame (rays: slots traced)
    int generations = 0;            // of rays (primary included)
    std::uint64_t shadow_rays = 0;  // traced through the hierarchy
    std::uint64_t secondary_rays = 0; // reflected and refracted rays traced (through the hierarchy)
    double shade_ms = 0.0;          // the frame's wall time less the traces' GPU phases: primary rays,
                                    // shading, gathering, ray compaction, submission and read-back
    std::uint32_t submissions = 0;  // of the frame: 1, or more when it had to be recorded again
    std::uint32_t ray_overflows = 0; // recordings done again because a generation exceeded the ray capacity
    std::uint32_t truncations = 0;  // recordings done again because rays outlived the generations recorded
    std::uint32_t ray_capacity = 0; // rays a generation may hold (the Morton slots, more after an overflow)
};

// What the frame reads: the tracer's scene buffers (scene.glsl's bindings 5..8), the engine's primitives
// (same order as `prims`), and either the BVH for the primary rays (nodes, and its primitives in leaf
// order, each with its scene-order index in info[3]) or, for hybrid frames, the G-buffer.
struct RshSceneBuffers {
    const vk::Buffer* prims = nullptr;
    const vk::Buffer* objects = nullptr;
    const vk::Buffer* params = nullptr;
    const vk::Buffer* rsh_prims = nullptr;
    std::uint32_t prim_count = 0;
    const vk::Buffer* gbuffer = nullptr;   // hybrid: primary hits (t bits, primitive, u, v) per pixel; else null
    const vk::Buffer* bvh_nodes = nullptr; // not hybrid: the BVH the primary rays are traced through
    const vk::Buffer* bvh_prims = nullptr;
};

class RshFrame {
public:
    RshFrame(vk::Context& context, const std::string& spirv_dir, const RshSettings& settings);
    ~RshFrame();
    RshFrame(const RshFrame&) = delete;
    RshFrame& operator=(const RshFrame&) = delete;

    // Renders width x height pixels into `image` (vec4 a pixel); the params buffer holds this frame's
    // camera and image size (gpu_scene.hpp's GpuParams), max_depth the scene's (at most 30).
    void render(int width, int height, int max_depth, const RshSceneBuffers& scene, const vk::Buffer& image,
                RshFrameStats* stats = nullptr);

    const RshEngine& engine() const noexcept;

    // The rays of a width x height image lie in a square of Morton slots whose side is the next power of two
    // of the larger side; this throws std::invalid_argument, naming the size, when that square's largest
    // buffer (3 candidate pairs of 64 bytes a slot) passes `max_buffer_bytes` (maxStorageBufferRange) or its
    // largest dispatch `max_groups` (maxComputeWorkGroupCount[0]).
    static void check_image_size(int width, int height, std::uint64_t max_buffer_bytes, std::uint32_t max_groups);

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

} // namespace rcx::gpu
