// A scene's fingerprint for cache files; see rcx/scene_hash.hpp.
#include "rcx/scene_hash.hpp"

#include <string>
#include <vector>

#include <raycache/cache_file.hpp>

namespace rcx {

namespace {

// Feeds plain values to FNV-1a 64: floats by their bits, sizes before the sequences they count.
struct Hasher {
    std::uint64_t hash = raycache::fnv1a64_basis;

    template <class T>
    void add(const T& value) {
        hash = raycache::fnv1a64(&value, sizeof value, hash);
    }
    void add(const glm::vec3& v) {
        add(v.x), add(v.y), add(v.z);
    }
    void add(const glm::uvec3& v) {
        add(v.x), add(v.y), add(v.z);
    }
    template <class T>
    void add(const std::vector<T>& values) {
        add(static_cast<std::uint64_t>(values.size()));
        for (const T& v : values) add(v);
    }
    void add(const Material& m) {
        add(m.diffuse), add(m.specular), add(m.shininess), add(m.reflectivity), add(m.transparency), add(m.ior);
        add(static_cast<std::uint8_t>(m.checker)), add(m.checker_color), add(m.checker_scale);
        add(static_cast<std::uint8_t>(m.cached));
    }
};

} // namespace

std::uint64_t scene_hash(const Scene& scene) {
    Hasher h;
    h.add(static_cast<std::uint64_t>(scene.spheres.size()));
    for (const Sphere& s : scene.spheres) h.add(s.centre), h.add(s.radius), h.add(s.material);
    h.add(static_cast<std::uint64_t>(scene.meshes.size()));
    for (const Mesh& m : scene.meshes) h.add(m.positions), h.add(m.normals), h.add(m.triangles), h.add(m.material);
    h.add(scene.light.position), h.add(scene.light.intensity);
    if (scene.light.samples > 1) h.add(static_cast<std::uint64_t>(scene.light.samples)), h.add(scene.light.radius); // soft shadows shade otherwise
    h.add(scene.environment), h.add(scene.ambient), h.add(scene.max_depth);
    return h.hash;
}

} // namespace rcx
