// rcx/scene.hpp: the example scenes (after Ruff's thesis, ch. 5), their cameras and camera paths, shared by
// every example tracer (Embree on the CPU, Vulkan compute); plain data, nothing renderer-specific.
//
// Conventions: world units, +Y up, the checkerboard floor is a large quad at y = floor_height; colours are
// linear RGB; a direction need not be normalised unless stated.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace rcx {

// How a surface shades (Whitted): local Phong term weighted by 1 - reflectivity - transparency, plus a
// perfect mirror term and a refracted term split by Fresnel.
struct Material {
    glm::vec3 diffuse{0.8f};          // diffuse albedo (the first colour of a checkerboard)
    float specular = 0.0f;            // Phong highlight weight, added on top (0 = none)
    float shininess = 32.0f;          // Phong exponent
    float reflectivity = 0.0f;        // weight of the perfect mirror ray, 0..1
    float transparency = 0.0f;        // weight of the refracted part (split by Fresnel), 0..1
    float ior = 1.5f;                 // index of refraction inside the object (outside is 1)
    bool checker = false;             // checkerboard in world x/z: diffuse and checker_color alternate
    glm::vec3 checker_color{0.1f};    // the second checkerboard colour
    float checker_scale = 1.0f;       // side of one checkerboard square, world units
    bool cached = false;              // this object gets a caching cube (its leaving rays may be cached)
};

struct Sphere {
    glm::vec3 centre{0.0f};
    float radius = 1.0f;
    Material material;
};

// An indexed triangle mesh with one normal per vertex (normals.size() == positions.size()).
struct Mesh {
    std::string name;
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;
    std::vector<glm::uvec3> triangles;
    Material material;
};

struct PointLight {
    glm::vec3 position{0.0f, 10.0f, 0.0f};
    glm::vec3 intensity{1.0f};        // no fall-off with distance
    // Soft shadows (the Embree tracer only): `samples` > 1 shadow rays to points of a disc of `radius`
    // around `position`, facing the shaded point, whose visible share scales the light. 1: a point light.
    // They make every shaded hit, and so every traced ray, costlier: what a cache saves grows with them.
    int samples = 1;
    float radius = 0.0f;
};

// A pinhole camera; the image's aspect ratio comes from the image size.
struct Camera {
    glm::vec3 eye{0.0f, 0.0f, 5.0f};
    glm::vec3 target{0.0f};
    glm::vec3 up{0.0f, 1.0f, 0.0f};
    float fov_y_degrees = 45.0f;      // vertical field of view
};

// A camera's basis and image-plane scale for one image size: what every primary ray of a frame shares,
// so tracers compute it once a frame (the Vulkan tracer hands it to its shaders).
struct CameraBasis {
    glm::vec3 eye, forward, right, up;
    float tan_half_fov; // tan(fov_y / 2)
    float aspect;       // width / height
    int width, height;
};
CameraBasis camera_basis(const Camera& camera, int width, int height);

// The unit direction of the primary ray through the centre of pixel (x, y), row 0 at the top.
glm::vec3 primary_direction(const CameraBasis& basis, int x, int y);

// How the camera moves from frame to frame, starting at the scene's camera (frame 0).
struct CameraPath {
    enum class Kind { fixed, orbit, pan };
    Kind kind = Kind::fixed;
    int frames = 1;                   // frames rendered by default
    float step_degrees = 0.0f;        // rotation per frame
    // The camera of `frame` (0 = start): orbit turns the eye about the +Y axis through the target (keeps
    // the distance to the target); pan turns the view direction about +Y around the eye (keeps the eye).
    Camera at(const Camera& start, int frame) const;
};

// "fixed", "orbit", "pan"; parse_path_kind throws std::invalid_argument for anything else.
const char* to_string(CameraPath::Kind kind);
CameraPath::Kind parse_path_kind(const std::string& text);

// How one object of a dynamic scene moves: frame f translates it, from where its scene put it at frame 0,
// along a horizontal circle it travels at a fixed angular speed, while it rises and falls between its
// frame-0 height and `bob` above it (never below, so nothing sinks into the floor). Positions at frame f
// depend on f only, not on earlier frames, so any frame can be rendered first.
struct Motion {
    enum class Kind { sphere, mesh };
    Kind kind = Kind::sphere;
    std::size_t index = 0;            // into Scene::spheres or Scene::meshes
    float circle_radius = 0.0f;       // of the circle travelled, world units
    float degrees_per_frame = 0.0f;   // angular speed along the circle
    float phase_degrees = 0.0f;       // where on the circle frame 0 is (0 = the circle's +X point)
    float bob = 0.0f;                 // highest rise over the frame-0 height, world units
    // The translation from frame 0 to `frame`: (R cos(p + w f) - R cos p, bob (1 - cos(w f)) / 2,
    // R sin(p + w f) - R sin p), with p the phase and w the speed in radians.
    glm::vec3 offset(int frame) const;
};

struct Scene {
    std::string name;
    std::vector<Sphere> spheres;
    std::vector<Mesh> meshes;         // the checkerboard floor is meshes[0] in every built-in scene
    PointLight light;
    glm::vec3 environment{0.0f};      // colour of rays that escape
    float ambient = 0.1f;             // ambient light, times the diffuse colour
    Camera camera;                    // the camera of frame 0
    CameraPath path;
    int max_depth = 5;                // recursion limit: primary rays are depth 0, a hit at depth max_depth
                                      // spawns no reflected/refracted ray (shadow rays do not count)

    std::vector<Motion> motions;      // empty for static scenes; at most one per object

    Camera camera_at(int frame) const { return path.at(camera, frame); }
    int cached_object_count() const;  // spheres and meshes whose material is cached
    bool dynamic() const noexcept { return !motions.empty(); }
    // This scene as it stands at `frame`: every moving object translated by its motion's offset; the
    // camera, materials and object order unchanged (so object i is the same object in every frame).
    Scene at_frame(int frame) const;
};

// What varies beyond the name.
struct SceneParams {
    std::string mesh_path = "/usr/share/assimp/models/PLY/Wuson.ply"; // the concave object of "concave"
    // behind-N: the thesis caches only the main sphere (its extra spheres use plain ray tracing); the
    // default caches them too. Set false to reproduce the thesis's setup.
    bool cache_behind_spheres = true;
};

inline constexpr int max_behind_spheres = 32;
inline constexpr int max_grid_spheres = 32;
inline constexpr int max_dynamic_spheres = 256;
inline constexpr float floor_height = -1.0f;

// Builds a scene by name: "behind-N" (N = 0..32), "grid-N" (N = 1..32 of grid-32's spheres, nearest its
// centre first; grid-32 is the thesis's Figure 1.1 grid), "diffuse-31", "reflective-32",
// "cone-cylinder", "concave", "glass", "mirrors-1000" (1000 small cached mirror spheres), "dynamic-N"
// (N = 1..256 moving spheres and a moving Wuson among four static cached mirrors). Throws std::invalid_argument listing the valid names for an
// unknown name, std::runtime_error when a mesh file cannot be read (naming the Debian package).
Scene make_scene(const std::string& name, const SceneParams& params = {});

// One buildable name per scene, behind-N for N = 0, 1, 2, 4, 8, 16, 32 (the thesis's Table 5.1 rows).
std::vector<std::string> scene_names();

// The checkerboard floor of every built-in scene: a quad of side 2 * half_extent at y = height.
Material checkerboard_material();
Mesh checkerboard_floor(float height = floor_height, float half_extent = 100.0f);

} // namespace rcx
