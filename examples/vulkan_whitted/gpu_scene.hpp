// gpu_scene.hpp: the Vulkan tracer's scene as its shaders read it (layouts documented in
// shaders/whitted.comp and shaders/scene.glsl): primitives, objects (materials, cached or not) and the
// per-frame parameters, packed from an rcx::Scene. No Vulkan calls: buffers are made by gpu_tracer.cpp.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>
#include <raycache/gpu_buffers.hpp>

#include "rcx/options.hpp"
#include "rcx/scene.hpp"

namespace rcx::gpu {

struct GpuPrimitive {
    float p[3][4];   // sphere: p[0] = centre, radius; triangle: vertices
    float n[3][4];   // triangle: vertex normals
    std::uint32_t info[4]; // kind (0 sphere, 1 triangle), object (Embree geometry id order), triangle,
                           // index in scene order (gather_primitives' order, kept when a BVH reorders them)
};
static_assert(sizeof(GpuPrimitive) == 112, "GPU layouts");

// The scene's primitives in its own order: spheres, then each mesh's triangles (objects numbered as the
// Embree tracer numbers its geometries). Throws std::invalid_argument for a malformed mesh.
std::vector<GpuPrimitive> gather_primitives(const Scene& scene);

// An object's material, cached flag, and (spheres) centre and radius.
struct GpuObject {
    float m[5][4];
};

// The per-frame parameters: camera basis, light, environment, frame size and mode, CDCT search.
struct GpuParams {
    float eye[4], forward[4], right[4], up[4];
    float light_position[4];  // w: ambient
    float light_intensity[4]; // w: tan(fov / 2)
    float environment[4];     // w: aspect
    std::int32_t frame[4];    // width, height, mode, max depth
    float relief[4];          // step, epsilon, max depth, max gap
    std::int32_t relief_i[4]; // max steps, search (RAYCACHE_DEPTH_SEARCH_*), max reads, pixel stride (warm-up)
    float origin_test[4];     // CCT origin test: drift (x the cube's half-size; < 0: off), parallax, -, -
};

inline void set4(float* out, glm::vec3 v, float w) {
    out[0] = v.x, out[1] = v.y, out[2] = v.z, out[3] = w;
}

// The shaders' number for a cache mode (GpuParams::frame[2], plus 16 for the hybrid raster pass).
int mode_number(CacheMode mode);

// The scene's objects in primitive order (spheres, then meshes), and the cubes of the cached ones.
struct GpuObjects {
    std::vector<GpuObject> objects;
    std::vector<raycache::GpuCubeShape> shapes; // the cached objects' cubes, in object order
    std::vector<int> shape_of;                  // per object: its cube in shapes, or -1
};

// Packs the objects; with `caching`, a cube of face_size texels around each cached object, placed by the
// library's rule (raycache/cube_placement.hpp: a sphere's own centre and radius, a mesh's vertices' box).
GpuObjects pack_objects(const Scene& scene, bool caching, int face_size);

} // namespace rcx::gpu
