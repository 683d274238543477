// tracer.hpp: the core of the Embree Whitted example: builds an Embree 3 scene from an rcx::Scene and
// renders one frame into an rcx::Image, with the secondary rays leaving cached objects going through a
// raycache::embree::SceneCache (or not, or answered by a constant: see rcx::CacheMode).
//
// Shading (Whitted): ambient + Phong diffuse and specular from one point light with a shadow ray (or, with
// PointLight::samples > 1, a disc light with that many shadow rays: soft shadows, costlier rays), perfect
// mirror reflection, refraction with Schlick's Fresnel and total internal reflection, a world-space
// checkerboard, the environment colour for rays that escape. A hit at depth scene.max_depth spawns no
// reflected or refracted ray (primary rays are depth 0; shadow rays do not count).
//
// The cache sits at one place: a ray leaving a cached object (the mirror ray off its outside, or the ray
// that leaves a refractive object after entering it and bouncing inside) is answered by
// SceneCache::leaving_ray, which traces it only on a miss.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <embree3/rtcore.h>
#include <raycache/embree/scene_cache.hpp>

#include "rcx/image.hpp"
#include "rcx/options.hpp"
#include "rcx/scene.hpp"

namespace rcx::embree {

struct RenderSettings {
    int width = 512;
    int height = 512;
    CacheMode mode = CacheMode::off;
    raycache::embree::SceneCache* caches = nullptr; // required for cct and cdct, unused otherwise
    int threads = 0;                                // 0 = every core (TBB's default)
    // cct/cdct: before the frame, a warm-up pass over every warm_up_stride-th pixel in x and y whose stores
    // the caches publish (SceneCache::begin_frame(); adaptive cubes take that pass's ray density) before the
    // full pass, so a single image reuses what it traced; the warm-up's pixels are final (traced with the
    // caches as they were before it), so the full pass does the others. 0 or 1: no warm-up (a cold frame
    // traces every ray).
    int warm_up_stride = 0;
};

// What one render did. Sums over 8x8 tiles, so the same inputs give the same counts on any thread count.
struct FrameStats {
    std::uint64_t rays = 0;          // rtcIntersect1 calls: primary + secondary (leaving rays answered by a cache excluded)
    std::uint64_t shadow_rays = 0;   // rtcOccluded1 calls
    std::uint64_t leaving_rays = 0;  // rays leaving cached objects, answered by the cache or traced
    double milliseconds = 0.0;       // wall-clock time of the tiles, without setup
};

class Tracer {
public:
    // Builds the Embree device and scene (one geometry per sphere and per mesh). Keeps a copy of `scene`.
    // Throws std::runtime_error with Embree's message when Embree fails.
    explicit Tracer(const Scene& scene);
    ~Tracer();
    Tracer(const Tracer&) = delete;
    Tracer& operator=(const Tracer&) = delete;

    const Scene& scene() const noexcept;
    RTCScene rtc_scene() const noexcept;                // committed
    std::vector<unsigned> cached_geometries() const;    // Embree geometry ids of cached objects

    // Attaches a cube of face_size x face_size texels to every cached object (bounds from the geometry).
    void attach_caches(raycache::embree::SceneCache& caches, int face_size) const;

    // Pre-fills every cube of `caches` (raycache/prefill.hpp): each empty texel traced once from its
    // cube's centre outwards, through the object itself, with the cache off, over TBB (threads: 0 = every core). The texels become
    // visible at the caches' next begin_frame(). Returns the texels stored; *milliseconds, when given,
    // the time it took.
    std::size_t prefill(raycache::embree::SceneCache& caches, int threads = 0, double* milliseconds = nullptr) const;

    // Between frames: makes the tracer render `next`, the same scene with objects moved (Scene::at_frame): the
    // moved objects' Embree buffers are rewritten and the scene's BVH rebuilt. Returns what moved (bounding
    // spheres before and after) and the light, for SceneCache::scene_changed(). Throws std::invalid_argument
    // when `next` has other objects.
    raycache::embree::SceneChange move_to(const Scene& next);

    // The colour (and hit distance) of one ray traced with the cache off, as a ray of recursion depth `depth`
    // (a ray leaving an object is depth 1). For oracles that retrace cached rays. Thread-safe.
    raycache::TracedRay trace_uncached(const glm::vec3& origin, const glm::vec3& direction, int depth) const;

    // Renders one frame. Thread-safe for concurrent calls only with distinct caches (or none).
    // Throws std::invalid_argument for a size < 1 or a cct/cdct mode without caches.
    Image render(const Camera& camera, const RenderSettings& settings, FrameStats* stats = nullptr) const;

    struct Impl; // the Embree objects and the scene copy; defined in tracer.cpp

private:
    std::unique_ptr<Impl> impl_;
};

// Ends a frame of `caches` (SceneCache::begin_frame) with each cube's end-of-frame work spread over TBB
// (threads: 0 = every core); the same result as caches.begin_frame().
raycache::embree::SceneCacheStatistics end_frame(raycache::embree::SceneCache& caches, int threads = 0);

// SceneCache::scene_changed with each pass's cubes spread over TBB (threads: 0 = every core); the same
// result as caches.scene_changed(change, policy).
raycache::embree::InvalidationStatistics scene_changed(raycache::embree::SceneCache& caches, const raycache::embree::SceneChange& change,
                                                       raycache::embree::Invalidation policy, int threads = 0);

} // namespace rcx::embree
