// rcx/tessellate.hpp: a scene's moving spheres as triangle meshes, to grow a dynamic scene's triangle count
// (the ray-space hierarchy's benchmark) without changing what moves, where, or how it is shaded.
#pragma once

#include <cstddef>

#include "rcx/scene.hpp"

namespace rcx {

// Triangles of one sphere tessellated at `level`: 2 level segments, level rings, so 4 level (level - 1).
std::size_t sphere_mesh_triangles(int level);

// `scene` with every sphere that a Motion moves replaced by make_sphere(radius, 2 level, level) around its
// centre, with its material, appended to the meshes in sphere order; each such Motion moves its mesh. Spheres
// that stand still stay analytic; the camera, light and existing meshes are unchanged. Throws
// std::invalid_argument for level < 2.
Scene tessellate_moving_spheres(const Scene& scene, int level);

} // namespace rcx
