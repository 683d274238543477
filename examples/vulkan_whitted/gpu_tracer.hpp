// gpu_tracer.hpp: the core of the Vulkan compute Whitted example: an rcx::Scene flattened into GPU
// buffers (gpu_scene.hpp; a BVH over spheres and triangles built on the CPU with Embree's BVH builder,
// rtcBuildBVH: bvh_builder.hpp; the hybrid raster pass: raster_pass.hpp),
// traversed and shaded in a compute shader (shaders/whitted.comp) as examples/embree_whitted/tracer.cpp
// shades, one invocation per pixel; caching cubes in storage buffers, used through RayCache's GLSL
// include, with the end-frame pass (shaders/end_frame.comp) between frames.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <raycache/adaptive_resolution.hpp>
#include <raycache/cache_file.hpp>
#include <rcx/vulkan.hpp>

#include "bvh_builder.hpp"
#include "gpu_scene.hpp"
#include "rcx/image.hpp"
#include "rcx/options.hpp"
#include "rcx/scene.hpp"
#include "rsh_frame.hpp"
#include "simd_groups.hpp"

namespace rcx::gpu {

// How rays after the primary hit are traced: the BVH (built on the CPU, every frame for a dynamic scene)
// or the ray-space hierarchy (rsh_frame.hpp: built on the GPU over the rays each frame, no scene
// structure). Primary hits come from the raster pass with --hybrid, else from the BVH traversal in both
// (so rsh without --hybrid still rebuilds a BVH every frame, for the primary rays alone).
enum class Secondary { bvh, rsh };
const char* to_string(Secondary secondary);

struct TracerSettings {
    CacheMode mode = CacheMode::off;
    int face_size = 512;      // cube face texels (cct, cdct), every cube's; not used with `adaptive`
    bool adaptive = false;    // each cube's face size follows its rays (raycache/gpu_adaptive.hpp), from
                              // adaptive_resolution.first_face_size, within min_face_size..max_face_size
    raycache::AdaptiveResolution adaptive_resolution{};
    // Bytes the cubes' texel, pending and doubtful-bit buffers (and, CCT, origin records) may take together
    // (raycache::gpu_texel_bytes_within):
    // fixed faces are lowered to fit it, adaptive cubes are fitted to it after every frame (largest first).
    std::uint64_t budget_bytes = std::uint64_t{256} << 20;
    bool secant = true;       // CDCT search: the secant search (a few reads) or, false, the relief walk
    int max_reads = 8;        // CDCT secant search: reads before a miss, 1..64
    float delta = 0.2f;       // CDCT relief walk: step; epsilon (both searches), linear steps, gap (0 = none)
    float epsilon = 0.02f;
    int max_steps = 1024;
    float max_gap = 0.5f;
    bool hybrid = false;      // primary hits from a raster pass into a G-buffer (thesis Table 5.1), the rest in compute
    Secondary secondary = Secondary::bvh;
    std::uint32_t pair_capacity = 1u << 21; // rsh: pairs a stream holds (RshSettings)
    float edge_threshold = 0.1f; // cct, cdct: the confidence test's threshold (RayCache's mark pass); < 0: off
    // cct: the origin test (RAYCACHE_ORIGINS; the Embree tracer's defaults): a tile answers rays leaving from
    // within origin_drift x its cube's half-size of the origins it was stored from, and within
    // origin_parallax x the distance to the nearest surface its rays hit; origin_drift < 0: off.
    float origin_drift = 0.1f;
    float origin_parallax = 0.01f;
    // cct, cdct: resting cubes (raycache/gpu_resting.hpp): a cube whose looked-up rays found fewer than this
    // share of hits in a frame rests the next (its rays traced without lookup or store, but for its probe
    // directions). < 0: the library's default for the technique (as the Embree tracer's); 0: never.
    float min_hit_rate = -1.0f;
};

struct FrameStats {
    double warm_up_milliseconds = 0.0;   // a warm-up pass (render's warm_up_stride): its submission, waited for
    std::uint64_t warm_up_stored_texels = 0; // ... the texels it stored, which the full pass can read
    std::uint64_t warm_up_lookups = 0;   // ... and its own lookups (the full pass's are `lookups`: it traces the
                                         // other pixels, the warm-up's being final)
    double milliseconds = 0.0;           // the frame's submission, waited for on the host: the tracing dispatch and
                                         // (cct, cdct) RayCache's end-of-frame passes after it (hybrid: with the raster
                                         // pass, which a warm-up records in its own submission instead)
    double gpu_trace_milliseconds = 0.0; // of `milliseconds`, the raster pass (hybrid) and the tracing dispatch on the
                                         // GPU (timestamps; 0 without them, and for --secondary rsh)
    double end_frame_milliseconds = 0.0; // ... and the end-of-frame passes (publish, then mark) over the texels stored
    std::uint64_t stored_texels = 0;     // texels stored this frame: what that pass published
    std::uint64_t lookups = 0;           // rays leaving cached objects that reached a cube, looked up or let through by
                                         // a resting one (RayCache's GPU counters)
    std::uint64_t hits = 0;              // ... and were answered by it
    double resize_milliseconds = 0.0;    // adaptive: choosing the next face sizes and moving the cubes that changed
    std::size_t resized_cubes = 0;       // ... how many changed size after this frame (and after its warm-up)
    std::size_t resting_cubes = 0;       // cubes that rested during this frame (their rays but probes traced alone;
                                         // SceneCacheStatistics::resting_cubes counts those resting the next one)
    std::uint64_t rested = 0;            // ... the rays they let through (counted in `lookups` as misses, not in `hits`)
    SimdGroupStatistics warps;           // the tracing dispatch's groups of 32 lanes (8 x 4 pixels) with leaving rays
                                         // of cached objects, and those whose such rays all hit (simd_groups.hpp;
                                         // cct and cdct through the BVH, else empty)
    double update_ms = 0.0;              // set_scene before this frame: BVH rebuild and upload (bvh; rsh without
                                         // --hybrid, for the primary rays) or upload (rsh)
    RshFrameStats rsh;                   // rsh: the frame's traces
};

class Tracer {
public:
    // Uploads the scene; loads shaders/<name>.spv from spirv_dir (rcx::vk::Error naming the file when one
    // is missing or rejected); allocates and clears the cubes of cached objects for cct/cdct.
    // cdct needs a context with int64_atomics() (std::invalid_argument otherwise). All cubes live in one
    // storage buffer (the GLSL include binds one per technique): a face size whose cubes exceed the
    // device's maxStorageBufferRange is lowered to the largest that fits (raycache::fit_gpu_face_sizes;
    // face_size() tells).
    Tracer(vk::Context& context, const Scene& scene, const std::string& spirv_dir, const TracerSettings& settings);
    ~Tracer();
    Tracer(const Tracer&) = delete;
    Tracer& operator=(const Tracer&) = delete;

    // Moves the scene's objects (a dynamic scene's at_frame): the same objects, primitives and materials
    // in the same order, other positions. bvh: rebuilds the BVH and uploads it; rsh: uploads the
    // primitives (hybrid) or the primitives and the primary rays' rebuilt BVH (not hybrid). The time goes
    // into the next frame's FrameStats::update_ms. Throws
    // std::invalid_argument when the primitive count differs.
    void set_scene(const Scene& moved);

    // Renders one frame, then (cct, cdct) runs the end-frame pass so this frame's stores become visible, and
    // the mark pass (RayCache's confidence test, unless edge_threshold < 0): texels whose colour differs from
    // a neighbour's by more than edge_threshold read as empty from the next frame on, so their rays are traced.
    // warm_up_stride > 1 (cct, cdct): first a warm-up pass over the pixels whose x and y are multiples of it,
    // ended as a frame is (its stores published and tested), so the full pass reads what it stored: a single
    // image reuses its own rays, as the Embree tracer's RenderSettings::warm_up_stride. Adaptive cubes are
    // resized to the warm-up's rays before the full pass (as the Embree adapter's begin_frame() does after it),
    // so the full pass's rays share their texels, and again after the full pass, to its rays.
    Image render(const Camera& camera, int width, int height, FrameStats* stats = nullptr, int warm_up_stride = 0);

    // cct, cdct: writes the cubes to `path` as a RayCache cache file (raycache/gpu_cache_file.hpp; the cached
    // objects keyed by their index in the scene), or loads them from one before the next frame: the file must
    // be for `identity`, hold a cube for each cached object at its placement and (fixed face sizes) of its
    // face size; adaptive cubes take the file's sizes. Between frames. Throws raycache::CacheFileError saying
    // what is wrong (a load then leaves the cubes as they were), std::logic_error without cubes.
    void save_caches(const std::string& path, const raycache::SceneIdentity& identity) const;
    void load_caches(const std::string& path, const raycache::SceneIdentity& identity);

    std::size_t bvh_nodes() const noexcept;
    int face_size() const noexcept;          // of the cubes (adaptive: the largest now), after fitting them into one buffer
    std::vector<int> face_sizes() const;     // each cached object's cube, in object order
    std::size_t cube_bytes() const noexcept; // texel + pending buffers
    // The property flags of the memory the BVH nodes and the cube texels were placed in (0: no cubes).
    VkMemoryPropertyFlags scene_memory_flags() const noexcept;
    VkMemoryPropertyFlags cube_memory_flags() const noexcept;
    // The driver's statistics of the tracing shader's compiled code ("name value" each: registers,
    // memory, instructions, as the driver names them); empty unless the context captures them
    // (ContextOptions::shader_statistics) and for --secondary rsh.
    std::vector<std::string> shader_statistics() const;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

// Where the build put the SPIR-V files (environment RAYCACHE_VULKAN_WHITTED_SHADERS overrides it).
std::string default_spirv_dir();

} // namespace rcx::gpu
