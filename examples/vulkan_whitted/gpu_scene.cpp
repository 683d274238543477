// The Vulkan tracer's scene layout; see gpu_scene.hpp.
#include "gpu_scene.hpp"

#include <stdexcept>
#include <string>

#include <raycache/cube_placement.hpp>

#include "rcx/meshes.hpp"

namespace rcx::gpu {

std::vector<GpuPrimitive> gather_primitives(const Scene& scene) {
    std::vector<GpuPrimitive> all;
    std::uint32_t object = 0;
    for (const Sphere& s : scene.spheres) {
        GpuPrimitive p{};
        set4(p.p[0], s.centre, s.radius);
        p.info[0] = 0, p.info[1] = object, p.info[2] = 0, p.info[3] = static_cast<std::uint32_t>(all.size());
        all.push_back(p);
        ++object;
    }
    for (const Mesh& m : scene.meshes) {
        validate_mesh(m, "Vulkan tracer");
        for (std::size_t k = 0; k < m.triangles.size(); ++k) {
            const glm::uvec3 t = m.triangles[k];
            GpuPrimitive p{};
            for (int c = 0; c < 3; ++c) {
                set4(p.p[c], m.positions[t[c]], 0.0f);
                set4(p.n[c], m.normals[t[c]], 0.0f);
            }
            p.info[0] = 1, p.info[1] = object, p.info[2] = static_cast<std::uint32_t>(k);
            p.info[3] = static_cast<std::uint32_t>(all.size());
            all.push_back(p);
        }
        ++object;
    }
    return all;
}

int mode_number(CacheMode mode) {
    switch (mode) {
    case CacheMode::off: return 0;
    case CacheMode::cct: return 1;
    case CacheMode::cdct: return 2;
    case CacheMode::ceiling: return 3;
    }
    return 0;
}

GpuObjects pack_objects(const Scene& scene, bool caching, int face_size) {
    GpuObjects out;
    std::vector<GpuObject>& objects = out.objects;
    std::vector<raycache::GpuCubeShape>& shapes = out.shapes;
    std::vector<int>& shape_of = out.shape_of;
    // cube: where the object's cube sits (raycache/cube_placement.hpp), called only for cached objects.
    auto add_object = [&](const Material& m, bool sphere, glm::vec3 centre, float radius, auto cube) {
        GpuObject o{};
        set4(o.m[0], m.diffuse, m.specular);
        set4(o.m[1], m.checker_color, m.shininess);
        o.m[2][0] = m.reflectivity, o.m[2][1] = m.transparency, o.m[2][2] = m.ior, o.m[2][3] = m.checker_scale;
        o.m[3][0] = m.checker ? 1.0f : 0.0f, o.m[3][1] = m.cached ? 1.0f : 0.0f, o.m[3][2] = sphere ? 1.0f : 0.0f;
        set4(o.m[4], centre, radius);
        objects.push_back(o);
        shape_of.push_back(-1);
        if (caching && m.cached) {
            shapes.push_back({face_size, cube()});
            shape_of.back() = static_cast<int>(shapes.size() - 1);
        }
    };
    for (const Sphere& s : scene.spheres)
        add_object(s.material, true, s.centre, s.radius, [&] { return raycache::cube_around_sphere(s.centre, s.radius); });
    for (const Mesh& m : scene.meshes)
        add_object(m.material, false, glm::vec3(0.0f), 0.0f,
                   [&] { return raycache::cube_around_points(m.positions, "mesh '" + m.name + "'"); });
    return out;
}

} // namespace rcx::gpu
