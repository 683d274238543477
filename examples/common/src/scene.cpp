// The example scenes. Layout notes per scene are next to their builders; every scene stands on the
// checkerboard floor (meshes[0], y = floor_height) and is lit by one point light.
#include "rcx/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <stdexcept>

#include "rcx/meshes.hpp"

namespace rcx {

namespace {

constexpr float pi = 3.14159265358979323846f;

glm::vec3 rotate_y(const glm::vec3& v, float degrees) {
    const float a = degrees * pi / 180.0f;
    const float c = std::cos(a), s = std::sin(a);
    return {c * v.x + s * v.z, v.y, -s * v.x + c * v.z};
}

// Distinct, saturated colours for the coloured balls; index wraps around.
glm::vec3 palette(std::size_t i) {
    static const glm::vec3 colors[] = {
        {0.85f, 0.15f, 0.12f}, {0.15f, 0.65f, 0.20f}, {0.15f, 0.30f, 0.85f}, {0.90f, 0.75f, 0.10f},
        {0.70f, 0.20f, 0.75f}, {0.10f, 0.70f, 0.75f}, {0.95f, 0.45f, 0.10f}, {0.55f, 0.80f, 0.25f},
    };
    return colors[i % (sizeof colors / sizeof colors[0])];
}

Material mirror(float reflectivity, glm::vec3 tint = glm::vec3(0.9f)) {
    Material m;
    m.diffuse = tint;
    m.reflectivity = reflectivity;
    m.specular = 0.6f;
    m.shininess = 96.0f;
    m.cached = true;
    return m;
}

Material matte(glm::vec3 color) {
    Material m;
    m.diffuse = color;
    m.specular = 0.3f;
    m.shininess = 32.0f;
    return m;
}

// The parts every scene shares: floor, light, sky, depth; the camera orbits 1 degree a frame, 10 frames.
Scene base_scene(const std::string& name) {
    Scene s;
    s.name = name;
    s.meshes.push_back(checkerboard_floor());
    s.light.position = {-5.0f, 9.0f, 1.0f};
    s.light.intensity = glm::vec3(1.0f);
    s.environment = {0.40f, 0.55f, 0.75f};
    s.ambient = 0.1f;
    s.max_depth = 5;
    s.path.kind = CameraPath::Kind::orbit;
    s.path.frames = 10;
    s.path.step_degrees = 1.0f;
    return s;
}

Sphere on_floor(float x, float z, float radius, const Material& m) {
    return Sphere{{x, floor_height + radius, z}, radius, m};
}

// Figure 5.2 / Table 5.1: the main mirror sphere (r = 1 at the origin) faces the camera, which is 3.2 away
// and sees it fill about 80% of a square image; n extra mirror spheres stand behind the camera in a curved
// wall of 8 x 4 slots (filled nearest to the wall's centre first), visible only in the main sphere.
Scene behind(int n, const SceneParams& params) {
    Scene s = base_scene("behind-" + std::to_string(n));
    s.spheres.push_back(Sphere{{0.0f, 0.0f, 0.0f}, 1.0f, mirror(0.85f)});

    struct Slot { glm::vec3 centre; float key; };
    std::vector<Slot> slots;
    const float r = 0.7f;
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 8; ++col) {
            const float x = (static_cast<float>(col) - 3.5f) * 1.5f;
            const float y = floor_height + r + 1.5f * static_cast<float>(row);
            const float z = 4.5f + 0.06f * x * x; // curved towards the main sphere
            const glm::vec3 c(x, y, z);
            slots.push_back({c, glm::length(c - glm::vec3(0.0f, 1.0f, 4.5f))});
        }
    std::stable_sort(slots.begin(), slots.end(), [](const Slot& a, const Slot& b) { return a.key < b.key; });
    for (int i = 0; i < n; ++i) {
        Material m = mirror(0.7f, palette(static_cast<std::size_t>(i)));
        m.cached = params.cache_behind_spheres;
        s.spheres.push_back(Sphere{slots[static_cast<std::size_t>(i)].centre, r, m});
    }
    s.camera.eye = {0.0f, 0.35f, 3.2f};
    s.camera.target = {0.0f, 0.0f, 0.0f};
    s.camera.fov_y_degrees = 45.0f;
    return s;
}

// Figure 1.1 / 3.4 / Table 5.2: an 8 x 4 grid of tinted mirror spheres on the floor, in front of the camera
// (grid-32); grid-N keeps N of its slots, nearest the grid's centre first. Distances are exact integers in
// half-slot units, (2 col - 7, 2 row - 3); ties go to the slot nearer the centre across the rows (so that
// grid-8 is the middle 4 x 2 block), then row-major. The kept spheres stay in row-major order with their
// grid-32 colours, so grid-32 is the full grid, and every N uses grid-32's camera.
Scene grid(int n) {
    Scene s = base_scene("grid-" + std::to_string(n));
    struct Slot { int row, col, distance2, across; };
    std::vector<Slot> slots;
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 8; ++col) {
            const int dx = 2 * col - 7, dz = 2 * row - 3;
            slots.push_back({row, col, dx * dx + dz * dz, std::abs(dz)});
        }
    std::stable_sort(slots.begin(), slots.end(), [](const Slot& a, const Slot& b) {
        return a.distance2 != b.distance2 ? a.distance2 < b.distance2 : a.across < b.across;
    });
    slots.resize(static_cast<std::size_t>(n));
    std::sort(slots.begin(), slots.end(), [](const Slot& a, const Slot& b) { return a.row * 8 + a.col < b.row * 8 + b.col; });
    for (const Slot& slot : slots) {
        const float x = (static_cast<float>(slot.col) - 3.5f) * 1.4f;
        const float z = -1.4f * static_cast<float>(slot.row);
        s.spheres.push_back(on_floor(x, z, 0.5f, mirror(0.8f, palette(static_cast<std::size_t>(slot.row * 8 + slot.col)))));
    }
    s.camera.eye = {0.0f, 3.0f, 7.0f};
    s.camera.target = {0.0f, -0.6f, -2.1f};
    s.camera.fov_y_degrees = 50.0f;
    return s;
}

// Table 5.3 (Figure 5.6): a mirror sphere (r = 1 at the origin) inside two rings of 11 + 20 balls.
Scene ring_scene(const std::string& name, bool reflective) {
    Scene s = base_scene(name);
    s.spheres.push_back(Sphere{{0.0f, 0.0f, 0.0f}, 1.0f, mirror(0.9f)});
    auto ring = [&](int count, float radius, float ball, std::size_t colour0) {
        for (int i = 0; i < count; ++i) {
            // Half a step off the +Z axis, so no ball sits between the camera and the main sphere.
            const float a = (static_cast<float>(i) + 0.5f) * 2.0f * pi / static_cast<float>(count);
            const glm::vec3 colour = palette(colour0 + static_cast<std::size_t>(i));
            const Material m = reflective ? mirror(0.75f, colour) : matte(colour);
            s.spheres.push_back(on_floor(radius * std::sin(a), radius * std::cos(a), ball, m));
        }
    };
    ring(11, 2.3f, 0.4f, 0);
    ring(20, 3.7f, 0.45f, 3);
    s.camera.eye = {0.0f, 3.6f, 7.5f};
    s.camera.target = {0.0f, -0.4f, 0.0f};
    s.camera.fov_y_degrees = 42.0f;
    return s;
}

// Figure 5.10: a mirror cone and a mirror cylinder (triangle meshes, cached), coloured balls around.
Scene cone_cylinder() {
    Scene s = base_scene("cone-cylinder");
    Mesh cone = make_cone(0.9f, 2.2f, 96);
    translate_mesh(cone, {-1.2f, floor_height, 0.0f});
    cone.material = mirror(0.85f);
    Mesh cylinder = make_cylinder(0.8f, 1.8f, 96);
    translate_mesh(cylinder, {1.2f, floor_height, 0.0f});
    cylinder.material = mirror(0.85f);
    s.meshes.push_back(std::move(cone));
    s.meshes.push_back(std::move(cylinder));
    const glm::vec2 balls[] = {{-3.0f, -1.5f}, {0.0f, -2.5f}, {3.0f, -1.5f}, {-2.6f, 1.8f}, {2.8f, 1.6f}};
    for (std::size_t i = 0; i < 5; ++i) s.spheres.push_back(on_floor(balls[i].x, balls[i].y, 0.5f, matte(palette(i))));
    s.camera.eye = {0.0f, 1.6f, 6.0f};
    s.camera.target = {0.0f, 0.0f, 0.0f};
    s.camera.fov_y_degrees = 45.0f;
    return s;
}

// The Wuson (assimp-testmodels) turned three-quarters to a camera on +Z, `size` across, standing on the
// floor at (x, z); names the Debian package when the default model is missing.
Mesh wuson_on_floor(const std::string& scene_name, const SceneParams& params, float size, glm::vec2 at) {
    Mesh wuson;
    try {
        wuson = load_mesh(params.mesh_path);
    } catch (const std::exception& e) {
        if (params.mesh_path != SceneParams{}.mesh_path) throw;
        throw std::runtime_error(std::string(e.what()) + " (scene '" + scene_name +
                                 "' needs the Wuson model; on Debian/Ubuntu: apt-get install assimp-testmodels)");
    }
    wuson.name = params.mesh_path == SceneParams{}.mesh_path ? "wuson" : "--mesh " + params.mesh_path;
    rotate_mesh(wuson, {0.0f, 1.0f, 0.0f}, -55.0f); // Y-up, body along Z: turn it three-quarters to the camera
    fit_mesh(wuson, {0.0f, 0.0f, 0.0f}, size);
    const Bounds b = mesh_bounds(wuson);
    translate_mesh(wuson, {at.x, floor_height - b.min.y, at.y});
    return wuson;
}

// Figure 5.11: a concave mirror object (the Wuson, from assimp-testmodels) and a mirror torus, both cached.
Scene concave(const SceneParams& params) {
    Scene s = base_scene("concave");
    Mesh wuson = wuson_on_floor(s.name, params, 2.4f, {-1.2f, 0.0f});
    wuson.material = mirror(0.85f);
    Mesh torus = make_torus(0.7f, 0.25f, 96, 48);
    rotate_mesh(torus, {1.0f, 0.0f, 0.0f}, 70.0f); // nearly upright, its hole facing the camera
    translate_mesh(torus, {1.7f, floor_height + 0.97f, -0.5f});
    torus.material = mirror(0.85f);
    s.meshes.push_back(std::move(wuson));
    s.meshes.push_back(std::move(torus));
    const glm::vec2 balls[] = {{-3.0f, -1.8f}, {0.4f, -2.4f}, {3.4f, -1.4f}, {2.8f, 2.2f}};
    for (std::size_t i = 0; i < 4; ++i) s.spheres.push_back(on_floor(balls[i].x, balls[i].y, 0.5f, matte(palette(i))));
    s.camera.eye = {0.0f, 1.6f, 5.0f};
    s.camera.target = {0.0f, -0.2f, 0.0f};
    s.camera.fov_y_degrees = 45.0f;
    return s;
}

// A glass ball (refraction with Fresnel, cached) over the checkerboard, coloured balls behind it.
Scene glass() {
    Scene s = base_scene("glass");
    Material g;
    g.diffuse = glm::vec3(1.0f);
    g.transparency = 1.0f;
    g.ior = 1.5f;
    g.specular = 0.6f;
    g.shininess = 128.0f;
    g.cached = true;
    s.spheres.push_back(Sphere{{0.0f, 0.0f, 0.0f}, 1.0f, g});
    const glm::vec2 balls[] = {{-1.8f, -2.5f}, {0.0f, -3.5f}, {1.9f, -2.2f}, {-0.9f, -5.0f}};
    for (std::size_t i = 0; i < 4; ++i) s.spheres.push_back(on_floor(balls[i].x, balls[i].y, 0.6f, matte(palette(i))));
    s.camera.eye = {0.0f, 0.8f, 4.5f};
    s.camera.target = {0.0f, -0.1f, 0.0f};
    s.camera.fov_y_degrees = 42.0f;
    return s;
}

// Many small mirrors, for memory and start-up time: a 10 x 10 x 10 lattice of tinted mirror spheres
// (r = 0.15, 0.5 apart, every one cached) floating above the floor, the whole lattice in view.
Scene mirrors1000() {
    Scene s = base_scene("mirrors-1000");
    constexpr int side = 10;
    constexpr float spacing = 0.5f, radius = 0.15f;
    const float half = 0.5f * spacing * static_cast<float>(side - 1);
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j)
            for (int k = 0; k < side; ++k) {
                const glm::vec3 centre(spacing * static_cast<float>(i) - half, -0.5f + spacing * static_cast<float>(j),
                                       spacing * static_cast<float>(k) - half);
                s.spheres.push_back(Sphere{centre, radius, mirror(0.8f, palette(static_cast<std::size_t>(i + j + k)))});
            }
    s.camera.eye = {0.0f, 3.6f, 11.0f};
    s.camera.target = {0.0f, 1.5f, 0.0f};
    s.camera.fov_y_degrees = 45.0f;
    return s;
}

// Moving objects among static mirrors (for dynamic-scene work: the ray-space hierarchy, cache
// invalidation): four static cached mirror spheres (r = 0.9) at the corners of a 5.6-wide square, the
// Wuson (matte, 1.0 across) circling the centre, and n small spheres (r = 0.35; even ones cached mirrors,
// odd ones matte) on rings around it, each circling through its ring slot (circle r = 0.25) at 1.5 to 3
// degrees a frame, some bobbing up to 0.4; no two objects ever overlap. The camera orbits 1 degree a frame
// for 30 frames.
Scene dynamic_scene(int n, const SceneParams& params) {
    Scene s = base_scene("dynamic-" + std::to_string(n));
    for (int i = 0; i < 4; ++i) {
        const float x = (i % 2 == 0) ? -2.8f : 2.8f, z = (i / 2 == 0) ? -2.8f : 2.8f;
        s.spheres.push_back(on_floor(x, z, 0.9f, mirror(0.85f, palette(static_cast<std::size_t>(i) + 4))));
    }
    // Ring 0 (6 slots) runs between the Wuson and the mirrors, rings of 16 outside the mirrors, 1.8 apart:
    // slots far enough apart that neighbours circling them never meet.
    for (int i = 0; i < n; ++i) {
        const int ring = i < 6 ? 0 : 1 + (i - 6) / 16;
        const int slot = i < 6 ? i : (i - 6) % 16;
        const int slots = ring == 0 ? 6 : 16;
        const float angle = (static_cast<float>(slot) + 0.5f * static_cast<float>(ring % 2)) * 2.0f * pi /
                            static_cast<float>(slots);
        const float ring_radius = ring == 0 ? 2.0f : 5.8f + 1.8f * static_cast<float>(ring - 1);
        const Material m = (i % 2 == 0) ? mirror(0.7f, palette(static_cast<std::size_t>(i))) : matte(palette(static_cast<std::size_t>(i)));
        s.spheres.push_back(on_floor(ring_radius * std::cos(angle), ring_radius * std::sin(angle), 0.35f, m));
        Motion motion;
        motion.kind = Motion::Kind::sphere;
        motion.index = s.spheres.size() - 1;
        motion.circle_radius = 0.25f;
        motion.degrees_per_frame = 1.5f + 0.75f * static_cast<float>(i % 3);
        motion.phase_degrees = 37.0f * static_cast<float>(i);
        motion.bob = (i % 4 == 1) ? 0.4f : 0.0f;
        s.motions.push_back(motion);
    }
    Mesh wuson = wuson_on_floor(s.name, params, 1.0f, {0.0f, 0.0f});
    wuson.material = matte({0.85f, 0.8f, 0.7f});
    s.meshes.push_back(std::move(wuson));
    Motion mesh_motion;
    mesh_motion.kind = Motion::Kind::mesh;
    mesh_motion.index = s.meshes.size() - 1;
    mesh_motion.circle_radius = 0.15f;
    mesh_motion.degrees_per_frame = 2.0f;
    s.motions.push_back(mesh_motion);
    s.camera.eye = {0.0f, 6.0f, 12.5f};
    s.camera.target = {0.0f, -0.5f, 0.0f};
    s.camera.fov_y_degrees = 50.0f;
    s.path.frames = 30;
    return s;
}

const char* const valid_names = "behind-N (N = 0..32), grid-N (N = 1..32; grid-32 is the full grid), diffuse-31, reflective-32, cone-cylinder, concave, "
                                "glass, mirrors-1000, dynamic-N (N = 1..256)";

// N of "<prefix>N" for N in [low, high]; -1 when the name does not start with prefix; throws
// invalid_argument for a bad or out-of-range N.
int numbered(const std::string& name, const std::string& prefix, int low, int high) {
    if (name.compare(0, prefix.size(), prefix) != 0) return -1;
    const std::string digits = name.substr(prefix.size());
    const bool all_digits = !digits.empty() && digits.size() <= 3 &&
                            std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; });
    const int n = all_digits ? std::stoi(digits) : -1;
    if (n < low || n > high)
        throw std::invalid_argument("scene '" + name + "': " + prefix + "N takes N = " + std::to_string(low) + ".." +
                                    std::to_string(high) + "; valid scenes: " + valid_names);
    return n;
}

} // namespace

CameraBasis camera_basis(const Camera& camera, int width, int height) {
    CameraBasis b;
    b.eye = camera.eye;
    b.forward = glm::normalize(camera.target - camera.eye);
    b.right = glm::normalize(glm::cross(b.forward, camera.up));
    b.up = glm::cross(b.right, b.forward);
    b.tan_half_fov = std::tan(0.5f * camera.fov_y_degrees * 3.14159265358979f / 180.0f);
    b.aspect = static_cast<float>(width) / static_cast<float>(height);
    b.width = width;
    b.height = height;
    return b;
}

glm::vec3 primary_direction(const CameraBasis& b, int x, int y) {
    const float sx = (2.0f * (static_cast<float>(x) + 0.5f) / static_cast<float>(b.width) - 1.0f) * b.tan_half_fov * b.aspect;
    const float sy = (1.0f - 2.0f * (static_cast<float>(y) + 0.5f) / static_cast<float>(b.height)) * b.tan_half_fov;
    return glm::normalize(b.forward + sx * b.right + sy * b.up);
}

Camera CameraPath::at(const Camera& start, int frame) const {
    Camera c = start;
    const float angle = step_degrees * static_cast<float>(frame);
    switch (kind) {
    case Kind::fixed: break;
    case Kind::orbit:
        c.eye = start.target + rotate_y(start.eye - start.target, angle);
        c.up = rotate_y(start.up, angle);
        break;
    case Kind::pan:
        c.target = start.eye + rotate_y(start.target - start.eye, angle);
        c.up = rotate_y(start.up, angle);
        break;
    }
    return c;
}

const char* to_string(CameraPath::Kind kind) {
    switch (kind) {
    case CameraPath::Kind::fixed: return "fixed";
    case CameraPath::Kind::orbit: return "orbit";
    case CameraPath::Kind::pan: return "pan";
    }
    return "?";
}

CameraPath::Kind parse_path_kind(const std::string& text) {
    if (text == "fixed") return CameraPath::Kind::fixed;
    if (text == "orbit") return CameraPath::Kind::orbit;
    if (text == "pan") return CameraPath::Kind::pan;
    throw std::invalid_argument("unknown camera path '" + text + "'; valid paths: orbit, pan, fixed");
}

glm::vec3 Motion::offset(int frame) const {
    const float p = phase_degrees * pi / 180.0f;
    const float turned = degrees_per_frame * static_cast<float>(frame) * pi / 180.0f;
    return {circle_radius * (std::cos(p + turned) - std::cos(p)), 0.5f * bob * (1.0f - std::cos(turned)),
            circle_radius * (std::sin(p + turned) - std::sin(p))};
}

Scene Scene::at_frame(int frame) const {
    Scene moved = *this;
    for (const Motion& m : motions) {
        const glm::vec3 d = m.offset(frame);
        if (m.kind == Motion::Kind::sphere) moved.spheres.at(m.index).centre += d;
        else translate_mesh(moved.meshes.at(m.index), d);
    }
    return moved;
}

int Scene::cached_object_count() const {
    int n = 0;
    for (const Sphere& s : spheres) n += s.material.cached ? 1 : 0;
    for (const Mesh& m : meshes) n += m.material.cached ? 1 : 0;
    return n;
}

Material checkerboard_material() {
    Material m;
    m.diffuse = glm::vec3(0.85f);
    m.checker = true;
    m.checker_color = glm::vec3(0.12f);
    m.checker_scale = 1.0f;
    return m;
}

Mesh checkerboard_floor(float height, float half_extent) {
    Mesh m;
    m.name = "floor";
    const float e = half_extent;
    m.positions = {{-e, height, -e}, {e, height, -e}, {e, height, e}, {-e, height, e}};
    m.normals.assign(4, glm::vec3(0.0f, 1.0f, 0.0f));
    m.triangles = {{0, 2, 1}, {0, 3, 2}}; // counter-clockwise seen from above
    m.material = checkerboard_material();
    return m;
}

Scene make_scene(const std::string& name, const SceneParams& params) {
    if (const int n = numbered(name, "behind-", 0, max_behind_spheres); n >= 0) return behind(n, params);
    if (const int n = numbered(name, "dynamic-", 1, max_dynamic_spheres); n >= 0) return dynamic_scene(n, params);
    if (const int n = numbered(name, "grid-", 1, max_grid_spheres); n >= 0) return grid(n);
    if (name == "diffuse-31") return ring_scene(name, false);
    if (name == "reflective-32") return ring_scene(name, true);
    if (name == "cone-cylinder") return cone_cylinder();
    if (name == "concave") return concave(params);
    if (name == "glass") return glass();
    if (name == "mirrors-1000") return mirrors1000();
    throw std::invalid_argument("unknown scene '" + name + "'; valid scenes: " + valid_names);
}

std::vector<std::string> scene_names() {
    return {"behind-0", "behind-1",   "behind-2",      "behind-4",      "behind-8", "behind-16", "behind-32",
            "grid-32",  "diffuse-31", "reflective-32", "cone-cylinder", "concave",  "glass",
            "mirrors-1000", "dynamic-8"};
}

} // namespace rcx
