// rcx/rsh_reference.hpp: the C++ reference of the ray-space hierarchy (Roger, Assarsson, Holzschuch,
// "Whitted ray-tracing for dynamic scenes using a ray-space hierarchy on the GPU", EGSR 2007, sections
// 3 and 4), step for step what the Vulkan engine (examples/vulkan_whitted/rsh_engine.*) does, on the CPU,
// for its tests: the hierarchy built bottom-up (4 consecutive rays per parent), traversed top-down one
// level at a time with a stream of (node, primitive) pairs that each level expands to the four children
// and compacts by an exclusive prefix sum over the kept flags, a fixed pair capacity with batches of
// primitives when a level would overflow (section 3.4), and the final intersection at the leaves.
// Layouts and the geometric tests come from raycache/shared/rsh_layout.h, as on the GPU.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include <glm/glm.hpp>
#include <raycache/shared/rsh_layout.h>

#include "rcx/scene.hpp"

namespace rcx::rsh {

using Node = raycache::shared::raycache_rsh_node;
using Pair = raycache::shared::raycache_rsh_pair;
using Ray = raycache::shared::raycache_rsh_ray;
using Primitive = raycache::shared::raycache_rsh_primitive;

// The closest hit of a ray: primitive == no_hit when none.
inline constexpr std::uint32_t no_hit = RAYCACHE_RSH_NO_HIT;
struct Hit {
    float t = std::numeric_limits<float>::infinity();
    std::uint32_t primitive = no_hit;
};

inline Primitive triangle(glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    return Primitive{glm::vec4(a, 0.0f), glm::vec4(b, 0.0f), glm::vec4(c, 0.0f)};
}
inline Primitive sphere(glm::vec3 centre, float radius) {
    return Primitive{glm::vec4(centre, radius), glm::vec4(0.0f), glm::vec4(0.0f, 0.0f, 0.0f, 1.0f)};
}

// Morton order over a square of side 2^k: index <-> pixel (x, y); 4 consecutive indices are a 2x2 block.
inline std::uint32_t morton_index(std::uint32_t x, std::uint32_t y) {
    std::uint32_t m = 0;
    for (int b = 0; b < 16; ++b) m |= ((x >> b) & 1u) << (2 * b) | ((y >> b) & 1u) << (2 * b + 1);
    return m;
}
inline glm::uvec2 morton_pixel(std::uint32_t m) {
    glm::uvec2 p(0u);
    for (int b = 0; b < 16; ++b) p.x |= ((m >> (2 * b)) & 1u) << b, p.y |= ((m >> (2 * b + 1)) & 1u) << b;
    return p;
}

// Levels below the root for `rays` leaves: the smallest L with 4^L >= rays (0 for one ray or none).
inline int levels_for(std::size_t rays) {
    int levels = 0;
    while ((std::size_t{1} << (2 * levels)) < rays) ++levels;
    return levels;
}

struct Hierarchy {
    int levels = 0;          // the leaves are level `levels`, the root level 0
    std::vector<Node> nodes; // all levels, level l from raycache_rsh_level_first(l)
    std::size_t leaf_first() const { return raycache::shared::raycache_rsh_level_first(levels); }
};

// Builds the hierarchy over `rays` (padded with empty leaves to 4^levels).
inline Hierarchy build(const std::vector<Ray>& rays) {
    using namespace raycache::shared;
    Hierarchy h;
    h.levels = levels_for(rays.size());
    h.nodes.resize(raycache_rsh_level_first(h.levels + 1), raycache_rsh_empty_node());
    const std::size_t leaves = h.leaf_first();
    for (std::size_t i = 0; i < rays.size(); ++i) h.nodes[leaves + i] = raycache_rsh_leaf(rays[i]);
    for (int l = h.levels - 1; l >= 0; --l) {
        const std::size_t first = raycache_rsh_level_first(l), below = raycache_rsh_level_first(l + 1);
        for (std::size_t k = 0; k < (std::size_t{1} << (2 * l)); ++k) {
            const Node* c = &h.nodes[below + 4 * k];
            h.nodes[first + k] = raycache_rsh_enclose(c[0], c[1], c[2], c[3]);
        }
    }
    return h;
}

// The tracer's intersection tests (shaders/primitives.glsl: Embree's sphere test and Moeller-Trumbore)
// in C++: a hit at t in (0, tfar] for triangles, [0, tfar] for spheres.
inline bool intersect(const Primitive& p, const Ray& r, float& t) {
    const glm::vec3 o = r.origin, d = r.direction;
    if (p.c.w != 0.0f) {
        const glm::vec3 c0 = glm::vec3(p.a) - o;
        const float rd2 = 1.0f / glm::dot(d, d);
        const float proj = glm::dot(c0, d) * rd2;
        const glm::vec3 perp = c0 - proj * d;
        const float l2 = glm::dot(perp, perp), r2 = p.a.w * p.a.w;
        if (!(l2 <= r2)) return false;
        const float td = std::sqrt((r2 - l2) * rd2);
        if (0.0f <= proj - td && proj - td <= r.tmax) return t = proj - td, true;
        if (0.0f <= proj + td && proj + td <= r.tmax) return t = proj + td, true;
        return false;
    }
    const glm::vec3 v0 = p.a, v1 = p.b, v2 = p.c;
    const glm::vec3 e1 = v0 - v1, e2 = v2 - v0, ng = glm::cross(e2, e1), c = v0 - o, rr = glm::cross(c, d);
    const float den = glm::dot(ng, d), abs_den = std::abs(den), sgn = den < 0.0f ? -1.0f : 1.0f;
    const float u = glm::dot(rr, e2) * sgn, v = glm::dot(rr, e1) * sgn;
    if (!(den != 0.0f && u >= 0.0f && v >= 0.0f && u + v <= abs_den)) return false;
    const float tt = glm::dot(ng, c) * sgn;
    if (!(0.0f < tt && tt <= abs_den * r.tmax)) return false;
    t = tt / abs_den;
    return true;
}

// Keeps the closer of two hits; equal distances go to the smaller primitive index (as the GPU's two
// atomicMin passes decide).
inline void keep_closest(Hit& best, float t, std::uint32_t primitive) {
    if (t < best.t || (t == best.t && primitive < best.primitive)) best = Hit{t, primitive};
}

// Every ray against every primitive: what the hierarchy must find.
inline std::vector<Hit> brute_force(const std::vector<Ray>& rays, const std::vector<Primitive>& primitives) {
    std::vector<Hit> hits(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) {
        if (!(rays[i].tmax > 0.0f)) continue;
        for (std::size_t k = 0; k < primitives.size(); ++k) {
            float t = 0.0f;
            if (intersect(primitives[k], rays[i], t)) keep_closest(hits[i], t, static_cast<std::uint32_t>(k));
        }
    }
    return hits;
}

struct TraceStats {
    std::size_t batches = 0;             // batches of primitives that completed (section 3.4)
    std::size_t overflows = 0;           // batches that overflowed the pair capacity and were split
    std::size_t cone_sphere_tests = 0;   // over all levels and batches, overflowed batches included
    std::size_t leaf_pairs = 0;          // (ray, primitive) pairs intersected at the leaves
};

// Section 3.4's batches: runs run(first, count) over primitives [0, total) in batches of at most `batch`,
// in order; a run that returns false (its stream overflowed) is split in two halves, run in turn, and
// `batch` lowered to the half, so a caller that keeps it starts its next trace with batches that fit.
// Counts completed and overflowed runs; a single primitive that overflows throws std::length_error.
template <class Run, class Count>
void for_batches(std::size_t total, std::size_t& batch, Run&& run, Count& batches, Count& overflows) {
    std::vector<std::pair<std::size_t, std::size_t>> todo;
    for (std::size_t end = total; end > 0;) {
        const std::size_t count = std::min(batch, end);
        end -= count;
        todo.push_back({end, count});
    }
    while (!todo.empty()) {
        const auto [first, count] = todo.back();
        todo.pop_back();
        if (run(first, count)) {
            ++batches;
            continue;
        }
        ++overflows;
        if (count == 1) throw std::length_error("ray-space hierarchy: one primitive meets more leaves than the pair capacity");
        batch = std::min(batch, count / 2);
        todo.push_back({first + count / 2, count - count / 2});
        todo.push_back({first, count / 2});
    }
}

// Traces `rays` (the hierarchy `h` was built from them) against `primitives` with a pair stream of at
// most `capacity` pairs (>= 1). A batch of primitives whose stream would exceed the capacity at some
// level is split in two and each half traced on its own; a single primitive that overflows alone throws
// std::length_error (the capacity is smaller than the leaves it meets).
inline std::vector<Hit> trace(const std::vector<Ray>& rays, const Hierarchy& h, const std::vector<Primitive>& primitives,
                              std::size_t capacity, TraceStats* stats = nullptr) {
    using namespace raycache::shared;
    if (capacity == 0) throw std::invalid_argument("rsh::trace: the pair capacity must be at least 1");
    TraceStats local;
    TraceStats& s = stats ? *stats : local;
    std::vector<glm::vec4> spheres(primitives.size());
    for (std::size_t k = 0; k < primitives.size(); ++k) spheres[k] = raycache_rsh_bounding_sphere(primitives[k]);
    std::vector<Hit> hits(rays.size());
    const std::uint32_t leaf_first = static_cast<std::uint32_t>(h.leaf_first());

    // One batch [first, first + count): false when a level overflowed (then nothing was written to hits).
    auto run = [&](std::size_t first, std::size_t count) {
        std::vector<Pair> in(count), out;
        for (std::size_t i = 0; i < count; ++i) in[i] = Pair{0u, static_cast<std::uint32_t>(first + i)};
        std::vector<std::uint32_t> flags, offsets;
        for (int l = 0; l < h.levels; ++l) {
            // Traversal: each pair against the four children of its node, one flag per child.
            const std::uint32_t parent_first = raycache_rsh_level_first(l), child_first = raycache_rsh_level_first(l + 1);
            flags.assign(4 * in.size(), 0u);
            for (std::size_t i = 0; i < in.size(); ++i)
                for (std::uint32_t c = 0; c < 4; ++c) {
                    const std::uint32_t child = child_first + 4 * (in[i].node - parent_first) + c;
                    flags[4 * i + c] = raycache_rsh_cone_sphere(h.nodes[child], spheres[in[i].primitive]) ? 1u : 0u;
                }
            s.cone_sphere_tests += flags.size();
            // Compaction: exclusive prefix sum of the flags, then each kept pair to its offset.
            offsets.assign(flags.size(), 0u);
            std::size_t total = 0;
            for (std::size_t j = 0; j < flags.size(); ++j) offsets[j] = static_cast<std::uint32_t>(total), total += flags[j];
            if (total > capacity) return false;
            out.assign(total, Pair{});
            for (std::size_t j = 0; j < flags.size(); ++j)
                if (flags[j])
                    out[offsets[j]] = Pair{child_first + 4 * (in[j / 4].node - parent_first) + static_cast<std::uint32_t>(j % 4),
                                           in[j / 4].primitive};
            in.swap(out);
        }
        // Final intersection at the leaves: each ray keeps its closest hit.
        s.leaf_pairs += in.size();
        for (const Pair& p : in) {
            const std::uint32_t ray = p.node - leaf_first;
            float t = 0.0f;
            if (ray < rays.size() && intersect(primitives[p.primitive], rays[ray], t)) keep_closest(hits[ray], t, p.primitive);
        }
        return true;
    };

    std::size_t batch = capacity; // the root level holds one pair per primitive
    for_batches(primitives.size(), batch, run, s.batches, s.overflows);
    return hits;
}

// The scene's primitives in the tracers' order (spheres, then each mesh's triangles), as the engine
// traces them.
inline std::vector<Primitive> primitives_of(const Scene& scene) {
    std::vector<Primitive> out;
    for (const Sphere& s : scene.spheres) out.push_back(sphere(s.centre, s.radius));
    for (const Mesh& m : scene.meshes)
        for (const glm::uvec3& t : m.triangles) out.push_back(triangle(m.positions[t.x], m.positions[t.y], m.positions[t.z]));
    return out;
}

// Test rays from a scene: the primary rays of a side x side image (side a power of 2) in Morton order,
// their hits found by brute force, and for each pixel whose primary ray hit a reflective object the
// mirrored ray (origin lifted off the surface along the normal); the other slots are empty (tmax 0).
inline std::vector<Ray> first_bounce_rays(const Scene& scene, const Camera& camera, int side) {
    const std::vector<Primitive> prims = primitives_of(scene);
    const CameraBasis basis = camera_basis(camera, side, side);
    std::vector<Ray> primary(static_cast<std::size_t>(side) * static_cast<std::size_t>(side));
    for (std::size_t m = 0; m < primary.size(); ++m) {
        const glm::uvec2 px = morton_pixel(static_cast<std::uint32_t>(m));
        primary[m] = Ray{basis.eye, std::numeric_limits<float>::infinity(),
                         primary_direction(basis, static_cast<int>(px.x), static_cast<int>(px.y)), static_cast<std::uint32_t>(m)};
    }
    const std::vector<Hit> hits = brute_force(primary, prims);
    std::vector<Ray> out(primary.size(), Ray{glm::vec3(0.0f), 0.0f, glm::vec3(0.0f, 0.0f, 1.0f), 0u});
    const std::size_t sphere_count = scene.spheres.size();
    for (std::size_t m = 0; m < primary.size(); ++m) {
        const Hit& h = hits[m];
        if (h.primitive == no_hit) continue;
        const glm::vec3 p = primary[m].origin + h.t * primary[m].direction;
        glm::vec3 n;
        float reflectivity = 0.0f;
        if (h.primitive < sphere_count) {
            n = glm::normalize(p - scene.spheres[h.primitive].centre);
            reflectivity = scene.spheres[h.primitive].material.reflectivity;
        } else {
            const Primitive& t = prims[h.primitive];
            n = glm::normalize(glm::cross(glm::vec3(t.b) - glm::vec3(t.a), glm::vec3(t.c) - glm::vec3(t.a)));
            std::size_t k = h.primitive - sphere_count;
            for (const Mesh& mesh : scene.meshes) {
                if (k < mesh.triangles.size()) { reflectivity = mesh.material.reflectivity; break; }
                k -= mesh.triangles.size();
            }
        }
        if (glm::dot(n, primary[m].direction) > 0.0f) n = -n;
        if (reflectivity <= 0.0f) continue;
        const glm::vec3 d = primary[m].direction;
        const float eps = 1e-4f * std::max(1.0f, std::max(std::abs(p.x), std::max(std::abs(p.y), std::abs(p.z))));
        out[m] = Ray{p + eps * n, std::numeric_limits<float>::infinity(), glm::normalize(d - 2.0f * glm::dot(d, n) * n),
                     static_cast<std::uint32_t>(m)};
    }
    return out;
}

} // namespace rcx::rsh
