// The Embree Whitted example's tracer core (examples/embree_whitted/tracer.hpp) with the cache off: every
// scene renders, pixels match hand-computed shading, and the thread count does not change a bit.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include "rcx/scene.hpp"
#include "tracer.hpp"

namespace {

rcx::embree::RenderSettings tiny(int w, int h, int threads = 0) {
    rcx::embree::RenderSettings s;
    s.width = w;
    s.height = h;
    s.mode = rcx::CacheMode::off;
    s.threads = threads;
    return s;
}

// One sphere of radius 1 at (0, 0, -5) seen from the origin down -Z; no floor; the light at (3, 4, 1);
// the centre pixel of an odd-sized image looks straight at the sphere's nearest point (0, 0, -4).
rcx::Scene one_sphere(const rcx::Material& m) {
    rcx::Scene s;
    s.name = "one-sphere";
    s.spheres.push_back(rcx::Sphere{{0.0f, 0.0f, -5.0f}, 1.0f, m});
    s.light.position = {3.0f, 4.0f, 1.0f};
    s.light.intensity = glm::vec3(0.9f, 0.8f, 0.7f);
    s.environment = {0.1f, 0.2f, 0.3f};
    s.ambient = 0.1f;
    s.camera.eye = {0.0f, 0.0f, 0.0f};
    s.camera.target = {0.0f, 0.0f, -1.0f};
    s.camera.fov_y_degrees = 40.0f;
    return s;
}

void check_close(const glm::vec3& got, const glm::vec3& want) {
    for (int c = 0; c < 3; ++c) CHECK(got[c] == doctest::Approx(want[c]).epsilon(1e-5));
}

} // namespace

TEST_CASE("a tiny render of every scene runs with the cache off") {
    for (const std::string& name : rcx::scene_names()) {
        CAPTURE(name);
        if ((name == "concave" || name.rfind("dynamic-", 0) == 0) && !std::filesystem::exists(rcx::SceneParams{}.mesh_path)) continue;
        const rcx::Scene scene = rcx::make_scene(name);
        const rcx::embree::Tracer tracer(scene);
        CHECK(tracer.cached_geometries().size() == static_cast<std::size_t>(scene.cached_object_count()));
        rcx::embree::FrameStats stats;
        const rcx::Image image = tracer.render(scene.camera_at(1), tiny(48, 48), &stats);
        REQUIRE(image.pixels.size() == 48u * 48u);
        bool finite = true, varied = false;
        for (const glm::vec3& p : image.pixels) {
            finite = finite && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && p.x >= 0 && p.y >= 0 && p.z >= 0;
            varied = varied || p != image.pixels[0];
        }
        CHECK(finite);
        CHECK(varied);
        CHECK(stats.rays > 48u * 48u); // primary rays and some secondary ones
        CHECK(stats.shadow_rays > 0);
        CHECK(stats.leaving_rays > 0);
    }
}

TEST_CASE("the centre pixel of a diffuse sphere is its analytic Lambert shade") {
    rcx::Material m;
    m.diffuse = {0.8f, 0.5f, 0.2f};
    const rcx::Scene scene = one_sphere(m);
    const rcx::embree::Tracer tracer(scene);
    rcx::embree::FrameStats stats;
    const rcx::Image image = tracer.render(scene.camera, tiny(49, 49), &stats);
    // Hit (0, 0, -4), normal (0, 0, 1), light direction (3, 4, 5) / sqrt(50): n.l = 5 / sqrt(50).
    const float n_dot_l = 5.0f / std::sqrt(50.0f);
    check_close(image.at(24, 24), scene.ambient * m.diffuse + n_dot_l * scene.light.intensity * m.diffuse);
    check_close(image.at(0, 0), scene.environment); // the corner ray misses the sphere
    CHECK(stats.rays == 49u * 49u);                  // a diffuse sphere spawns no secondary ray
}

TEST_CASE("a disc light's sample points see the share of its area an occluder's shadow leaves") {
    // The centre pixel shades (0, 0, -4) with normal (0, 0, 1); the light's centre lies L = sqrt(50) away in
    // l = (3, 4, 5) / L. A small sphere of radius rho centred on that line, D from the point, hides the
    // light's points within L tan(asin(rho / D)) of its centre, in the disc facing the point. With the disc
    // radius R, the visible share of its area is 1 - (r / R)^2: derived from the geometry alone, not from the
    // tracer's sample pattern, which must match it within about a sample of the N.
    rcx::Material m;
    m.diffuse = {0.8f, 0.5f, 0.2f};
    rcx::Scene scene = one_sphere(m);
    const glm::vec3 p(0.0f, 0.0f, -4.0f);
    const float L = std::sqrt(50.0f);
    const glm::vec3 l = (scene.light.position - p) / L;
    const double R = 1.0, r = 0.6, D = 3.0;
    const double rho = D * std::sin(std::atan(r / L)); // tan(asin(rho / D)) = r / L
    rcx::Material dark;
    dark.diffuse = glm::vec3(0.0f);
    scene.spheres.push_back(rcx::Sphere{p + static_cast<float>(D) * l, static_cast<float>(rho), dark});
    const float n_dot_l = 5.0f / L;
    auto visible_share = [&](int samples) {
        scene.light.samples = samples;
        scene.light.radius = static_cast<float>(R);
        const rcx::embree::Tracer tracer(scene);
        const glm::vec3 got = tracer.render(scene.camera, tiny(49, 49)).at(24, 24);
        return (got.x - scene.ambient * m.diffuse.x) / (n_dot_l * scene.light.intensity.x * m.diffuse.x);
    };
    const double area_share = 1.0 - (r / R) * (r / R); // 0.64
    for (int samples : {16, 64, 256}) {
        CAPTURE(samples);
        CHECK(std::abs(visible_share(samples) - area_share) <= 1.5 / samples + 1e-4);
    }
    // A point light at the disc's centre is hidden; more samples do not change an unoccluded pixel's shade.
    CHECK(visible_share(1) == doctest::Approx(0.0).epsilon(1e-6));
    scene.spheres.pop_back();
    CHECK(visible_share(64) == doctest::Approx(1.0).epsilon(1e-6));
}

TEST_CASE("a point light's pixels do not depend on the radius a disc light would have") {
    const rcx::Scene scene = rcx::make_scene("behind-4");
    rcx::Scene with_radius = scene;
    with_radius.light.radius = 2.0f; // samples stays 1: ignored
    const rcx::Image a = rcx::embree::Tracer(scene).render(scene.camera, tiny(40, 40));
    const rcx::Image b = rcx::embree::Tracer(with_radius).render(scene.camera, tiny(40, 40));
    CHECK(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(a.pixels[0])) == 0);
}

TEST_CASE("the centre pixel of a mirror sphere adds the environment seen straight back") {
    rcx::Material m;
    m.diffuse = {0.8f, 0.5f, 0.2f};
    m.reflectivity = 0.75f;
    m.cached = true; // with the cache off, cached objects are traced like any other
    const rcx::Scene scene = one_sphere(m);
    const rcx::embree::Tracer tracer(scene);
    const rcx::Image image = tracer.render(scene.camera, tiny(49, 49));
    const float n_dot_l = 5.0f / std::sqrt(50.0f);
    const glm::vec3 local = 0.25f * (scene.ambient * m.diffuse + n_dot_l * scene.light.intensity * m.diffuse);
    check_close(image.at(24, 24), local + 0.75f * scene.environment);
}

TEST_CASE("the centre pixel of a glass sphere sums the Fresnel series through it") {
    rcx::Material m;
    m.transparency = 1.0f;
    m.ior = 1.5f;
    m.specular = 0.0f;
    rcx::Scene scene = one_sphere(m);
    scene.max_depth = 5;
    const rcx::embree::Tracer tracer(scene);
    const rcx::Image image = tracer.render(scene.camera, tiny(49, 49));
    // Normal incidence: F = ((1.5 - 1) / (1.5 + 1))^2 = 0.04 on both faces; every ray that gets out sees
    // the environment E. A hit from inside at depth d < 5: (1 - F) E + F * (hit from inside at d + 1);
    // a hit at depth 5 spawns nothing. The primary hit (depth 0): F E + (1 - F) * (inside hit at depth 1).
    const float F = 0.04f;
    const glm::vec3 E = scene.environment;
    glm::vec3 inside(0.0f);
    for (int d = 5; d >= 1; --d) inside = d >= scene.max_depth ? glm::vec3(0.0f) : (1.0f - F) * E + F * inside;
    check_close(image.at(24, 24), F * E + (1.0f - F) * inside);
}

TEST_CASE("one and two threads render bit-identical images with the same ray counts") {
    for (const char* name : {"behind-4", "glass", "cone-cylinder"}) {
        CAPTURE(name);
        const rcx::Scene scene = rcx::make_scene(name);
        const rcx::embree::Tracer tracer(scene);
        rcx::embree::FrameStats one_stats, two_stats;
        const rcx::Image one = tracer.render(scene.camera_at(2), tiny(61, 37, 1), &one_stats);
        const rcx::Image two = tracer.render(scene.camera_at(2), tiny(61, 37, 2), &two_stats);
        CHECK(rcx::bit_identical(one, two));
        CHECK(one_stats.rays == two_stats.rays);
        CHECK(one_stats.shadow_rays == two_stats.shadow_rays);
    }
}

TEST_CASE("the ceiling mode traces no leaving ray, and cct/cdct without caches are refused") {
    const rcx::Scene scene = rcx::make_scene("behind-2");
    const rcx::embree::Tracer tracer(scene);
    rcx::embree::RenderSettings s = tiny(32, 32);
    rcx::embree::FrameStats off, ceiling;
    tracer.render(scene.camera, s, &off);
    s.mode = rcx::CacheMode::ceiling;
    tracer.render(scene.camera, s, &ceiling);
    CHECK(ceiling.rays < off.rays);
    CHECK(ceiling.leaving_rays > 0);
    s.mode = rcx::CacheMode::cct;
    CHECK_THROWS_AS(tracer.render(scene.camera, s), std::invalid_argument);
    s.mode = rcx::CacheMode::cdct;
    CHECK_THROWS_AS(tracer.render(scene.camera, s), std::invalid_argument);
    s.mode = rcx::CacheMode::off;
    s.width = 0;
    CHECK_THROWS_AS(tracer.render(scene.camera, s), std::invalid_argument);
}
