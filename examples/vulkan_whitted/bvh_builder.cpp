// The Vulkan tracer's BVH builder; see bvh_builder.hpp.
#include "bvh_builder.hpp"

#include <algorithm>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>

#include <embree3/rtcore.h>
#include <glm/glm.hpp>

namespace rcx::gpu {

namespace {

// Nodes made by Embree's builder callbacks, in Embree's thread-local memory.
struct BuildNode {
    bool leaf = false;
};
struct InnerNode : BuildNode {
    BuildNode* children[2] = {nullptr, nullptr};
    RTCBounds bounds[2];
};
struct LeafNode : BuildNode {
    std::uint32_t count = 0;
    std::uint32_t ids[1]; // count entries (allocated to fit)
};

void* create_node(RTCThreadLocalAllocator alloc, unsigned int child_count, void*) {
    if (child_count != 2) return nullptr;
    void* memory = rtcThreadLocalAlloc(alloc, sizeof(InnerNode), 16);
    return new (memory) InnerNode();
}

void set_children(void* node, void** children, unsigned int child_count, void*) {
    auto* inner = static_cast<InnerNode*>(node);
    for (unsigned i = 0; i < child_count && i < 2; ++i) inner->children[i] = static_cast<BuildNode*>(children[i]);
}

void set_bounds(void* node, const RTCBounds** bounds, unsigned int child_count, void*) {
    auto* inner = static_cast<InnerNode*>(node);
    for (unsigned i = 0; i < child_count && i < 2; ++i) inner->bounds[i] = *bounds[i];
}

void* create_leaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* prims, size_t count, void*) {
    const std::size_t bytes = sizeof(LeafNode) + (count > 0 ? count - 1 : 0) * sizeof(std::uint32_t);
    void* memory = rtcThreadLocalAlloc(alloc, bytes, 16);
    auto* leaf = new (memory) LeafNode();
    leaf->leaf = true;
    leaf->count = static_cast<std::uint32_t>(count);
    for (std::size_t i = 0; i < count; ++i) leaf->ids[i] = prims[i].primID;
    return leaf;
}

RTCBounds bounds_of_points(std::initializer_list<glm::vec3> points, float pad) {
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
    for (const glm::vec3& p : points) lo = glm::min(lo, p), hi = glm::max(hi, p);
    RTCBounds b{};
    b.lower_x = lo.x - pad, b.lower_y = lo.y - pad, b.lower_z = lo.z - pad;
    b.upper_x = hi.x + pad, b.upper_y = hi.y + pad, b.upper_z = hi.z + pad;
    return b;
}

struct Flattener {
    const std::vector<GpuPrimitive>& all;
    FlatBvh& out;
    void fill(std::size_t index, const BuildNode* node, const RTCBounds& b) {
        BvhNode n{};
        n.lo[0] = b.lower_x, n.lo[1] = b.lower_y, n.lo[2] = b.lower_z;
        n.hi[0] = b.upper_x, n.hi[1] = b.upper_y, n.hi[2] = b.upper_z;
        if (node->leaf) {
            const auto* leaf = static_cast<const LeafNode*>(node);
            n.a = static_cast<std::int32_t>(out.primitives.size());
            n.b = static_cast<std::int32_t>(leaf->count);
            for (std::uint32_t i = 0; i < leaf->count; ++i) out.primitives.push_back(all[leaf->ids[i]]);
            out.nodes[index] = n;
            return;
        }
        const auto* inner = static_cast<const InnerNode*>(node);
        const std::size_t child = out.nodes.size();
        out.nodes.resize(child + 2);
        n.a = static_cast<std::int32_t>(child);
        n.b = 0;
        out.nodes[index] = n;
        fill(child, inner->children[0], inner->bounds[0]);
        fill(child + 1, inner->children[1], inner->bounds[1]);
    }
};

} // namespace

FlatBvh build_bvh(const Scene& scene) {
    // Every primitive, with its bounds for the builder.
    std::vector<GpuPrimitive> all = gather_primitives(scene);
    std::vector<RTCBuildPrimitive> build;
    for (std::size_t i = 0; i < all.size(); ++i) {
        const GpuPrimitive& p = all[i];
        const glm::vec3 a(p.p[0][0], p.p[0][1], p.p[0][2]);
        const RTCBounds b = p.info[0] == 0 ? bounds_of_points({a - glm::vec3(p.p[0][3]), a + glm::vec3(p.p[0][3])}, 0.0f)
                                           : bounds_of_points({a, glm::vec3(p.p[1][0], p.p[1][1], p.p[1][2]),
                                                               glm::vec3(p.p[2][0], p.p[2][1], p.p[2][2])}, 0.0f);
        RTCBuildPrimitive bp{};
        bp.lower_x = b.lower_x, bp.lower_y = b.lower_y, bp.lower_z = b.lower_z;
        bp.upper_x = b.upper_x, bp.upper_y = b.upper_y, bp.upper_z = b.upper_z;
        bp.geomID = p.info[1];
        bp.primID = static_cast<unsigned>(i);
        build.push_back(bp);
    }
    if (all.empty()) throw std::runtime_error("Vulkan tracer: the scene has no primitives");

    RTCDevice device = rtcNewDevice(nullptr);
    if (!device) throw std::runtime_error("Vulkan tracer: cannot create an Embree device for the BVH builder");
    RTCBVH bvh = rtcNewBVH(device);
    RTCBuildArguments args = rtcDefaultBuildArguments();
    args.byteSize = sizeof(args);
    args.buildFlags = RTC_BUILD_FLAG_NONE;
    args.buildQuality = RTC_BUILD_QUALITY_MEDIUM;
    args.maxBranchingFactor = 2;
    args.maxDepth = 48;
    args.sahBlockSize = 1;
    args.minLeafSize = 1;
    args.maxLeafSize = 4;
    args.traversalCost = 1.0f;
    args.intersectionCost = 1.0f;
    args.bvh = bvh;
    const std::size_t count = build.size();
    build.reserve(count * 2); // spare capacity, as the builder may use it
    args.primitives = build.data();
    args.primitiveCount = count;
    args.primitiveArrayCapacity = build.capacity();
    args.createNode = create_node;
    args.setNodeChildren = set_children;
    args.setNodeBounds = set_bounds;
    args.createLeaf = create_leaf;
    args.splitPrimitive = nullptr;
    args.buildProgress = nullptr;
    args.userPtr = nullptr;
    const BuildNode* root = static_cast<const BuildNode*>(rtcBuildBVH(&args));
    const RTCError error = rtcGetDeviceError(device);
    if (!root || error != RTC_ERROR_NONE) {
        rtcReleaseBVH(bvh);
        rtcReleaseDevice(device);
        throw std::runtime_error("Vulkan tracer: Embree's BVH builder failed (error " + std::to_string(static_cast<int>(error)) + ")");
    }

    RTCBounds scene_bounds{};
    scene_bounds.lower_x = scene_bounds.lower_y = scene_bounds.lower_z = std::numeric_limits<float>::infinity();
    scene_bounds.upper_x = scene_bounds.upper_y = scene_bounds.upper_z = -std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i < count; ++i) {
        const RTCBuildPrimitive& p = build[i];
        scene_bounds.lower_x = std::min(scene_bounds.lower_x, p.lower_x);
        scene_bounds.lower_y = std::min(scene_bounds.lower_y, p.lower_y);
        scene_bounds.lower_z = std::min(scene_bounds.lower_z, p.lower_z);
        scene_bounds.upper_x = std::max(scene_bounds.upper_x, p.upper_x);
        scene_bounds.upper_y = std::max(scene_bounds.upper_y, p.upper_y);
        scene_bounds.upper_z = std::max(scene_bounds.upper_z, p.upper_z);
    }
    FlatBvh flat;
    flat.nodes.resize(1);
    Flattener{all, flat}.fill(0, root, scene_bounds);
    rtcReleaseBVH(bvh); // frees the nodes
    rtcReleaseDevice(device);
    return flat;
}

} // namespace rcx::gpu
