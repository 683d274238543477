// rcx/meshes.hpp: procedural triangle meshes (cone, cylinder, sphere, torus) and mesh files read with Assimp.
// Every mesh has one smooth normal per vertex; hard edges (caps, the cone's rim) duplicate vertices.
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "rcx/scene.hpp"

namespace rcx {

// A cone standing on y = 0 (base radius `radius`, apex at y = height) with a closed base.
// segments >= 3 around the axis; throws std::invalid_argument otherwise.
Mesh make_cone(float radius, float height, int segments = 64);

// A cylinder from y = 0 to y = height, with both caps. segments >= 3.
Mesh make_cylinder(float radius, float height, int segments = 64);

// A UV sphere centred on the origin: poles on the Y axis, `rings` bands of latitude (>= 2), `segments`
// around (>= 3), 2 segments (rings - 1) triangles, every vertex on the sphere (so the mesh lies inside it).
// Throws std::invalid_argument for radius <= 0 or too few segments or rings.
Mesh make_sphere(float radius, int segments, int rings);

// A torus around the +Y axis through the origin: `major` from the axis to the tube's centre, tube radius
// `minor` (< major). major_segments, minor_segments >= 3.
Mesh make_torus(float major, float minor, int major_segments = 64, int minor_segments = 32);

// Reads every mesh of a file (any format Assimp reads), triangulated, with smooth normals generated where
// missing and identical vertices joined, merged into one Mesh (material left at its default).
// Throws std::runtime_error naming the path and Assimp's reason when it cannot be read or has no triangles.
Mesh load_mesh(const std::string& path);

// Translates and scales `mesh` uniformly so its bounding box is centred on `centre` and its largest side
// is `size`. Throws std::invalid_argument for an empty or degenerate mesh.
void fit_mesh(Mesh& mesh, const glm::vec3& centre, float size);

// Rotates positions and normals by `degrees` about `axis` (through the origin, right-handed).
void rotate_mesh(Mesh& mesh, const glm::vec3& axis, float degrees);

// Moves every vertex by `offset`.
void translate_mesh(Mesh& mesh, const glm::vec3& offset);

// Axis-aligned bounds of the positions: {min, max}; {0, 0} for an empty mesh.
struct Bounds {
    glm::vec3 min{0.0f};
    glm::vec3 max{0.0f};
};
Bounds mesh_bounds(const Mesh& mesh);

// What a tracer needs of a mesh: one normal per vertex, every triangle's indices in range. Throws
// std::invalid_argument "<who>: mesh '<name>' needs one normal per vertex" (or "... has a vertex index out
// of range") otherwise; `who` names the tracer ("Embree tracer", "Vulkan tracer").
void validate_mesh(const Mesh& mesh, const std::string& who);

} // namespace rcx
