// rsh_frame.hpp: one Whitted frame with every ray traced through the ray-space hierarchy (rsh_engine.hpp):
// generation 0 is one primary ray per pixel in Morton order (with --hybrid, its hits come from the raster
// pass's G-buffer instead), each generation is traced, shaded (shaders/rsh_whitted.comp: shade.glsl's
// shading), its shadow rays traced reversed from the light (paper section 3.5.1), its colours gathered
// into the pixels, and its reflected and refracted rays become the next generation (section 3.5.2) until
// none is left or the scene's depth limit. The next generation's rays are compacted on the host (one
// read-back a generation); the pair streams inside each trace never leave the device.
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
    std::uint64_t secondary_rays = 0; // reflected and refracted rays traced
    double shade_ms = 0.0;          // the shading, gathering and host compaction between traces (wall)
};

// What the frame reads: the tracer's scene buffers (scene.glsl's bindings 5..8: any buffer for the
// nodes, which it does not read), the engine's primitives (same order as `prims`), and, for hybrid
// frames, the G-buffer.
struct RshSceneBuffers {
    const vk::Buffer* prims = nullptr;
    const vk::Buffer* objects = nullptr;
    const vk::Buffer* params = nullptr;
    const vk::Buffer* rsh_prims = nullptr;
    std::uint32_t prim_count = 0;
    const vk::Buffer* gbuffer = nullptr; // hybrid: primary hits (t bits, primitive, u, v) per pixel; else null
};

class RshFrame {
public:
    RshFrame(vk::Context& context, const std::string& spirv_dir, const RshSettings& settings);
    ~RshFrame();
    RshFrame(const RshFrame&) = delete;
    RshFrame& operator=(const RshFrame&) = delete;

    // Renders width x height pixels into `image` (vec4 a pixel); the params buffer holds this frame's
    // camera and image size (gpu_scene.hpp's GpuParams), max_depth the scene's.
    void render(int width, int height, int max_depth, const RshSceneBuffers& scene, const vk::Buffer& image,
                RshFrameStats* stats = nullptr);

    const RshEngine& engine() const noexcept;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

} // namespace rcx::gpu
