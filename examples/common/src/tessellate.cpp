// Moving spheres as meshes (rcx/tessellate.hpp).
#include "rcx/tessellate.hpp"

#include <stdexcept>
#include <string>
#include <vector>

#include "rcx/meshes.hpp"

namespace rcx {

std::size_t sphere_mesh_triangles(int level) {
    return level < 2 ? 0 : 4u * static_cast<std::size_t>(level) * static_cast<std::size_t>(level - 1);
}

Scene tessellate_moving_spheres(const Scene& scene, int level) {
    if (level < 2) throw std::invalid_argument("tessellate_moving_spheres: level must be >= 2, got " + std::to_string(level));
    std::vector<const Motion*> motion_of(scene.spheres.size(), nullptr);
    for (const Motion& m : scene.motions)
        if (m.kind == Motion::Kind::sphere) motion_of.at(m.index) = &m;
    Scene out = scene;
    out.spheres.clear();
    out.motions.clear();
    for (const Motion& m : scene.motions)
        if (m.kind == Motion::Kind::mesh) out.motions.push_back(m); // mesh indices stay: meshes are only appended
    for (std::size_t i = 0; i < scene.spheres.size(); ++i) {
        const Sphere& sphere = scene.spheres[i];
        if (!motion_of[i]) {
            out.spheres.push_back(sphere);
            continue;
        }
        Mesh mesh = make_sphere(sphere.radius, 2 * level, level);
        translate_mesh(mesh, sphere.centre);
        mesh.material = sphere.material;
        out.meshes.push_back(std::move(mesh));
        Motion moved = *motion_of[i];
        moved.kind = Motion::Kind::mesh;
        moved.index = out.meshes.size() - 1;
        out.motions.push_back(moved);
    }
    return out;
}

} // namespace rcx
