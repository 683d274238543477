// The Vulkan compute Whitted tracer core: frame orchestration (buffers, dispatches, the end-of-frame pass);
// the BVH is built in bvh_builder.cpp, the scene packed in gpu_scene.cpp, the hybrid raster pass recorded
// by raster_pass.cpp. See gpu_tracer.hpp.
#include "gpu_tracer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <utility>

#include <glm/glm.hpp>
#include <raycache/shared/depth_secant.h>
#include <raycache/shared/edge_rule.h>
#include <raycache/gpu_adaptive.hpp>
#include <raycache/gpu_buffers.hpp>
#include <raycache/gpu_cache_file.hpp>
#include <raycache/gpu_resting.hpp>
#include <raycache/shared/gpu_layout.h>

#include "gpu_scene.hpp"
#include "raster_pass.hpp"
#include "rcx/rsh_reference.hpp"

namespace rcx::gpu {

namespace {

double ms_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

std::string default_spirv_dir() {
    if (const char* env = std::getenv("RAYCACHE_VULKAN_WHITTED_SHADERS"); env && *env) return env;
    return RCX_VULKAN_WHITTED_SPIRV_DIR;
}

struct Tracer::Impl {
    Impl(vk::Context& c, const Scene& s, const TracerSettings& t) : context(c), scene(s), settings(t) {}
    vk::Context& context;
    Scene scene;
    TracerSettings settings;
    FlatBvh bvh;
    std::unique_ptr<vk::ComputePipeline> whitted, end_frame;
    std::unique_ptr<vk::Timestamps> timestamps; // of a frame's submission (render's trace_pass)
    std::unique_ptr<vk::Buffer> nodes, primitives, objects, cubes, params, dummy, texels, pending;
    std::unique_ptr<vk::Buffer> output, frame, gbuffer;
    std::unique_ptr<vk::Buffer> doubtful, cube_table, zeros; // RayCache's confidence test: doubtful bits, cube table
    std::unique_ptr<vk::Buffer> origins; // the CCT's origin test: a record per tile (raycache/shared/origin_rule.h)
    raycache::GpuFrameLayout frame_layout;          // RayCache's frame buffer: counters, store list
    std::unique_ptr<raycache::GpuResting> resting;  // which cubes rest the next frame (cct, cdct)
    std::unique_ptr<Raster> raster;
    std::unique_ptr<RshFrame> rsh;          // --secondary rsh: secondary rays through the ray-space hierarchy
    std::unique_ptr<vk::Buffer> rsh_prims;  // ... its primitives (raycache_rsh_primitive, scene order)
    std::unique_ptr<vk::Buffer> bvh_prims;  // ... without --hybrid: the BVH's primitives (leaf order) for the primary rays
    double update_ms = 0.0;                 // the last set_scene
    std::uint32_t texel_count = 0;
    bool cdct = false;
    // The cubes: one per cached object (shapes, in object order; shape_of: per object, its cube or -1), placed
    // in the texel buffer by `layout`. Adaptive sizes (settings.adaptive): `sized` and `still` per cube, for
    // raycache::next_gpu_face_sizes.
    std::vector<raycache::GpuCubeShape> shapes;
    std::vector<int> shape_of;
    raycache::GpuBufferLayout layout;
    std::vector<bool> sized;
    std::vector<raycache::StillRays> still;
    std::uint64_t max_buffer = 0; // maxStorageBufferRange
    std::uint64_t cube_room = 0;  // of it, what the cubes may take (the frame buffer's counters come first; the budget)

    // f(raycache::CctTexel{}) or f(raycache::CdctTexel{}): the library's per-technique calls, chosen once.
    template <class F>
    decltype(auto) with_texel(F&& f) const {
        return cdct ? f(raycache::CdctTexel{}) : f(raycache::CctTexel{});
    }
    // Whether frames store into cubes, so end with RayCache's end-of-frame passes (a warm-up's resizing may
    // change the cubes, so ask again after it).
    bool ends_frames() const noexcept { return end_frame && texel_count > 0; }
    // Whether the CCT's lookups and stores keep origins (and frames end with the drop pass).
    bool origin_test() const noexcept { return !cdct && settings.origin_drift >= 0.0f; }

    // The buffers RayCache's bindings get now (the technique's own, stand-ins for the other's); place_cubes
    // replaces them, so take them again after it.
    struct CacheBuffers {
        const vk::Buffer *cct_texels, *cct_pending, *cdct_texels, *cdct_pending, *cct_doubtful, *cdct_doubtful, *cct_table, *cdct_table;
        const vk::Buffer* cct_origins;
    };
    CacheBuffers cache_buffers() const {
        auto own = [&](bool mine, const std::unique_ptr<vk::Buffer>& b, const vk::Buffer& other) { return mine && b ? b.get() : &other; };
        return {own(!cdct, texels, *dummy),   own(!cdct, pending, *dummy),  own(cdct, texels, *dummy),
                own(cdct, pending, *dummy),   own(!cdct, doubtful, *zeros), own(cdct, doubtful, *zeros),
                own(!cdct, cube_table, *zeros), own(cdct, cube_table, *zeros), own(!cdct, origins, *dummy)};
    }

    // Places the cubes with these face sizes (one per shape): the layout, the per-object descriptors, the
    // texel, pending and doubtful buffers (cleared, or with the old cubes moved in: raycache::move_gpu_cubes,
    // unless `move_old` is false) and the frame buffer sized for the new texel count.
    void place_cubes(const std::vector<int>& sizes, bool move_old = true) { place_layout(layout_of(sizes), move_old); }
    // The layout of the cubes at these face sizes (one per shape), and placing a layout made by it.
    raycache::GpuBufferLayout layout_of(const std::vector<int>& sizes) const {
        std::vector<raycache::GpuCubeShape> placed = shapes;
        for (std::size_t k = 0; k < placed.size(); ++k) placed[k].face_size = sizes[k];
        return with_texel([&](auto texel) { return raycache::gpu_buffer_layout<decltype(texel)>(placed); });
    }
    void place_layout(raycache::GpuBufferLayout next, bool move_old);

    // The cubes' keys in a cache file, in layout order: the cached object's index in the scene, its placement.
    std::vector<raycache::GpuCubeKey> cube_keys() const {
        std::vector<raycache::GpuCubeKey> keys(shapes.size());
        for (std::size_t i = 0; i < shape_of.size(); ++i)
            if (shape_of[i] >= 0) keys[static_cast<std::size_t>(shape_of[i])] = {i, 0, shapes[static_cast<std::size_t>(shape_of[i])].bounds};
        return keys;
    }
    void require_cubes(const char* what) const {
        if (!texels || !doubtful || !texels->as<std::uint32_t>() || !doubtful->as<std::uint32_t>())
            throw std::logic_error(std::string("Vulkan tracer: ") + what + " needs caching cubes in host-visible memory (--cache cct or cdct)");
    }
};

void Tracer::Impl::place_layout(raycache::GpuBufferLayout next, bool move_old) {
    if (next.bytes > max_buffer)
        throw std::invalid_argument("Vulkan tracer: the cubes need " + std::to_string(next.bytes) +
                                    " bytes, more than one storage buffer may hold on this device (" +
                                    std::to_string(max_buffer) + "); use a smaller --face-size");
    // The budget's bound counts origin records at one byte a texel, which faces under 8 texels pass.
    if (const std::uint64_t need = raycache::gpu_cube_bytes(next, origin_test()); need > settings.budget_bytes)
        throw std::invalid_argument("Vulkan tracer: the cubes' buffers need " + std::to_string(need) +
                                    " bytes, more than --budget-mib allows (" + std::to_string(settings.budget_bytes) + " bytes)");
    std::vector<raycache::shared::raycache_gpu_cube> per_object;
    for (const int k : shape_of) {
        raycache::shared::raycache_gpu_cube none{};
        none.face_size = 0; // no texels: lookups miss, stores are refused (counted nowhere: index 0 of face size 0)
        per_object.push_back(k >= 0 ? next.cubes[static_cast<std::size_t>(k)] : none);
    }
    // Everything new is made first and swapped in at the end, so a failed allocation leaves the old cubes whole.
    auto new_cubes = std::make_unique<vk::Buffer>(vk::buffer_of(context, per_object, 16));
    const std::uint32_t cached = static_cast<std::uint32_t>(shapes.size());
    // The list holds every texel and every origin record (tiles are listed by stores and stale lookups).
    raycache::GpuFrameLayout new_frame_layout = raycache::gpu_frame_layout(
        cached, raycache::gpu_frame_list_capacity(cached, next.texels + next.origin_tiles, max_buffer), max_buffer);
    auto new_frame = std::make_unique<vk::Buffer>(context, std::max<std::uint64_t>(new_frame_layout.bytes, 16));
    std::unique_ptr<vk::Buffer> new_texels, new_pending, new_doubtful, new_table, new_origins;
    if (next.texels > 0) {
        new_texels = std::make_unique<vk::Buffer>(context, next.bytes);
        new_pending = std::make_unique<vk::Buffer>(context, next.bytes);
        new_texels->fill(RAYCACHE_GPU_CLEAR_WORD);
        new_pending->fill(RAYCACHE_GPU_CLEAR_WORD);
        new_doubtful = std::make_unique<vk::Buffer>(context, next.doubtful_bytes);
        new_doubtful->fill(raycache::gpu_doubtful_clear_word);
        new_table = std::make_unique<vk::Buffer>(vk::buffer_of(context, next.cubes)); // by first_texel, as placed
        if (origin_test()) {
            new_origins = std::make_unique<vk::Buffer>(context, next.origin_bytes);
            new_origins->fill(RAYCACHE_GPU_CLEAR_WORD);
        }
        if (texels && move_old) { // moving: the device is idle (render() waited for the frame and its end-of-frame passes)
            const bool boxes = origins && new_origins && origins->as<std::uint32_t>() && new_origins->as<std::uint32_t>();
            with_texel([&](auto texel) {
                return raycache::move_gpu_cubes<decltype(texel)>(layout, texels->as<std::uint32_t>(), doubtful->as<std::uint32_t>(), next,
                                                                 new_texels->as<std::uint32_t>(), new_doubtful->as<std::uint32_t>(),
                                                                 settings.edge_threshold, boxes ? origins->as<std::uint32_t>() : nullptr,
                                                                 boxes ? new_origins->as<std::uint32_t>() : nullptr);
            });
        }
    }
    cubes = std::move(new_cubes);
    if (resting && move_old) resting->resized(layout, next); // cubes that grew start empty
    frame_layout = new_frame_layout;
    frame = std::move(new_frame);
    texels = std::move(new_texels);
    pending = std::move(new_pending);
    doubtful = std::move(new_doubtful);
    cube_table = std::move(new_table);
    origins = std::move(new_origins);
    layout = std::move(next);
    texel_count = static_cast<std::uint32_t>(layout.texels);
}

Tracer::Tracer(vk::Context& context, const Scene& scene, const std::string& spirv_dir, const TracerSettings& settings)
    : impl_(std::make_unique<Impl>(context, scene, settings)) {
    Impl& t = *impl_;
    t.cdct = settings.mode == CacheMode::cdct;
    if (t.cdct && !context.int64_atomics())
        throw std::invalid_argument("Vulkan tracer: --cache cdct needs a device with shaderInt64 and shaderBufferInt64Atomics");
    // Shaders first: a missing or rejected SPIR-V file is the first thing to report.
    const std::string suffix = t.cdct ? "_cdct" : "";
    std::vector<VkDescriptorType> bindings(15, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    t.whitted = std::make_unique<vk::ComputePipeline>(context, spirv_dir + "/whitted" + suffix + ".spv", bindings, 0);
    if (uses_caches(settings.mode))
        t.end_frame = std::make_unique<vk::ComputePipeline>(
            context, spirv_dir + "/end_frame" + suffix + ".spv", std::vector<VkDescriptorType>(10, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
            8);
    const bool rsh = settings.secondary == Secondary::rsh;
    if (rsh && settings.mode != CacheMode::off)
        throw std::invalid_argument("Vulkan tracer: --secondary rsh traces every ray, without caching cubes: use --cache off");
    std::vector<GpuPrimitive> scene_order; // rsh: the primitives the hierarchy and the shading index
    if (rsh) {
        // No scene structure for the secondary rays: the primitives in scene order. Without --hybrid the
        // primary rays are traced as the BVH path traces them, through a BVH (rebuilt by set_scene).
        scene_order = gather_primitives(scene);
        if (scene_order.empty()) throw std::runtime_error("Vulkan tracer: the scene has no primitives");
        if (settings.hybrid) {
            t.bvh.primitives = scene_order;
            t.bvh.nodes.assign(1, BvhNode{});
        } else {
            t.bvh = build_bvh(scene);
        }
        RshSettings rs;
        rs.pair_capacity = settings.pair_capacity;
        t.rsh = std::make_unique<RshFrame>(context, spirv_dir, rs);
        t.rsh_prims = std::make_unique<vk::Buffer>(vk::buffer_of(context, rsh::primitives_of(scene), 48));
    } else {
        t.bvh = build_bvh(scene);
    }

    // Objects: materials, and a cube descriptor for each cached one (face size 0: none).
    const bool caching = uses_caches(settings.mode);
    if (caching && (settings.face_size < 1 || settings.face_size > RAYCACHE_MAX_FACE_SIZE))
        throw std::invalid_argument("Vulkan tracer: --face-size must be 1.." + std::to_string(RAYCACHE_MAX_FACE_SIZE));
    if (caching && settings.adaptive) raycache::validate(settings.adaptive_resolution);
    // The GLSL include reads one texel buffer per technique, so all cubes must fit in one storage buffer
    // (lavapipe: 128 MiB), and with their pending twin and doubtful bits within the budget:
    // raycache::fit_gpu_face_sizes lowers the faces to the largest size that fits, leaving room in the buffer
    // for the frame buffer's counters, so that its store list can hold every texel (up to 16,776,960).
    // Adaptive cubes start at the first face size and then follow their rays (raycache/gpu_adaptive.hpp).
    const std::uint64_t word_bytes = t.cdct ? 8 : 4;
    const std::uint64_t range = context.properties().limits.maxStorageBufferRange;
    const std::uint32_t cached = caching ? static_cast<std::uint32_t>(scene.cached_object_count()) : 0u;
    const std::uint64_t counter_bytes = 4 * (std::uint64_t{RAYCACHE_FRAME_HEADER_WORDS} + std::uint64_t{cached} * RAYCACHE_FRAME_CUBE_WORDS);
    t.max_buffer = range;
    t.cube_room = range;
    if (cached > 0) {
        if (range <= counter_bytes) throw std::invalid_argument("Vulkan tracer: too many cached objects for one storage buffer");
        // Origin records are bounded per texel by the smallest face the cubes take: adaptive ones no smaller
        // than their minimum, so no resize passes the budget; fixed ones lowered under 8 texels to fit a tiny
        // budget are refused here, by place_cubes.
        const int smallest = settings.adaptive ? std::min(settings.adaptive_resolution.min_face_size, settings.adaptive_resolution.first_face_size)
                                               : std::min(settings.face_size, 8);
        const std::uint64_t within = t.with_texel([&](auto texel) {
            return raycache::gpu_texel_bytes_within<decltype(texel)>(settings.budget_bytes, t.origin_test(), smallest);
        });
        t.cube_room = std::min(range - counter_bytes, within);
        const int start = settings.adaptive ? settings.adaptive_resolution.first_face_size : t.settings.face_size;
        t.settings.face_size = raycache::fit_gpu_face_sizes(std::vector<int>(cached, start), word_bytes, t.cube_room)[0];
    }
    GpuObjects packed = pack_objects(scene, caching, t.settings.face_size);
    const std::vector<GpuObject>& objects = packed.objects;
    t.shapes = std::move(packed.shapes);
    t.shape_of = std::move(packed.shape_of);
    t.sized.assign(t.shapes.size(), false);
    t.still.assign(t.shapes.size(), raycache::StillRays{});
    t.place_cubes(std::vector<int>(t.shapes.size(), t.settings.face_size));
    if (caching) {
        // Negative: the technique's default; NaN passes on to GpuResting, which refuses it.
        const float rate = settings.min_hit_rate < 0.0f ? raycache::default_min_hit_rate(t.cdct) : settings.min_hit_rate;
        t.resting = std::make_unique<raycache::GpuResting>(t.shapes.size(), rate);
    }

    // Room for any binary BVH over these primitives (2n - 1 nodes), so set_scene uploads in place.
    t.nodes = std::make_unique<vk::Buffer>(context, std::max(t.bvh.nodes.size(), 2 * t.bvh.primitives.size()) * sizeof(BvhNode));
    t.nodes->upload(t.bvh.nodes.data(), t.bvh.nodes.size() * sizeof(BvhNode));
    t.primitives = std::make_unique<vk::Buffer>(vk::buffer_of(context, rsh ? scene_order : t.bvh.primitives, 16));
    if (rsh && !settings.hybrid) t.bvh_prims = std::make_unique<vk::Buffer>(vk::buffer_of(context, t.bvh.primitives, 16));
    t.objects = std::make_unique<vk::Buffer>(vk::buffer_of(context, objects, 16));
    t.params = std::make_unique<vk::Buffer>(context, sizeof(GpuParams));
    t.timestamps = std::make_unique<vk::Timestamps>(context, 3); // a frame submission's passes (render)
    t.dummy = std::make_unique<vk::Buffer>(context, 16);
    t.dummy->fill(RAYCACHE_GPU_CLEAR_WORD);
    t.zeros = std::make_unique<vk::Buffer>(context, 32); // no doubtful texels; a cube table of none
    t.zeros->fill(0u);
    if (settings.hybrid)
        t.raster = std::make_unique<Raster>(
            context, spirv_dir,
            std::initializer_list<const vk::Buffer*>{t.nodes.get(), t.primitives.get(), t.objects.get(), t.params.get()});
}

Tracer::~Tracer() = default;

void Tracer::save_caches(const std::string& path, const raycache::SceneIdentity& identity) const {
    const Impl& t = *impl_;
    t.require_cubes("saving caches");
    const std::vector<std::uint8_t> bytes = t.with_texel([&](auto texel) {
        return raycache::encode_gpu_cache<decltype(texel)>(identity, t.layout, t.cube_keys(), t.texels->as<std::uint32_t>(),
                                                           static_cast<std::size_t>(t.layout.words), t.doubtful->as<std::uint32_t>(),
                                                           t.origins ? t.origins->as<std::uint32_t>() : nullptr);
    });
    raycache::write_file_atomically(path, bytes);
}

void Tracer::load_caches(const std::string& path, const raycache::SceneIdentity& identity) {
    Impl& t = *impl_;
    t.require_cubes("loading caches");
    // Fixed faces must match; adaptive cubes take the file's sizes (and count as sized when they hold texels).
    std::vector<int> fixed;
    for (const auto& cube : t.layout.cubes) fixed.push_back(t.settings.adaptive ? 0 : cube.face_size);
    t.with_texel([&](auto texel) {
        using Texel = decltype(texel);
        const auto cubes = raycache::load_gpu_cache_file<Texel>(path, identity, t.cube_keys(), fixed); // checked whole first
        // The file's sizes must fit the device's buffer and the budget, as the tracer's own do, before
        // anything is replaced (adaptive cubes of another run may be larger than this one allows).
        raycache::GpuBufferLayout next = t.layout_of(raycache::loaded_face_sizes(cubes));
        if (next.bytes > t.cube_room)
            throw raycache::CacheFileError("RayCache: cache file '" + path + "': its cubes need " + std::to_string(next.bytes) +
                                           " bytes of texels, more than this tracer's cubes may take (" + std::to_string(t.cube_room) +
                                           ": the device's storage buffer and --budget-mib); nothing was loaded");
        t.place_layout(std::move(next), false); // the old cubes are replaced, not moved in
        t.texels->fill(RAYCACHE_GPU_CLEAR_WORD);
        t.doubtful->fill(raycache::gpu_doubtful_clear_word);
        if (t.origins) t.origins->fill(RAYCACHE_GPU_CLEAR_WORD);
        raycache::write_gpu_cubes(cubes, t.layout, t.texels->as<std::uint32_t>(), static_cast<std::size_t>(t.layout.words),
                                  t.doubtful->as<std::uint32_t>(), t.origins ? t.origins->as<std::uint32_t>() : nullptr);
        for (std::size_t k = 0; k < cubes.size(); ++k) {
            t.sized[k] = cubes[k].cube->valid_texels() > 0;
            t.still[k] = raycache::StillRays{};
            t.still[k].resized = true; // replaced: its first frame says nothing about its rays, as a made C++ cube's
            if (t.resting) t.resting->restart(t.layout.cubes[k].index, t.sized[k]); // works, as the Embree adapter's
        }
    });
}

const char* to_string(Secondary secondary) { return secondary == Secondary::rsh ? "rsh" : "bvh"; }

void Tracer::set_scene(const Scene& moved) {
    Impl& t = *impl_;
    const auto start = std::chrono::steady_clock::now();
    if (t.rsh) {
        const std::vector<GpuPrimitive> prims = gather_primitives(moved);
        const std::vector<rsh::Primitive> rp = rsh::primitives_of(moved);
        if (prims.size() != t.bvh.primitives.size())
            throw std::invalid_argument("Vulkan tracer: set_scene needs the same primitives, moved");
        t.primitives->upload(prims.data(), prims.size() * sizeof(GpuPrimitive));
        t.rsh_prims->upload(rp.data(), rp.size() * sizeof(rsh::Primitive));
        if (t.bvh_prims) { // the primary rays' BVH, rebuilt as the BVH path rebuilds it
            FlatBvh bvh = build_bvh(moved);
            if (bvh.nodes.size() * sizeof(BvhNode) > t.nodes->size())
                throw std::invalid_argument("Vulkan tracer: set_scene needs the same primitives, moved");
            t.bvh = std::move(bvh);
            t.nodes->upload(t.bvh.nodes.data(), t.bvh.nodes.size() * sizeof(BvhNode));
            t.bvh_prims->upload(t.bvh.primitives.data(), t.bvh.primitives.size() * sizeof(GpuPrimitive));
        }
    } else {
        FlatBvh bvh = build_bvh(moved);
        if (bvh.primitives.size() != t.bvh.primitives.size() || bvh.nodes.size() * sizeof(BvhNode) > t.nodes->size())
            throw std::invalid_argument("Vulkan tracer: set_scene needs the same primitives, moved");
        t.bvh = std::move(bvh);
        t.nodes->upload(t.bvh.nodes.data(), t.bvh.nodes.size() * sizeof(BvhNode));
        t.primitives->upload(t.bvh.primitives.data(), t.bvh.primitives.size() * sizeof(GpuPrimitive));
    }
    t.scene = moved;
    t.update_ms = ms_since(start);
}

std::size_t Tracer::bvh_nodes() const noexcept { return impl_->rsh && !impl_->bvh_prims ? 0 : impl_->bvh.nodes.size(); }
int Tracer::face_size() const noexcept {
    int largest = 0;
    for (const auto& cube : impl_->layout.cubes) largest = std::max(largest, cube.face_size);
    return impl_->layout.cubes.empty() ? impl_->settings.face_size : largest;
}
std::vector<int> Tracer::face_sizes() const {
    std::vector<int> sizes;
    for (const auto& cube : impl_->layout.cubes) sizes.push_back(cube.face_size);
    return sizes;
}
std::size_t Tracer::cube_bytes() const noexcept {
    return impl_->texels ? static_cast<std::size_t>(2 * impl_->texels->size()) : 0;
}
VkMemoryPropertyFlags Tracer::scene_memory_flags() const noexcept { return impl_->nodes->memory_flags(); }
VkMemoryPropertyFlags Tracer::cube_memory_flags() const noexcept {
    return impl_->texels ? impl_->texels->memory_flags() : 0;
}

std::vector<std::string> Tracer::shader_statistics() const {
    return impl_->whitted ? impl_->whitted->statistics() : std::vector<std::string>{};
}

Image Tracer::render(const Camera& camera, int width, int height, FrameStats* stats, int warm_up_stride) {
    if (width < 1 || height < 1)
        throw std::invalid_argument("Vulkan tracer: image size must be at least 1x1");
    if (warm_up_stride < 0) throw std::invalid_argument("Vulkan tracer: the warm-up stride must be 0 or more");
    Impl& t = *impl_;
    const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    if (!t.output || t.output->size() < pixels * 16) t.output = std::make_unique<vk::Buffer>(t.context, pixels * 16, vk::BufferUse::readback);
    if (t.raster && (!t.gbuffer || t.gbuffer->size() < pixels * 16)) t.gbuffer = std::make_unique<vk::Buffer>(t.context, pixels * 16);

    // The camera basis as the Embree tracer computes it (on the CPU, with glm); the shaders finish
    // rcx::primary_direction per pixel.
    const CameraBasis basis = camera_basis(camera, width, height);
    GpuParams p{};
    set4(p.eye, basis.eye, 0.0f);
    set4(p.forward, basis.forward, 0.0f);
    set4(p.right, basis.right, 0.0f);
    set4(p.up, basis.up, 0.0f);
    set4(p.light_position, t.scene.light.position, t.scene.ambient);
    set4(p.light_intensity, t.scene.light.intensity, basis.tan_half_fov);
    set4(p.environment, t.scene.environment, basis.aspect);
    p.frame[0] = width, p.frame[1] = height, p.frame[2] = mode_number(t.settings.mode) + (t.raster ? 16 : 0), p.frame[3] = t.scene.max_depth;
    p.relief[0] = t.settings.delta, p.relief[1] = t.settings.epsilon, p.relief[2] = 100.0f;
    p.relief[3] = t.settings.max_gap > 0.0f ? t.settings.max_gap : std::numeric_limits<float>::infinity();
    p.relief_i[0] = t.settings.max_steps;
    p.relief_i[1] = t.settings.secant ? RAYCACHE_DEPTH_SEARCH_SECANT : RAYCACHE_DEPTH_SEARCH_RELIEF;
    p.relief_i[2] = t.settings.max_reads;
    p.relief_i[3] = 1; // every pixel (trace_pass sets its own stride)
    p.origin_test[0] = t.origin_test() ? t.settings.origin_drift : -1.0f;
    p.origin_test[1] = t.settings.origin_parallax;
    t.params->upload(&p, sizeof p);
    // RayCache's frame buffer, started: before the frame, and again between a warm-up and the full pass.
    // Lookups mark their direction cells only for adaptive sizes (fixed ones never read them); resting cubes
    // pass their rays but probes by (raycache/gpu_resting.hpp).
    auto start_frame_buffer = [&] {
        const std::vector<std::uint32_t> words =
            raycache::gpu_frame_start_words(t.frame_layout, t.settings.adaptive, t.resting ? t.resting->resting_words() : std::vector<std::uint32_t>{});
        t.frame->upload(words.data(), words.size() * 4);
    };
    start_frame_buffer();

    const vk::Buffer& gbuffer = t.gbuffer ? *t.gbuffer : *t.dummy;

    // RayCache's end-of-frame pass over the texels stored since the frame buffer was started, dispatched from
    // the frame buffer's own group count; then, after a barrier (it reads the texels just published), the
    // confidence test's mark pass over the same list, and (CCT) the origin test's drop pass. Recorded after the tracing dispatch and a barrier, in
    // its submission: a second submission cost the frame a trip to the host and back.
    auto record_end_of_frame = [&](vk::Commands& commands) {
        struct Pass {
            std::uint32_t mark;
            float threshold;
        };
        const Impl::CacheBuffers c = t.cache_buffers();
        auto pass = [&](std::uint32_t mark) {
            const Pass push{mark, t.settings.edge_threshold};
            commands.dispatch_indirect(*t.end_frame,
                                       {*c.cct_texels, *c.cct_pending, *c.cdct_texels, *c.cdct_pending, *t.frame,
                                        *c.cct_doubtful, *c.cdct_doubtful, *c.cct_table, *c.cdct_table, *c.cct_origins},
                                       &push, sizeof push, *t.frame, raycache::gpu_end_frame_dispatch_offset);
        };
        pass(0u);
        if (raycache::shared::raycache_edge_test_enabled(t.settings.edge_threshold)) {
            commands.barrier();
            pass(1u);
        }
        if (t.origin_test()) { // after the marks, which still compare the stale tiles' texels (as C++'s do)
            commands.barrier();
            pass(2u);
        }
    };

    // One submission: the raster pass when `raster` (hybrid: it fills the G-buffer the dispatch reads), the
    // tracing dispatch over the pixels whose x and y are multiples of `stride` (1: all), and with caches the
    // end-of-frame passes. Returns their GPU times (timestamps 0..2: raster pass and tracing, then the
    // end-of-frame passes; 0 where the queue has none).
    struct PassTimes {
        double trace_ms = 0.0, end_frame_ms = 0.0;
    };
    // `done` > 1: the pixels whose x and y are multiples of it are final (a warm-up's) and left alone.
    auto trace_pass = [&](int stride, bool raster, int done = 0) {
        p.relief_i[3] = done > 1 ? -done : stride;
        t.params->upload(&p, sizeof p);
        const std::uint64_t columns = (static_cast<std::uint64_t>(width) + stride - 1) / stride;
        const std::uint64_t rows = (static_cast<std::uint64_t>(height) + stride - 1) / stride;
        const Impl::CacheBuffers c = t.cache_buffers();
        const bool caching = t.ends_frames();
        t.context.submit([&](vk::Commands& commands) {
            t.timestamps->reset(commands);
            t.timestamps->write(commands, 0);
            if (raster) {
                t.raster->record(commands.handle(), width, height, static_cast<std::uint32_t>(t.bvh.primitives.size()), gbuffer);
                commands.barrier(); // the copy's writes, visible to the tracing shader
            }
            commands.dispatch(*t.whitted,
                              {*c.cct_texels, *c.cct_pending, *c.cdct_texels, *c.cdct_pending, *t.frame, *t.nodes, *t.primitives,
                               *t.objects, *t.params, *t.output, *t.cubes, gbuffer, *c.cct_doubtful, *c.cdct_doubtful, *c.cct_origins},
                              nullptr, 0, vk::group_count(columns, 8), vk::group_count(rows, 8));
            t.timestamps->write(commands, 1);
            if (caching) {
                commands.barrier(); // the stores and the list's group count, visible to the passes
                record_end_of_frame(commands);
                t.timestamps->write(commands, 2);
            }
        });
        PassTimes times;
        const std::vector<std::uint64_t> ticks = t.timestamps->ticks(caching ? 3 : 2);
        if (ticks.size() >= 2) times.trace_ms = t.timestamps->milliseconds(ticks[0], ticks[1]);
        if (ticks.size() >= 3) times.end_frame_ms = t.timestamps->milliseconds(ticks[1], ticks[2]);
        return times;
    };
    // The frame buffer's counters and list, read back after the end of frame.
    auto frame_statistics = [&]() {
        const raycache::GpuFrameStatistics frame_stats = raycache::read_gpu_statistics(t.frame->as<std::uint32_t>(), t.frame_layout);
        // The list holds every texel, or 16,776,960 of them for larger cubes: more stores in one frame would need
        // the library's sweep, which this tracer does not run.
        if (frame_stats.overflow > 0)
            throw std::runtime_error("Vulkan tracer: more texels and tiles listed in one frame than RayCache's store list holds (" +
                                     std::to_string(t.frame_layout.list_capacity) + ")");
        if (t.resting) t.resting->after_frame(frame_stats); // which cubes rest the next frame (or the full pass)
        return frame_stats;
    };
    // Adaptive cubes: each takes the size the rays just ended call for; cubes that change size are moved into
    // new buffers (raycache/gpu_adaptive.hpp), counted in `resized`, timed in `resize_ms`.
    double resize_ms = 0.0;
    std::size_t resized = 0;
    auto resize = [&](const raycache::GpuFrameStatistics& frame_stats) {
        if (!t.settings.adaptive || t.shapes.empty()) return;
        const auto resize_start = std::chrono::steady_clock::now();
        const raycache::GpuFaceSizes next = t.with_texel([&](auto texel) {
            return raycache::next_gpu_face_sizes<decltype(texel)>(t.settings.adaptive_resolution, t.layout, frame_stats, t.sized, t.cube_room,
                                                                 &t.still);
        });
        if (next.changed) {
            for (std::size_t k = 0; k < next.face_sizes.size(); ++k) resized += next.face_sizes[k] != t.layout.cubes[k].face_size;
            t.place_cubes(next.face_sizes);
        }
        resize_ms += ms_since(resize_start);
    };

    // A warm-up pass (caches only): traced and ended like a frame of its own (adaptive cubes resized to its
    // rays, as the Embree adapter's begin_frame() does), then the frame buffer is started again, so the full
    // pass reads what the warm-up stored, and its counters and cells are the full pass's alone.
    double warm_up_ms = 0.0;
    std::uint64_t warm_up_stored = 0, warm_up_lookups = 0;
    const bool warm_up = warm_up_stride > 1 && t.ends_frames();
    if (warm_up) {
        const auto warm_up_start = std::chrono::steady_clock::now();
        trace_pass(warm_up_stride, t.raster != nullptr);
        const raycache::GpuFrameStatistics warm_up_stats = frame_statistics();
        if (stats) warm_up_stored = warm_up_stats.listed - raycache::gpu_listed_tiles(t.frame->as<std::uint32_t>(), t.frame_layout);
        warm_up_lookups = warm_up_stats.total.lookups;
        warm_up_ms = ms_since(warm_up_start);
        resize(warm_up_stats);
        start_frame_buffer(); // after the resize: the frame buffer it made, if any
    }

    auto start = std::chrono::steady_clock::now();
    PassTimes times;
    if (t.rsh) {
        if (t.raster)
            t.context.submit([&](vk::Commands& commands) {
                t.raster->record(commands.handle(), width, height, static_cast<std::uint32_t>(t.bvh.primitives.size()), gbuffer);
            });
        RshSceneBuffers b;
        b.prims = t.primitives.get(), b.objects = t.objects.get(), b.params = t.params.get(), b.rsh_prims = t.rsh_prims.get();
        b.prim_count = static_cast<std::uint32_t>(t.bvh.primitives.size());
        b.gbuffer = t.raster ? &gbuffer : nullptr;
        b.bvh_nodes = t.bvh_prims ? t.nodes.get() : nullptr;
        b.bvh_prims = t.bvh_prims.get();
        t.rsh->render(width, height, t.scene.max_depth, b, *t.output, stats ? &stats->rsh : nullptr);
    } else {
        // After a warm-up the G-buffer already holds this camera's primary hits, and the warm-up's pixels are
        // final: tracing them again would only read back what they just stored.
        times = trace_pass(1, t.raster && !warm_up, warm_up ? warm_up_stride : 0);
    }
    const double ms = ms_since(start);

    const raycache::GpuFrameStatistics gpu_stats = frame_statistics();
    // Scanned only for the caller's statistics (the list's tiles are not texels stored).
    const std::uint64_t listed_tiles = stats && t.ends_frames() ? raycache::gpu_listed_tiles(t.frame->as<std::uint32_t>(), t.frame_layout) : 0;
    resize(gpu_stats); // may replace the frame buffer

    Image image(width, height);
    const float* out = t.output->as<float>();
    for (std::size_t i = 0; i < pixels; ++i) image.pixels[i] = glm::vec3(out[4 * i], out[4 * i + 1], out[4 * i + 2]);
    if (stats && t.ends_frames() && t.settings.secondary == Secondary::bvh) {
        std::vector<std::uint32_t> outcomes(pixels); // whitted.comp's bits, in the alpha channel
        for (std::size_t i = 0; i < pixels; ++i) outcomes[i] = static_cast<std::uint32_t>(out[4 * i + 3]);
        stats->warps = simd_group_statistics(outcomes, width, height, 32);
    }
    if (stats) {
        stats->warm_up_milliseconds = warm_up_ms;
        stats->warm_up_stored_texels = warm_up_stored;
        stats->warm_up_lookups = warm_up_lookups;
        stats->milliseconds = ms;
        stats->gpu_trace_milliseconds = times.trace_ms;
        stats->end_frame_milliseconds = times.end_frame_ms;
        stats->stored_texels = gpu_stats.listed - listed_tiles;
        stats->lookups = gpu_stats.total.lookups;
        stats->hits = gpu_stats.total.hits;
        stats->update_ms = t.update_ms;
        stats->resize_milliseconds = resize_ms;
        stats->resized_cubes = resized;
        stats->resting_cubes = static_cast<std::size_t>(std::count(gpu_stats.resting.begin(), gpu_stats.resting.end(), true));
        stats->rested = gpu_stats.total.misses_by[static_cast<std::size_t>(raycache::MissReason::resting)];
    }
    t.update_ms = 0.0;
    return image;
}

} // namespace rcx::gpu
