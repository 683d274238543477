// bvh_builder.hpp: the Vulkan tracer's BVH over spheres and triangles, built on the CPU with Embree's BVH
// builder (rtcBuildBVH) and flattened into the layout the shaders traverse (shaders/whitted.comp).
#pragma once

#include <cstdint>
#include <vector>

#include "gpu_scene.hpp"
#include "rcx/scene.hpp"

namespace rcx::gpu {

// A flattened BVH, as the shader reads it (layouts documented in shaders/whitted.comp).
struct BvhNode {
    float lo[3];
    std::int32_t a;  // inner: first child (the second is a + 1); leaf: first primitive
    float hi[3];
    std::int32_t b;  // inner: 0; leaf: primitive count
};
static_assert(sizeof(BvhNode) == 32, "GPU layouts");

struct FlatBvh {
    std::vector<BvhNode> nodes;
    std::vector<GpuPrimitive> primitives; // in leaf order
};

// Builds the BVH with Embree's BVH builder (binary, up to 4 primitives a leaf, SAH) and flattens it.
// Objects are numbered as the Embree tracer numbers its geometries: spheres, then meshes.
// Throws std::runtime_error when Embree fails or the scene has nothing in it.
FlatBvh build_bvh(const Scene& scene);

} // namespace rcx::gpu
