// The example scenes (examples/common, rcx/scene.hpp and rcx/meshes.hpp): every scene builds, names are
// checked, behind-N and grid-N have their spheres where the thesis puts them, and camera paths move as specified.
#include <doctest/doctest.h>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "rcx/meshes.hpp"
#include "rcx/scene.hpp"
#include "rcx/scene_hash.hpp"
#include "rcx/tessellate.hpp"

namespace {

const std::string wuson = rcx::SceneParams{}.mesh_path;

float angle_degrees(glm::vec3 a, glm::vec3 b) {
    const float c = glm::dot(glm::normalize(a), glm::normalize(b));
    return std::acos(glm::clamp(c, -1.0f, 1.0f)) * 180.0f / 3.14159265f;
}

glm::vec3 forward(const rcx::Camera& c) { return glm::normalize(c.target - c.eye); }

// Every triangle's winding agrees with its vertex normals (but for a fraction `tolerated`: a loaded mesh
// may have a few folded or degenerate faces), every normal is unit length.
void check_mesh(const rcx::Mesh& m, double tolerated = 0.0) {
    REQUIRE(m.normals.size() == m.positions.size());
    REQUIRE_FALSE(m.triangles.empty());
    for (const glm::vec3& n : m.normals) CHECK(glm::length(n) == doctest::Approx(1.0f).epsilon(1e-4));
    int wrong = 0;
    for (const glm::uvec3& t : m.triangles) {
        REQUIRE(t.x < m.positions.size());
        REQUIRE(t.y < m.positions.size());
        REQUIRE(t.z < m.positions.size());
        const glm::vec3 face = glm::cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]);
        if (glm::dot(face, m.normals[t.x] + m.normals[t.y] + m.normals[t.z]) <= 0.0f) ++wrong;
    }
    CHECK(wrong <= tolerated * static_cast<double>(m.triangles.size()));
}

} // namespace

TEST_CASE("every listed scene builds with a checkerboard floor, a light and a cached object") {
    for (const std::string& name : rcx::scene_names()) {
        CAPTURE(name);
        if ((name == "concave" || name.rfind("dynamic-", 0) == 0) && !std::filesystem::exists(wuson)) {
            CHECK_THROWS_WITH_AS(rcx::make_scene(name), doctest::Contains("assimp-testmodels"), std::runtime_error);
            continue;
        }
        const rcx::Scene s = rcx::make_scene(name);
        CHECK(s.name == name);
        REQUIRE_FALSE(s.meshes.empty());
        CHECK(s.meshes[0].material.checker);
        CHECK(s.max_depth == 5);
        CHECK(s.path.frames >= 1);
        CHECK(s.cached_object_count() >= 1);
        for (const rcx::Mesh& m : s.meshes) check_mesh(m, m.name == "wuson" ? 0.01 : 0.0);
        for (const rcx::Sphere& sp : s.spheres) CHECK(sp.radius > 0.0f);
    }
}

TEST_CASE("the scenes have the thesis's object counts") {
    CHECK(rcx::make_scene("grid-32").spheres.size() == 32);
    CHECK(rcx::make_scene("grid-32").cached_object_count() == 32);
    const rcx::Scene diffuse = rcx::make_scene("diffuse-31");
    CHECK(diffuse.spheres.size() == 32);
    CHECK(diffuse.cached_object_count() == 1);
    const rcx::Scene reflective = rcx::make_scene("reflective-32");
    CHECK(reflective.spheres.size() == 32);
    CHECK(reflective.cached_object_count() == 32);
    const rcx::Scene cc = rcx::make_scene("cone-cylinder");
    CHECK(cc.meshes.size() == 3); // floor, cone, cylinder
    CHECK(cc.cached_object_count() == 2);
    const rcx::Scene glass = rcx::make_scene("glass");
    CHECK(glass.spheres[0].material.transparency > 0.0f);
    CHECK(glass.spheres[0].material.cached);
}

TEST_CASE("behind-N has a cached main sphere facing the camera and N cached mirror spheres behind the camera") {
    for (int n = 0; n <= rcx::max_behind_spheres; ++n) {
        CAPTURE(n);
        const rcx::Scene s = rcx::make_scene("behind-" + std::to_string(n));
        REQUIRE(s.spheres.size() == static_cast<std::size_t>(1 + n));
        CHECK(s.cached_object_count() == 1 + n);
        const glm::vec3 f = forward(s.camera);
        const rcx::Sphere& main = s.spheres[0];
        CHECK(main.material.reflectivity > 0.0f);
        CHECK(glm::dot(main.centre - s.camera.eye, f) > main.radius); // in front
        for (int i = 1; i <= n; ++i) {
            const rcx::Sphere& b = s.spheres[static_cast<std::size_t>(i)];
            CHECK(b.material.reflectivity > 0.0f);
            CHECK(glm::dot(b.centre - s.camera.eye, f) < -b.radius); // wholly behind the eye
        }
    }
    rcx::SceneParams thesis;
    thesis.cache_behind_spheres = false;
    CHECK(rcx::make_scene("behind-8", thesis).cached_object_count() == 1);
}

namespace {

// grid-32's slot (row, col) as the thesis's Figure 1.1 grid is laid out here: spheres of radius 0.5 on the
// floor, 1.4 apart, columns centred on x = 0, row 0 at z = 0 (nearest the camera), rows going to -z.
glm::vec3 grid_slot(int row, int col) { return {(col - 3.5f) * 1.4f, rcx::floor_height + 0.5f, -1.4f * row}; }

// The slots a grid-N must hold, in row-major order: `cols_by_row[r]` lists the columns taken in row r.
std::vector<glm::vec3> grid_slots(const std::vector<std::vector<int>>& cols_by_row) {
    std::vector<glm::vec3> out;
    for (int row = 0; row < static_cast<int>(cols_by_row.size()); ++row)
        for (int col : cols_by_row[static_cast<std::size_t>(row)]) out.push_back(grid_slot(row, col));
    return out;
}

void check_centres(const std::string& name, const std::vector<glm::vec3>& want) {
    CAPTURE(name);
    const rcx::Scene s = rcx::make_scene(name);
    REQUIRE(s.spheres.size() == want.size());
    for (std::size_t i = 0; i < want.size(); ++i) {
        CAPTURE(i);
        CHECK(s.spheres[i].centre.x == doctest::Approx(want[i].x).epsilon(1e-6));
        CHECK(s.spheres[i].centre.y == doctest::Approx(want[i].y).epsilon(1e-6));
        CHECK(s.spheres[i].centre.z == doctest::Approx(want[i].z).epsilon(1e-6));
    }
}

} // namespace

TEST_CASE("grid-32 is Figure 1.1's 8 x 4 grid of cached mirror spheres in front of the camera, row by row") {
    const rcx::Scene s = rcx::make_scene("grid-32");
    std::vector<std::vector<int>> all(4, {0, 1, 2, 3, 4, 5, 6, 7});
    check_centres("grid-32", grid_slots(all));
    const glm::vec3 f = forward(s.camera);
    for (std::size_t i = 0; i < s.spheres.size(); ++i) {
        CAPTURE(i);
        const rcx::Sphere& sp = s.spheres[i];
        CHECK(sp.radius == 0.5f);
        CHECK(sp.material.cached);
        CHECK(sp.material.reflectivity == doctest::Approx(0.8f));
        CHECK(glm::dot(sp.centre - s.camera.eye, f) > sp.radius); // in front of the camera
        // Tinted by column: the palette's 8 colours wrap at the row's end.
        CHECK(sp.material.diffuse == s.spheres[i % 8].material.diffuse);
        if (i % 8 != 0) CHECK(sp.material.diffuse != s.spheres[i - 1].material.diffuse);
    }
    CHECK(s.spheres[0].material.diffuse == glm::vec3(0.85f, 0.15f, 0.12f));
    CHECK(s.camera.eye == glm::vec3(0.0f, 3.0f, 7.0f));
    CHECK(s.camera.target == glm::vec3(0.0f, -0.6f, -2.1f));
}

TEST_CASE("grid-N fills grid-32's slots nearest the grid's centre first, across the rows before along them") {
    // Hand-derived from the layout: the centre is between rows 1 and 2 and columns 3 and 4; in half-slot
    // units a slot is (2 col - 7, 2 row - 3) from it, squared distance 2 for the middle four, 10 for the
    // next eight (columns 2 and 5 of rows 1-2 taken before columns 3 and 4 of rows 0 and 3: nearer in
    // rows), 18 for the corners of the middle 4 x 4 block, then outwards by column.
    check_centres("grid-1", grid_slots({{}, {3}}));
    check_centres("grid-2", grid_slots({{}, {3, 4}}));
    check_centres("grid-3", grid_slots({{}, {3, 4}, {3}}));
    check_centres("grid-4", grid_slots({{}, {3, 4}, {3, 4}}));
    check_centres("grid-8", grid_slots({{}, {2, 3, 4, 5}, {2, 3, 4, 5}}));
    check_centres("grid-12", grid_slots({{3, 4}, {2, 3, 4, 5}, {2, 3, 4, 5}, {3, 4}}));
    check_centres("grid-16", grid_slots({{2, 3, 4, 5}, {2, 3, 4, 5}, {2, 3, 4, 5}, {2, 3, 4, 5}}));
    check_centres("grid-20", grid_slots({{2, 3, 4, 5}, {1, 2, 3, 4, 5, 6}, {1, 2, 3, 4, 5, 6}, {2, 3, 4, 5}}));

    const rcx::Scene full = rcx::make_scene("grid-32");
    for (int n = 1; n <= rcx::max_grid_spheres; ++n) {
        CAPTURE(n);
        const rcx::Scene s = rcx::make_scene("grid-" + std::to_string(n));
        CHECK(s.name == "grid-" + std::to_string(n));
        REQUIRE(s.spheres.size() == static_cast<std::size_t>(n));
        CHECK(s.cached_object_count() == n);
        CHECK(s.camera.eye == full.camera.eye); // one view for the whole table
        CHECK(s.camera.target == full.camera.target);
        CHECK(s.camera.fov_y_degrees == full.camera.fov_y_degrees);
        // Each sphere is grid-32's sphere of the same slot (position, size, material), kept in row-major order.
        std::size_t j = 0;
        for (const rcx::Sphere& sp : s.spheres) {
            while (j < full.spheres.size() && full.spheres[j].centre != sp.centre) ++j;
            REQUIRE(j < full.spheres.size());
            CHECK(sp.radius == full.spheres[j].radius);
            CHECK(sp.material.diffuse == full.spheres[j].material.diffuse);
            CHECK(sp.material.reflectivity == full.spheres[j].material.reflectivity);
        }
        // Grows by one slot: grid-(N-1)'s spheres are all in grid-N.
        if (n > 1)
            for (const rcx::Sphere& prev : rcx::make_scene("grid-" + std::to_string(n - 1)).spheres) {
                bool found = false;
                for (const rcx::Sphere& sp : s.spheres) found = found || sp.centre == prev.centre;
                CHECK(found);
            }
    }
    for (const char* bad : {"grid-0", "grid-33", "grid-", "grid-x", "grid-1a", "grid--1"}) {
        CAPTURE(bad);
        CHECK_THROWS_WITH_AS(rcx::make_scene(bad), doctest::Contains("grid-N takes N = 1..32"), std::invalid_argument);
    }
}

TEST_CASE("behind-32's main sphere fills a good part of a square image") {
    const rcx::Scene s = rcx::make_scene("behind-32");
    const float distance = glm::length(s.spheres[0].centre - s.camera.eye);
    const float diameter_degrees = 2.0f * std::asin(s.spheres[0].radius / distance) * 180.0f / 3.14159265f;
    CHECK(diameter_degrees / s.camera.fov_y_degrees > 0.6f);
    CHECK(diameter_degrees / s.camera.fov_y_degrees < 1.0f);
}

TEST_CASE("unknown scene names throw invalid_argument listing the valid names") {
    for (const char* bad : {"", "nope", "grid-33", "behind-33", "behind-", "behind--1", "behind-x", "behind-1a", "behind-1000"}) {
        CAPTURE(bad);
        try {
            rcx::make_scene(bad);
            FAIL("no exception");
        } catch (const std::invalid_argument& e) {
            const std::string what = e.what();
            for (const char* valid : {"behind-N", "grid-N", "diffuse-31", "reflective-32", "cone-cylinder", "concave", "glass",
                                      "mirrors-1000", "dynamic-N"})
                CHECK(what.find(valid) != std::string::npos);
        }
    }
}

TEST_CASE("mirrors-1000 has 1000 small cached mirror spheres, apart, above the floor and inside the camera's view") {
    const rcx::Scene s = rcx::make_scene("mirrors-1000");
    REQUIRE(s.spheres.size() == 1000);
    CHECK(s.cached_object_count() == 1000);
    const rcx::CameraBasis b = rcx::camera_basis(s.camera, 1, 1);
    for (const rcx::Sphere& sp : s.spheres) {
        CHECK(sp.radius == doctest::Approx(0.15f));
        CHECK(sp.material.reflectivity > 0.0f);
        CHECK(sp.centre.y - sp.radius > rcx::floor_height);
        // The whole sphere inside the (square) view: its centre's angle off the view axis, in x and in y.
        const glm::vec3 d = sp.centre - b.eye;
        const float z = glm::dot(d, b.forward);
        REQUIRE(z > sp.radius);
        CHECK(std::abs(glm::dot(d, b.right)) + sp.radius < z * b.tan_half_fov);
        CHECK(std::abs(glm::dot(d, b.up)) + sp.radius < z * b.tan_half_fov);
    }
    // Lattice neighbours do not touch: each cube encloses only its own sphere.
    CHECK(glm::length(s.spheres[0].centre - s.spheres[1].centre) > 2.0f * s.spheres[0].radius);
}

TEST_CASE("a motion travels its circle at its speed and bobs between its frame-0 height and bob above it") {
    rcx::Motion m;
    m.circle_radius = 2.0f;
    m.degrees_per_frame = 30.0f;
    m.phase_degrees = 90.0f; // frame 0 at the circle's +Z point (0, 2): relative to the circle's centre
    m.bob = 0.4f;
    // Hand-derived: frame 3 has turned 90 degrees, to the -X point (-2, 0): offset (-2, bob/2, -2).
    const glm::vec3 three = m.offset(3);
    CHECK(three.x == doctest::Approx(-2.0f).epsilon(1e-5));
    CHECK(three.y == doctest::Approx(0.2f).epsilon(1e-5));
    CHECK(three.z == doctest::Approx(-2.0f).epsilon(1e-5));
    // Frame 6: half a turn, to (0, -2): offset (0, bob, -4), the highest point.
    const glm::vec3 six = m.offset(6);
    CHECK(six.x == doctest::Approx(0.0f).scale(1.0f).epsilon(1e-5));
    CHECK(six.y == doctest::Approx(0.4f).epsilon(1e-5));
    CHECK(six.z == doctest::Approx(-4.0f).epsilon(1e-5));
    // A whole turn (frame 12) and frame 0 bring it back.
    CHECK(glm::length(m.offset(12)) < 1e-5f);
    CHECK(m.offset(0) == glm::vec3(0.0f));
    for (int f = 0; f < 40; ++f) CHECK(m.offset(f).y >= 0.0f); // never below its frame-0 height
}

TEST_CASE("dynamic-N: N moving spheres and a moving Wuson among four static cached mirrors") {
    if (!std::filesystem::exists(wuson)) {
        CHECK_THROWS_WITH_AS(rcx::make_scene("dynamic-8"), doctest::Contains("assimp-testmodels"), std::runtime_error);
        return;
    }
    const rcx::Scene s = rcx::make_scene("dynamic-8");
    CHECK(s.name == "dynamic-8");
    REQUIRE(s.spheres.size() == 4u + 8u);
    REQUIRE(s.meshes.size() == 2u); // the floor and the Wuson
    CHECK(s.dynamic());
    REQUIRE(s.motions.size() == 9u);
    CHECK(s.cached_object_count() == 4 + 4); // the static mirrors and the even moving spheres
    for (std::size_t i = 0; i < 4; ++i) CHECK(s.spheres[i].material.cached);
    for (const rcx::Motion& m : s.motions) {
        if (m.kind == rcx::Motion::Kind::sphere) CHECK(m.index >= 4u); // the mirrors stand still
        else CHECK(m.index == 1u);                                      // the Wuson, not the floor
    }
    CHECK_FALSE(rcx::make_scene("behind-4").dynamic());
    CHECK(rcx::make_scene("dynamic-256").spheres.size() == 260u);
    for (const char* bad : {"dynamic-0", "dynamic-257", "dynamic-", "dynamic-x"}) {
        CAPTURE(bad);
        CHECK_THROWS_WITH_AS(rcx::make_scene(bad), doctest::Contains("dynamic-N takes N = 1..256"), std::invalid_argument);
    }
}

TEST_CASE("a dynamic scene at frame f moves exactly its moving objects, by their offsets, and nothing else") {
    if (!std::filesystem::exists(wuson)) return; // assimp-testmodels not installed
    const rcx::Scene s = rcx::make_scene("dynamic-16");
    const rcx::Scene same = s.at_frame(0);
    for (std::size_t i = 0; i < s.spheres.size(); ++i) CHECK(same.spheres[i].centre == s.spheres[i].centre);
    const int frame = 45;
    const rcx::Scene later = s.at_frame(frame);
    REQUIRE(later.spheres.size() == s.spheres.size());
    REQUIRE(later.meshes.size() == s.meshes.size());
    std::vector<glm::vec3> want(s.spheres.size());
    for (std::size_t i = 0; i < s.spheres.size(); ++i) want[i] = s.spheres[i].centre;
    glm::vec3 mesh_offset(0.0f);
    for (const rcx::Motion& m : s.motions) {
        if (m.kind == rcx::Motion::Kind::sphere) want[m.index] += m.offset(frame);
        else mesh_offset = m.offset(frame);
    }
    int moved = 0;
    for (std::size_t i = 0; i < s.spheres.size(); ++i) {
        CAPTURE(i);
        CHECK(glm::length(later.spheres[i].centre - want[i]) < 1e-5f);
        CHECK(later.spheres[i].radius == s.spheres[i].radius);
        CHECK(later.spheres[i].material.cached == s.spheres[i].material.cached);
        moved += later.spheres[i].centre != s.spheres[i].centre ? 1 : 0;
        CHECK(later.spheres[i].centre.y - later.spheres[i].radius >= rcx::floor_height - 1e-5f); // not in the floor
    }
    CHECK(moved == 16);
    CHECK(glm::length(mesh_offset) > 0.1f);
    for (std::size_t v = 0; v < s.meshes[1].positions.size(); v += 97)
        CHECK(glm::length(later.meshes[1].positions[v] - (s.meshes[1].positions[v] + mesh_offset)) < 1e-5f);
    CHECK(later.meshes[0].positions == s.meshes[0].positions); // the floor stays
    CHECK(later.camera.eye == s.camera.eye);
}

TEST_CASE("dynamic-N's objects never overlap one another along their paths") {
    if (!std::filesystem::exists(wuson)) return; // assimp-testmodels not installed
    const rcx::Scene s = rcx::make_scene("dynamic-64");
    for (int frame = 0; frame < 240; frame += 3) {
        const rcx::Scene at = s.at_frame(frame);
        const rcx::Bounds mesh = rcx::mesh_bounds(at.meshes[1]);
        for (std::size_t i = 0; i < at.spheres.size(); ++i) {
            const rcx::Sphere& a = at.spheres[i];
            // Against the Wuson's box (in x/z: the spheres stand beside it, not over it).
            const glm::vec3 nearest = glm::clamp(a.centre, mesh.min, mesh.max);
            if (glm::length(nearest - a.centre) <= a.radius) FAIL("sphere " << i << " meets the Wuson at frame " << frame);
            for (std::size_t j = i + 1; j < at.spheres.size(); ++j)
                if (glm::length(a.centre - at.spheres[j].centre) <= a.radius + at.spheres[j].radius)
                    FAIL("spheres " << i << " and " << j << " overlap at frame " << frame);
        }
    }
}

TEST_CASE("an orbit keeps the distance to the target and turns the eye about +Y by the step") {
    rcx::Camera start;
    start.eye = {1.0f, 2.0f, 6.0f};
    start.target = {0.5f, 0.0f, -1.0f};
    rcx::CameraPath path{rcx::CameraPath::Kind::orbit, 10, 3.0f};
    for (int f = 0; f < 10; ++f) {
        CAPTURE(f);
        const rcx::Camera c = path.at(start, f);
        CHECK(c.target == start.target);
        CHECK(glm::length(c.eye - c.target) == doctest::Approx(glm::length(start.eye - start.target)).epsilon(1e-5));
        CHECK(c.eye.y == doctest::Approx(start.eye.y));
        const glm::vec3 a = start.eye - start.target, b = c.eye - c.target;
        CHECK(angle_degrees({a.x, 0, a.z}, {b.x, 0, b.z}) == doctest::Approx(3.0f * f).epsilon(1e-3));
    }
}

TEST_CASE("a pan keeps the eye and turns the view direction about +Y by the step") {
    rcx::Camera start;
    start.eye = {0.0f, 1.0f, 4.0f};
    start.target = {0.0f, 0.0f, 0.0f};
    rcx::CameraPath path{rcx::CameraPath::Kind::pan, 9, 10.0f / 3.0f};
    for (int f = 0; f < 9; ++f) {
        CAPTURE(f);
        const rcx::Camera c = path.at(start, f);
        CHECK(c.eye == start.eye);
        const glm::vec3 a = forward(start), b = forward(c);
        CHECK(b.y == doctest::Approx(a.y).epsilon(1e-5)); // about +Y: the pitch is unchanged
        CHECK(angle_degrees({a.x, 0, a.z}, {b.x, 0, b.z}) == doctest::Approx(10.0f / 3.0f * f).epsilon(1e-3));
    }
    const rcx::CameraPath fixed{rcx::CameraPath::Kind::fixed, 5, 7.0f};
    CHECK(fixed.at(start, 4).eye == start.eye);
    CHECK(fixed.at(start, 4).target == start.target);
    CHECK(rcx::parse_path_kind("pan") == rcx::CameraPath::Kind::pan);
    CHECK_THROWS_AS(rcx::parse_path_kind("spin"), std::invalid_argument);
}

TEST_CASE("procedural meshes have outward windings, unit normals and their analytic shape") {
    check_mesh(rcx::make_cone(1.0f, 2.0f, 16));
    check_mesh(rcx::make_cylinder(1.0f, 2.0f, 16));
    const rcx::Mesh torus = rcx::make_torus(2.0f, 0.5f, 24, 12);
    check_mesh(torus);
    for (const glm::vec3& p : torus.positions) {
        const glm::vec2 ring = glm::normalize(glm::vec2(p.x, p.z)) * 2.0f;
        CHECK(glm::length(p - glm::vec3(ring.x, 0.0f, ring.y)) == doctest::Approx(0.5f).epsilon(1e-4));
    }
    const rcx::Bounds b = rcx::mesh_bounds(rcx::make_cylinder(1.0f, 2.0f, 64));
    CHECK(b.min.y == doctest::Approx(0.0f));
    CHECK(b.max.y == doctest::Approx(2.0f));
    CHECK_THROWS_AS(rcx::make_cone(1.0f, 1.0f, 2), std::invalid_argument);
    CHECK_THROWS_AS(rcx::make_torus(0.5f, 1.0f), std::invalid_argument);
}

TEST_CASE("a UV sphere mesh has outward windings, its vertices on the sphere and 2 segments (rings - 1) triangles") {
    const rcx::Mesh m = rcx::make_sphere(2.0f, 8, 4);
    check_mesh(m);
    CHECK(m.triangles.size() == 48u);          // 8 + 8 at the poles, 2 x 8 x 2 between: 2 x 8 x 3
    CHECK(m.positions.size() == 2u + 3u * 8u); // two poles, three rings of 8
    for (const glm::vec3& p : m.positions) CHECK(glm::length(p) == doctest::Approx(2.0f).epsilon(1e-5));
    const rcx::Bounds b = rcx::mesh_bounds(m);
    CHECK(b.max.y == doctest::Approx(2.0f)); // the poles on the y axis
    CHECK(b.min.y == doctest::Approx(-2.0f));
    CHECK(b.max.x == doctest::Approx(2.0f)); // a vertex of the equator at +x
    CHECK(rcx::make_sphere(1.0f, 3, 2).triangles.size() == 6u);
    CHECK_THROWS_AS(rcx::make_sphere(1.0f, 2, 4), std::invalid_argument);
    CHECK_THROWS_AS(rcx::make_sphere(1.0f, 8, 1), std::invalid_argument);
    CHECK_THROWS_AS(rcx::make_sphere(0.0f, 8, 4), std::invalid_argument);
}

TEST_CASE("tessellating a scene's moving spheres makes them meshes that move the same way, the rest stays") {
    rcx::Scene s;
    s.meshes.push_back(rcx::checkerboard_floor());
    rcx::Material red;
    red.diffuse = {1.0f, 0.0f, 0.0f};
    rcx::Material mirror;
    mirror.reflectivity = 0.7f;
    mirror.cached = true;
    s.spheres.push_back({{0.0f, 0.0f, 0.0f}, 1.0f, red});     // stands still
    s.spheres.push_back({{3.0f, 0.5f, 0.0f}, 0.5f, mirror});  // moves
    s.spheres.push_back({{-3.0f, 0.25f, 1.0f}, 0.25f, red});  // moves
    rcx::Motion a;
    a.index = 1;
    a.circle_radius = 1.0f;
    a.degrees_per_frame = 90.0f;
    rcx::Motion b = a;
    b.index = 2;
    b.bob = 0.5f;
    s.motions = {a, b};

    const rcx::Scene t = rcx::tessellate_moving_spheres(s, 4);
    REQUIRE(t.spheres.size() == 1u);
    CHECK(t.spheres[0].centre == s.spheres[0].centre);
    REQUIRE(t.meshes.size() == 3u);
    CHECK(t.meshes[0].positions == s.meshes[0].positions);
    CHECK(rcx::sphere_mesh_triangles(4) == 48u); // 2L segments, L rings: 2 (2L)(L - 1)
    for (std::size_t m = 1; m < 3; ++m) {
        CAPTURE(m);
        const rcx::Sphere& from = s.spheres[m];
        CHECK(t.meshes[m].triangles.size() == 48u);
        CHECK(t.meshes[m].material.cached == from.material.cached);
        CHECK(t.meshes[m].material.diffuse == from.material.diffuse);
        CHECK(t.meshes[m].material.reflectivity == from.material.reflectivity);
        for (const glm::vec3& p : t.meshes[m].positions)
            CHECK(glm::length(p - from.centre) == doctest::Approx(from.radius).epsilon(1e-5));
        check_mesh(t.meshes[m]);
    }
    REQUIRE(t.motions.size() == 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        CHECK(t.motions[i].kind == rcx::Motion::Kind::mesh);
        CHECK(t.motions[i].index == i + 1);
    }
    // Frame 2: a half turn of a circle of radius 1 from its +X point: 2 along -x; b also at the top of its bob.
    const rcx::Scene later = t.at_frame(2);
    CHECK(later.meshes[1].positions[0].x == doctest::Approx(t.meshes[1].positions[0].x - 2.0f));
    CHECK(later.meshes[2].positions[0].y == doctest::Approx(t.meshes[2].positions[0].y + 0.5f));
    CHECK(later.spheres[0].centre == s.spheres[0].centre);
    CHECK_THROWS_AS(rcx::tessellate_moving_spheres(s, 1), std::invalid_argument);

    if (!std::filesystem::exists(wuson)) return; // dynamic-N needs assimp-testmodels
    const rcx::Scene dynamic = rcx::tessellate_moving_spheres(rcx::make_scene("dynamic-8"), 8);
    std::size_t triangles = 0;
    for (const rcx::Mesh& m : dynamic.meshes) triangles += m.triangles.size();
    CHECK(dynamic.spheres.size() == 4u);                   // the static mirrors
    CHECK(triangles == 2u + 3732u + 8u * 4u * 8u * 7u);     // floor, Wuson, 8 spheres of 4 L (L - 1)
}

namespace {
// A path in the temporary folder for `name`, unique to this process, so that test runs in parallel (ctest
// -j, other checkouts on the machine) never write each other's files.
std::string scratch_path(const std::string& name) {
    return (std::filesystem::temp_directory_path() / (std::to_string(::getpid()) + "-" + name)).string();
}

} // namespace

TEST_CASE("load_mesh reads the Wuson smooth and names the path when it cannot read a file") {
    CHECK_THROWS_WITH_AS(rcx::load_mesh("/no/such/mesh.ply"), doctest::Contains("/no/such/mesh.ply"), std::runtime_error);
    const std::string not_a_mesh = scratch_path("raycache-not-a-mesh.ply");
    {
        std::FILE* f = std::fopen(not_a_mesh.c_str(), "w");
        REQUIRE(f);
        std::fputs("this is not a mesh\n", f);
        std::fclose(f);
    }
    CHECK_THROWS_WITH_AS(rcx::load_mesh(not_a_mesh), doctest::Contains(not_a_mesh.c_str()), std::runtime_error);
    std::filesystem::remove(not_a_mesh);
    if (!std::filesystem::exists(wuson)) return; // assimp-testmodels not installed
    rcx::Mesh m = rcx::load_mesh(wuson);
    CHECK(m.triangles.size() == 3732);
    CHECK(m.positions.size() < 3 * m.triangles.size()); // identical vertices joined
    rcx::fit_mesh(m, {0.0f, 0.0f, 0.0f}, 2.0f);
    const rcx::Bounds b = rcx::mesh_bounds(m);
    const glm::vec3 size = b.max - b.min;
    CHECK(std::max(size.x, std::max(size.y, size.z)) == doctest::Approx(2.0f).epsilon(1e-4));
    for (const glm::vec3& n : m.normals) CHECK(glm::length(n) == doctest::Approx(1.0f).epsilon(1e-4));
}

TEST_CASE("a mesh that cannot be fitted is called degenerate or too large, by its name") {
    rcx::Mesh point;
    point.name = "--mesh point.obj";
    point.positions = {glm::vec3(1.0f), glm::vec3(1.0f), glm::vec3(1.0f)};
    point.triangles = {glm::uvec3(0, 1, 2)};
    CHECK_THROWS_WITH_AS(rcx::fit_mesh(point, glm::vec3(0.0f), 2.0f), doctest::Contains("mesh '--mesh point.obj' is empty or degenerate"),
                         std::invalid_argument);
    rcx::Mesh huge = point;
    huge.name = "--mesh huge.obj";
    huge.positions = {glm::vec3(-3e38f), glm::vec3(3e38f, -3e38f, 0.0f), glm::vec3(3e38f)}; // extent 6e38: past a float
    CHECK_THROWS_WITH_AS(rcx::fit_mesh(huge, glm::vec3(0.0f), 2.0f), doctest::Contains("mesh '--mesh huge.obj' is too large"),
                         std::invalid_argument);
}

namespace {

// The first `fraction` of `source`'s bytes, written to a file in the temporary folder; its path.
std::string truncated_copy(const std::string& source, double fraction, const std::string& name) {
    std::FILE* in = std::fopen(source.c_str(), "rb");
    REQUIRE(in);
    std::string bytes;
    char buffer[65536];
    for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, in)) > 0;) bytes.append(buffer, n);
    std::fclose(in);
    const std::string path = scratch_path(name);
    std::FILE* out = std::fopen(path.c_str(), "wb");
    REQUIRE(out);
    std::fwrite(bytes.data(), 1, static_cast<std::size_t>(fraction * static_cast<double>(bytes.size())), out);
    std::fclose(out);
    return path;
}

} // namespace

TEST_CASE("load_mesh refuses a PLY file truncated anywhere, instead of aborting or reading a partial mesh") {
    const std::string cube = "/usr/share/assimp/models/PLY/cube_binary.ply";
    if (!std::filesystem::exists(wuson) || !std::filesystem::exists(cube)) return; // assimp-testmodels not installed
    // Wuson.ply is ASCII: 11184 vertices (the first 92% of the file), then 3732 faces. Assimp used to
    // abort (an assertion in its triangulation) on 10% to 90%, and at 99% repeat the last face to make up
    // the declared 3732.
    for (double fraction : {0.0005, 0.1, 0.3, 0.5, 0.7, 0.9, 0.95, 0.99, 0.999}) {
        CAPTURE(fraction);
        const std::string path = truncated_copy(wuson, fraction, "raycache-truncated-wuson.ply");
        CHECK_THROWS_WITH_AS(rcx::load_mesh(path), doctest::Contains(path.c_str()), std::runtime_error);
        if (fraction > 0.001) // past the header: it says what is missing
            CHECK_THROWS_WITH_AS(rcx::load_mesh(path), doctest::Contains("the file ends early"), std::runtime_error);
        std::filesystem::remove(path);
    }
    // Binary: 8 vertices of 12 bytes, then 12 faces of 13 bytes.
    for (double fraction : {0.5, 0.8, 0.99}) {
        CAPTURE(fraction);
        const std::string path = truncated_copy(cube, fraction, "raycache-truncated-cube.ply");
        CHECK_THROWS_WITH_AS(rcx::load_mesh(path), doctest::Contains("the file ends early"), std::runtime_error);
        std::filesystem::remove(path);
    }
    CHECK(rcx::load_mesh(cube).triangles.size() == 12); // whole, both read
    CHECK(rcx::load_mesh(wuson).triangles.size() == 3732);
}

TEST_CASE("load_mesh says a folder is a directory, not that there is no such file") {
    const std::string folder = std::filesystem::temp_directory_path().string();
    CHECK_THROWS_WITH_AS(rcx::load_mesh(folder), doctest::Contains("is a directory"), std::runtime_error);
    CHECK_THROWS_WITH_AS(rcx::load_mesh("/dev/null"), doctest::Contains("not a regular file"), std::runtime_error);
    CHECK_THROWS_WITH_AS(rcx::load_mesh("/no/such/mesh.ply"), doctest::Contains("no such file"), std::runtime_error);
}

TEST_CASE("a scene's hash for cache files follows what cached colours depend on, not the camera") {
    const rcx::Scene scene = rcx::make_scene("behind-4");
    const std::uint64_t hash = rcx::scene_hash(scene);
    CHECK(rcx::scene_hash(rcx::make_scene("behind-4")) == hash);
    CHECK(rcx::scene_hash(rcx::make_scene("behind-8")) != hash);
    rcx::Scene changed = scene;
    changed.camera.eye.x += 1.0f;
    changed.path.frames += 5;
    CHECK(rcx::scene_hash(changed) == hash);
    changed = scene;
    changed.spheres.back().centre.y = std::nextafter(changed.spheres.back().centre.y, 100.0f);
    CHECK(rcx::scene_hash(changed) != hash);
    changed = scene;
    changed.spheres.front().material.reflectivity *= 0.5f;
    CHECK(rcx::scene_hash(changed) != hash);
    changed = scene;
    changed.meshes.front().positions.front().x += 1.0f;
    CHECK(rcx::scene_hash(changed) != hash);
    changed = scene;
    changed.light.intensity *= 2.0f;
    CHECK(rcx::scene_hash(changed) != hash);
    changed = scene;
    changed.max_depth = 2;
    CHECK(rcx::scene_hash(changed) != hash);
}
