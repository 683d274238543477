// The Embree Whitted tracer core; see tracer.hpp.
#include "tracer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

#include <tbb/blocked_range.h>
#include <atomic>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <raycache/embree/scene_cache.hpp>

#include "rcx/meshes.hpp"

namespace rcx::embree {

namespace {

constexpr int tile_size = 8;
constexpr float infinity = std::numeric_limits<float>::infinity();

// What an Embree geometry id stands for.
struct ObjectRef {
    bool is_sphere = true;
    std::size_t index = 0; // into scene.spheres or scene.meshes
};

void embree_error(void* user, RTCError code, const char* message) {
    auto* last = static_cast<std::string*>(user);
    if (last->empty()) *last = "Embree error " + std::to_string(static_cast<int>(code)) + ": " + (message ? message : "");
}

// Ray offset from a surface: relative to the size of the coordinates, so far-away floor points work too.
float surface_epsilon(const glm::vec3& p) {
    const float m = std::max(std::abs(p.x), std::max(std::abs(p.y), std::abs(p.z)));
    return 1e-4f * std::max(1.0f, m);
}

// Schlick's approximation of the Fresnel reflectance from refractive index n1 into n2; cos_i = cos of the
// incidence angle, cos_t of the transmitted one (used when leaving the denser medium).
float schlick(float n1, float n2, float cos_i, float cos_t) {
    const float r0 = (n1 - n2) / (n1 + n2);
    const float c = n1 <= n2 ? cos_i : cos_t;
    const float x = 1.0f - c;
    return r0 * r0 + (1.0f - r0 * r0) * x * x * x * x * x;
}

} // namespace

struct Tracer::Impl {
    Scene scene;
    std::string error;
    RTCDevice device = nullptr;
    RTCScene rtc = nullptr;
    std::vector<ObjectRef> objects; // by Embree geometry id
    std::vector<float*> vertices;   // by Embree geometry id: its vertex buffer (moved objects are rewritten)

    Impl() = default;
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;
    // Here rather than in ~Tracer, so that a constructor that throws half-way releases them too.
    ~Impl() {
        if (rtc) rtcReleaseScene(rtc);
        if (device) rtcReleaseDevice(device);
    }

    // Throws when Embree reported an error, releasing `unattached` (a geometry not yet in the scene) first.
    void check(const char* what, RTCGeometry unattached = nullptr) const {
        const RTCError e = rtcGetDeviceError(device);
        if (error.empty() && e == RTC_ERROR_NONE) return;
        if (unattached) rtcReleaseGeometry(unattached);
        if (!error.empty()) throw std::runtime_error(std::string("Embree tracer: ") + what + ": " + error);
        throw std::runtime_error(std::string("Embree tracer: ") + what + ": Embree error " + std::to_string(static_cast<int>(e)));
    }

    void attach(RTCGeometry g, ObjectRef ref, float* vertex_buffer) {
        rtcCommitGeometry(g);
        const unsigned id = rtcAttachGeometry(rtc, g);
        rtcReleaseGeometry(g);
        if (objects.size() <= id) objects.resize(id + 1), vertices.resize(id + 1);
        objects[id] = ref;
        vertices[id] = vertex_buffer;
    }

    const Material& material(unsigned geom) const {
        const ObjectRef& r = objects[geom];
        return r.is_sphere ? scene.spheres[r.index].material : scene.meshes[r.index].material;
    }
};

namespace {

// One tile's worth of shading state: counters only, so tiles share nothing mutable but the caches.
struct Shader {
    const Tracer::Impl& t;
    CacheMode mode;
    raycache::embree::SceneCache* caches;
    FrameStats stats{};
    // What the path of the leaving ray being traced for a cache saw (null outside such a trace), and that
    // ray's depth: deeper rays are bounces after its first hit.
    raycache::PathRecord* record = nullptr;
    int record_depth = 0;
    // Whether the caches keep path records this frame (read once, between frames, by the frame's setup).
    bool records_kept = true;

    // The first hit along the ray, shaded; hits on geometry `pass_through` are skipped (pre-filling a
    // cube traces from inside its own object).
    raycache::TracedRay trace(const glm::vec3& origin, const glm::vec3& direction, int depth,
                              unsigned pass_through = RTC_INVALID_GEOMETRY_ID) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRayHit rh{};
        rh.ray.org_x = origin.x;
        rh.ray.org_y = origin.y;
        rh.ray.org_z = origin.z;
        rh.ray.dir_x = direction.x;
        rh.ray.dir_y = direction.y;
        rh.ray.dir_z = direction.z;
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = infinity;
        rh.ray.mask = 0xFFFFFFFFu; // Debian's Embree is built with ray masks: a zero mask hits nothing
        rh.ray.flags = 0;
        rh.ray.time = 0.0f;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(t.rtc, &context, &rh);
        ++stats.rays;
        for (int skipped = 0; skipped < 16 && rh.hit.geomID != RTC_INVALID_GEOMETRY_ID && rh.hit.geomID == pass_through; ++skipped) {
            rh.ray.tnear = rh.ray.tfar * (1.0f + 1e-6f) + 1e-4f;
            rh.ray.tfar = infinity;
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(t.rtc, &context, &rh);
            ++stats.rays;
        }
        if (record) {
            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
                if (depth > record_depth) record->escaped(direction); // a bounce from a hit point escaped
            } else {
                record->hit(raycache::embree::path_key({rh.hit.geomID, rh.hit.instID[0]}), origin + rh.ray.tfar * direction);
                record->chained |= depth > record_depth; // a segment from one hit point to another
            }
        }
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {t.scene.environment, infinity};
        return {shade(rh, origin, direction, depth), rh.ray.tfar};
    }

    bool occluded(const glm::vec3& origin, const glm::vec3& direction, float distance) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRay ray{};
        ray.org_x = origin.x;
        ray.org_y = origin.y;
        ray.org_z = origin.z;
        ray.dir_x = direction.x;
        ray.dir_y = direction.y;
        ray.dir_z = direction.z;
        ray.tnear = 0.0f;
        ray.tfar = distance;
        ray.mask = 0xFFFFFFFFu;
        ray.flags = 0;
        ray.time = 0.0f;
        rtcOccluded1(t.rtc, &context, &ray);
        ++stats.shadow_rays;
        if (record) record->lit = true;
        return ray.tfar < 0.0f; // Embree sets tfar to -inf on a hit
    }

    // The share of the light seen from `above` (a point lifted off the surface, facing normal nf), whose
    // centre lies `distance` away in unit direction l: 0 or 1 for a point light; for a disc light
    // (PointLight::samples > 1) the share of its sample points not occluded. The points are the same for
    // every shaded point (a Vogel spiral on the disc facing it): no noise, so an image differs from another
    // renderer's only where their rays differ, and soft shadows only make each traced ray costlier.
    float light_visible(const glm::vec3& above, const glm::vec3& nf, const glm::vec3& l, float distance, float eps) {
        const PointLight& light = t.scene.light;
        if (light.samples <= 1) return occluded(above, l, distance - eps) ? 0.0f : 1.0f;
        const glm::vec3 helper = std::abs(l.x) < 0.9f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
        const glm::vec3 u = glm::normalize(glm::cross(l, helper)), v = glm::cross(l, u);
        constexpr float golden_angle = 2.39996322972865332f;
        int seen = 0;
        for (int k = 0; k < light.samples; ++k) {
            const float r = light.radius * std::sqrt((static_cast<float>(k) + 0.5f) / static_cast<float>(light.samples));
            const float angle = golden_angle * static_cast<float>(k);
            const glm::vec3 to_point = light.position + r * (std::cos(angle) * u + std::sin(angle) * v) - above;
            const float length = glm::length(to_point);
            const glm::vec3 direction = to_point / length;
            if (glm::dot(nf, direction) > 0.0f && !occluded(above, direction, length - eps)) ++seen;
        }
        return static_cast<float>(seen) / static_cast<float>(light.samples);
    }

    // The colour brought back by the ray leaving object `geom` from `origin` in unit `direction`: the one
    // place where the cache plugs in.
    glm::vec3 leaving(unsigned geom, unsigned inst, const Material& m, const glm::vec3& origin,
                      const glm::vec3& direction, int depth) {
        // What tracing it cost, in rays (its own, its shadow rays, its bounces): resting cubes weigh it.
        auto trace_leaving = [&] {
            const std::uint64_t before = stats.rays + stats.shadow_rays;
            raycache::TracedRay traced = trace(origin, direction, depth + 1);
            traced.work = static_cast<std::uint32_t>(std::min<std::uint64_t>(stats.rays + stats.shadow_rays - before, UINT32_MAX));
            return traced;
        };
        if (!m.cached) return trace_leaving().color;
        ++stats.leaving_rays;
        switch (mode) {
        case CacheMode::off: return trace_leaving().color;
        case CacheMode::ceiling: return t.scene.environment; // any constant: the cost of no tracing at all
        case CacheMode::cct:
        case CacheMode::cdct:
            // Cubes that keep no path records (a scene that has not moved yet) need none built.
            if (!records_kept) return caches->leaving_ray(raycache::embree::ObjectId{geom, inst}, origin, direction, trace_leaving);
            // The recording form: the cache learns what the traced path saw (for exact invalidation), and
            // an enclosing cached path (`record`) learns where this cube answered it, if it did.
            return caches->leaving_ray(raycache::embree::ObjectId{geom, inst}, origin, direction, [&](raycache::PathRecord& path) {
                path.track_cached_reads(); // every leaving ray nested in it passes it as `enclosing`
                raycache::PathRecord* const outer = record;
                const int outer_depth = record_depth;
                record = &path;
                record_depth = depth + 1;
                const raycache::TracedRay traced = trace_leaving();
                record = outer;
                record_depth = outer_depth;
                if (outer) { // this ray is a bounce of an enclosing cached path: what it saw is part of that path
                    outer->merge(path);
                    if (std::isinf(traced.distance)) outer->escaped(direction); // from its hit point on this object
                    else outer->chained = true;
                }
                return traced;
            }, record);
        }
        return trace_leaving().color;
    }

    glm::vec3 shade(const RTCRayHit& rh, const glm::vec3& origin, const glm::vec3& d, int depth) {
        const Scene& scene = t.scene;
        const unsigned geom = rh.hit.geomID;
        const ObjectRef& ref = t.objects[geom];
        const Material& m = t.material(geom);
        const glm::vec3 p = origin + rh.ray.tfar * d;

        // Outward normals: geometric (which side of the surface we are on) and shading (lighting).
        glm::vec3 ng, ns;
        if (ref.is_sphere) {
            ng = ns = glm::normalize(p - scene.spheres[ref.index].centre);
        } else {
            const Mesh& mesh = scene.meshes[ref.index];
            const glm::uvec3 tri = mesh.triangles[rh.hit.primID];
            const float u = rh.hit.u, v = rh.hit.v;
            ns = glm::normalize((1.0f - u - v) * mesh.normals[tri.x] + u * mesh.normals[tri.y] + v * mesh.normals[tri.z]);
            ng = glm::cross(mesh.positions[tri.y] - mesh.positions[tri.x], mesh.positions[tri.z] - mesh.positions[tri.x]);
            ng = glm::normalize(glm::dot(ng, ns) < 0.0f ? -ng : ng); // trust the vertex normals' side
        }
        const bool inside = glm::dot(d, ng) > 0.0f; // the ray comes from the inside of the object
        const glm::vec3 nf = inside ? -ng : ng;     // geometric normal facing the ray
        glm::vec3 n = inside ? -ns : ns;            // shading normal facing the ray
        if (glm::dot(n, d) >= 0.0f) n = nf;         // interpolated normal turned away: fall back
        const float eps = surface_epsilon(p);
        const glm::vec3 above = p + eps * nf;       // origin of rays leaving on the ray's side
        const glm::vec3 below = p - eps * nf;       // origin of rays crossing the surface

        glm::vec3 base = m.diffuse;
        if (m.checker) {
            const float s = m.checker_scale > 0.0f ? m.checker_scale : 1.0f;
            const long cell = static_cast<long>(std::floor(p.x / s)) + static_cast<long>(std::floor(p.z / s));
            if (cell & 1) base = m.checker_color;
        }
        const float local = std::max(0.0f, 1.0f - m.reflectivity - m.transparency);

        glm::vec3 color(0.0f);
        if (!inside) {
            color += scene.ambient * local * base;
            const glm::vec3 to_light = scene.light.position - p;
            const float distance = glm::length(to_light);
            const glm::vec3 l = to_light / distance;
            const float n_dot_l = glm::dot(n, l);
            const float visible = n_dot_l > 0.0f && glm::dot(nf, l) > 0.0f ? light_visible(above, nf, l, distance, eps) : 0.0f;
            if (visible > 0.0f) { // times 1 for a point light: its pixels are those of a tracer without soft shadows
                color += scene.light.intensity * (local * n_dot_l * visible) * base;
                if (m.specular > 0.0f) {
                    const float r_dot_v = glm::dot(glm::reflect(-l, n), -d);
                    if (r_dot_v > 0.0f) color += scene.light.intensity * (m.specular * std::pow(r_dot_v, m.shininess) * visible);
                }
            }
        }
        if (depth >= scene.max_depth) return color;

        const unsigned inst = rh.hit.instID[0];
        const float cos_i = -glm::dot(d, n);
        const glm::vec3 mirrored = glm::normalize(d + 2.0f * cos_i * n);
        if (m.reflectivity > 0.0f && !inside) color += m.reflectivity * leaving(geom, inst, m, above, mirrored, depth);

        if (m.transparency > 0.0f) {
            const float n1 = inside ? m.ior : 1.0f, n2 = inside ? 1.0f : m.ior;
            const float eta = n1 / n2;
            const float sin2_t = eta * eta * (1.0f - cos_i * cos_i);
            glm::vec3 transmitted(0.0f);
            float fresnel = 1.0f; // total internal reflection
            if (sin2_t < 1.0f) {
                const float cos_t = std::sqrt(1.0f - sin2_t);
                fresnel = schlick(n1, n2, cos_i, cos_t);
                const glm::vec3 t_dir = glm::normalize(eta * d + (eta * cos_i - cos_t) * n);
                // Entering: an ordinary ray inside the object. Leaving: the ray that leaves the object.
                transmitted = inside ? leaving(geom, inst, m, below, t_dir, depth) : trace(below, t_dir, depth + 1).color;
            }
            glm::vec3 reflected(0.0f);
            if (fresnel > 0.0f)
                reflected = inside ? trace(above, mirrored, depth + 1).color // stays inside: not a leaving ray
                                   : leaving(geom, inst, m, above, mirrored, depth);
            color += m.transparency * (fresnel * reflected + (1.0f - fresnel) * transmitted);
        }
        return color;
    }
};

} // namespace

Tracer::Tracer(const Scene& scene) : impl_(std::make_unique<Impl>()) {
    Impl& t = *impl_;
    t.scene = scene;
    t.device = rtcNewDevice(nullptr);
    if (!t.device)
        throw std::runtime_error("Embree tracer: cannot create an Embree device (error " +
                                 std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
    rtcSetDeviceErrorFunction(t.device, embree_error, &t.error);
    t.rtc = rtcNewScene(t.device);

    for (std::size_t i = 0; i < t.scene.spheres.size(); ++i) {
        const Sphere& s = t.scene.spheres[i];
        RTCGeometry g = rtcNewGeometry(t.device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
        t.check("sphere vertex buffer", g);
        v[0] = s.centre.x;
        v[1] = s.centre.y;
        v[2] = s.centre.z;
        v[3] = s.radius;
        t.attach(g, {true, i}, v);
    }
    for (std::size_t i = 0; i < t.scene.meshes.size(); ++i) {
        const Mesh& m = t.scene.meshes[i];
        validate_mesh(m, "Embree tracer");
        RTCGeometry g = rtcNewGeometry(t.device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), m.positions.size()));
        auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(unsigned), m.triangles.size()));
        t.check("mesh buffers", g);
        for (std::size_t k = 0; k < m.positions.size(); ++k)
            for (int c = 0; c < 3; ++c) v[3 * k + static_cast<std::size_t>(c)] = m.positions[k][c];
        for (std::size_t k = 0; k < m.triangles.size(); ++k)
            for (int c = 0; c < 3; ++c) idx[3 * k + static_cast<std::size_t>(c)] = m.triangles[k][c];
        t.attach(g, {false, i}, v);
    }
    rtcCommitScene(t.rtc);
    t.check("building the scene");
}

Tracer::~Tracer() = default;

namespace {
// The sphere around a mesh: its box's centre, out to its farthest vertex.
raycache::BoundingSphere bounding_sphere(const Mesh& m) {
    glm::vec3 lo(infinity), hi(-infinity);
    for (const glm::vec3& p : m.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const glm::vec3 c = 0.5f * (lo + hi);
    float r2 = 0.0f;
    for (const glm::vec3& p : m.positions) r2 = std::max(r2, glm::dot(p - c, p - c));
    return {c, std::sqrt(r2) * 1.0001f};
}
} // namespace

raycache::embree::SceneChange Tracer::move_to(const Scene& next) {
    Impl& t = *impl_;
    const Scene& now = t.scene;
    if (next.spheres.size() != now.spheres.size() || next.meshes.size() != now.meshes.size())
        throw std::invalid_argument("Embree tracer: move_to needs the same objects in the same order (Scene::at_frame)");
    raycache::embree::SceneChange change;
    for (unsigned id = 0; id < t.objects.size(); ++id) {
        const ObjectRef& ref = t.objects[id];
        RTCGeometry g = rtcGetGeometry(t.rtc, id);
        raycache::BoundingSphere before, after;
        if (ref.is_sphere) {
            const Sphere &a = now.spheres[ref.index], &b = next.spheres[ref.index];
            if (a.centre == b.centre && a.radius == b.radius) continue;
            float* v = t.vertices[id];
            v[0] = b.centre.x, v[1] = b.centre.y, v[2] = b.centre.z, v[3] = b.radius;
            before = {a.centre, a.radius}, after = {b.centre, b.radius};
        } else {
            const Mesh &a = now.meshes[ref.index], &b = next.meshes[ref.index];
            if (a.positions == b.positions) continue;
            if (a.positions.size() != b.positions.size())
                throw std::invalid_argument("Embree tracer: move_to cannot change mesh '" + a.name + "''s vertex count");
            float* v = t.vertices[id];
            for (std::size_t k = 0; k < b.positions.size(); ++k)
                for (int c = 0; c < 3; ++c) v[3 * k + static_cast<std::size_t>(c)] = b.positions[k][c];
            before = bounding_sphere(a), after = bounding_sphere(b);
        }
        rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(g);
        change.moved.push_back({raycache::embree::ObjectId{id}, before, after, std::nullopt});
    }
    change.light_moved = next.light.position != now.light.position;
    change.lights.push_back(next.light.position);
    t.scene = next;
    if (!change.moved.empty()) rtcCommitScene(t.rtc); // the BVH over the moved objects' new places
    t.check("moving objects");
    return change;
}

const Scene& Tracer::scene() const noexcept { return impl_->scene; }
RTCScene Tracer::rtc_scene() const noexcept { return impl_->rtc; }

std::vector<unsigned> Tracer::cached_geometries() const {
    std::vector<unsigned> ids;
    for (unsigned id = 0; id < impl_->objects.size(); ++id)
        if (impl_->material(id).cached) ids.push_back(id);
    return ids;
}

void Tracer::attach_caches(raycache::embree::SceneCache& caches, int face_size) const {
    for (unsigned id : cached_geometries()) caches.attach(impl_->rtc, raycache::embree::ObjectId{id}, face_size);
}

raycache::TracedRay Tracer::trace_uncached(const glm::vec3& origin, const glm::vec3& direction, int depth) const {
    Shader shader{*impl_, CacheMode::off, nullptr};
    return shader.trace(origin, direction, depth);
}

std::size_t Tracer::prefill(raycache::embree::SceneCache& caches, int threads, double* milliseconds) const {
    struct Row {
        raycache::embree::ObjectId id;
        int face, row;
    };
    std::vector<Row> rows;
    for (const raycache::embree::ObjectId id : caches.objects())
        for (int face = 0; face < 6; ++face)
            for (int row = 0; row < caches.face_size(id); ++row) rows.push_back({id, face, row});
    std::atomic<std::size_t> stored{0};
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    const auto start = std::chrono::steady_clock::now();
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows.size()), [&](const tbb::blocked_range<std::size_t>& range) {
            // A ray leaving the object is a depth-1 ray; traced with the cache off, from the cube's centre
            // through the object itself.
            Shader shader{*impl_, CacheMode::off, nullptr};
            std::size_t count = 0;
            for (std::size_t i = range.begin(); i != range.end(); ++i)
                count += caches.prefill_row(rows[i].id, rows[i].face, rows[i].row, [&](glm::vec3 o, glm::vec3 d) {
                    return shader.trace(o, d, 1, rows[i].id.geom_id);
                });
            stored += count;
        });
    });
    if (milliseconds)
        *milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return stored.load();
}

Image Tracer::render(const Camera& camera, const RenderSettings& settings, FrameStats* stats) const {
    if (settings.width < 1 || settings.height < 1)
        throw std::invalid_argument("Embree tracer: image size must be at least 1x1, got " +
                                    std::to_string(settings.width) + "x" + std::to_string(settings.height));
    if (uses_caches(settings.mode) && !settings.caches)
        throw std::invalid_argument(std::string("Embree tracer: cache mode ") + to_string(settings.mode) +
                                    " needs a SceneCache");

    Image image(settings.width, settings.height);
    const CameraBasis basis = camera_basis(camera, settings.width, settings.height);
    const int tiles_x = (settings.width + tile_size - 1) / tile_size;
    const int tiles_y = (settings.height + tile_size - 1) / tile_size;
    std::vector<FrameStats> tile_stats(static_cast<std::size_t>(tiles_x) * static_cast<std::size_t>(tiles_y));

    const bool records_kept = settings.caches && settings.caches->keeps_path_records();
    // One pass over the pixels whose x and y are multiples of `stride` (1: every pixel), tile by tile, less
    // those whose x and y are multiples of `done` (a warm-up's, already final; 0: none).
    auto pass = [&](int stride, int done) {
        return [&, stride, done](const tbb::blocked_range<int>& range) {
            for (int tile = range.begin(); tile != range.end(); ++tile) {
                Shader shader{*impl_, settings.mode, settings.caches};
                shader.records_kept = records_kept;
                const int x0 = (tile % tiles_x) * tile_size, y0 = (tile / tiles_x) * tile_size;
                const int x1 = std::min(x0 + tile_size, settings.width), y1 = std::min(y0 + tile_size, settings.height);
                for (int y = y0; y < y1; ++y) {
                    if (y % stride) continue;
                    const bool row_done = done > 1 && y % done == 0;
                    for (int x = x0; x < x1; ++x)
                        if (x % stride == 0 && !(row_done && x % done == 0))
                            image.at(x, y) = shader.trace(basis.eye, primary_direction(basis, x, y), 0).color;
                }
                FrameStats& s = tile_stats[static_cast<std::size_t>(tile)];
                s.rays += shader.stats.rays;
                s.shadow_rays += shader.stats.shadow_rays;
                s.leaving_rays += shader.stats.leaving_rays;
            }
        };
    };

    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::task_arena::automatic);
    const auto start = std::chrono::steady_clock::now();
    const int tiles = tiles_x * tiles_y;
    const bool warm_up = settings.warm_up_stride > 1 && uses_caches(settings.mode);
    if (warm_up) {
        arena.execute([&] { tbb::parallel_for(tbb::blocked_range<int>(0, tiles), pass(settings.warm_up_stride, 0)); });
        end_frame(*settings.caches, settings.threads); // the warm-up's stores become visible to the full pass
    }
    // After a warm-up its pixels are final: tracing them again would only read back what they just stored.
    arena.execute([&] { tbb::parallel_for(tbb::blocked_range<int>(0, tiles), pass(1, warm_up ? settings.warm_up_stride : 0)); });
    const auto end = std::chrono::steady_clock::now();

    if (stats) {
        *stats = FrameStats{};
        for (const FrameStats& s : tile_stats) {
            stats->rays += s.rays;
            stats->shadow_rays += s.shadow_rays;
            stats->leaving_rays += s.leaving_rays;
        }
        stats->milliseconds = std::chrono::duration<double, std::milli>(end - start).count();
    }
    return image;
}

namespace {
// A SceneCache parallel_for (begin_frame, scene_changed) over TBB.
void tbb_for(std::size_t count, const std::function<void(std::size_t)>& f) {
    tbb::parallel_for(std::size_t{0}, count, [&](std::size_t i) { f(i); });
}
// SceneCache's call(parallel_for) on `threads` threads: TBB's own arena for every core (threads <= 0), so
// no arena of our own is started on each call; else an arena of that many.
template <class Call>
decltype(auto) on_threads(int threads, Call&& call) {
    if (threads <= 0) return call(tbb_for);
    tbb::task_arena arena(threads);
    return call([&arena](std::size_t count, const std::function<void(std::size_t)>& f) { arena.execute([&] { tbb_for(count, f); }); });
}
} // namespace

raycache::embree::SceneCacheStatistics end_frame(raycache::embree::SceneCache& caches, int threads) {
    return on_threads(threads, [&](auto&& parallel_for) { return caches.begin_frame(parallel_for); });
}

raycache::embree::InvalidationStatistics scene_changed(raycache::embree::SceneCache& caches, const raycache::embree::SceneChange& change,
                                                       raycache::embree::Invalidation policy, int threads) {
    return on_threads(threads, [&](auto&& parallel_for) { return caches.scene_changed(change, policy, parallel_for); });
}

} // namespace rcx::embree
