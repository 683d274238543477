// raycache_demo: the caching cube without a ray tracer. A mirror sphere sits in an analytic world (a
// checkerboard floor, three coloured balls, a sky); a camera orbits it, and each frame's reflected rays go
// through the CCT and the CDCT. Prints, per frame, how much of each cube is filled, how many rays it
// answered, and how far its answers are from tracing every ray.
//
// Usage: raycache_demo [face_size=128] [frames=16]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <optional>
#include <vector>

#include <raycache/raycache.hpp>

namespace {

struct Ball {
    glm::vec3 centre;
    float radius;
    glm::vec3 color;
};

const Ball balls[] = {
    {{2.5f, 0.0f, 0.0f}, 1.0f, {0.9f, 0.2f, 0.2f}},
    {{-1.5f, 0.0f, 2.0f}, 1.0f, {0.2f, 0.8f, 0.3f}},
    {{-1.0f, 0.5f, -2.5f}, 1.5f, {0.2f, 0.3f, 0.9f}},
};
const glm::vec3 mirror_centre(0.0f, 0.0f, 0.0f);
const float mirror_radius = 1.0f;
const float floor_height = -1.0f;

// Distance along unit d from o to a sphere, or a negative number when the ray misses it.
float hit_sphere(const glm::vec3& o, const glm::vec3& d, const glm::vec3& c, float r) {
    const glm::vec3 oc = o - c;
    const float b = glm::dot(oc, d);
    const float disc = b * b - (glm::dot(oc, oc) - r * r);
    if (disc < 0.0f) return -1.0f;
    const float s = std::sqrt(disc);
    return -b - s > 1e-4f ? -b - s : -b + s;
}

// The world seen along a ray that left the mirror: nearest ball, floor or sky (flat colours, no light).
raycache::TracedRay trace_world(const glm::vec3& o, const glm::vec3& d) {
    raycache::TracedRay nearest{glm::vec3(0.55f, 0.7f, 0.95f) * (0.6f + 0.4f * std::max(d.y, 0.0f))};
    for (const Ball& b : balls) {
        const float t = hit_sphere(o, d, b.centre, b.radius);
        if (t > 1e-4f && t < nearest.distance) nearest = {b.color, t};
    }
    if (d.y < 0.0f) {
        const float t = (floor_height - o.y) / d.y;
        if (t > 1e-4f && t < nearest.distance) {
            const glm::vec3 p = o + t * d;
            const bool dark = (static_cast<int>(std::floor(p.x)) + static_cast<int>(std::floor(p.z))) & 1;
            nearest = {dark ? glm::vec3(0.1f) : glm::vec3(0.9f), t};
        }
    }
    return nearest;
}

struct FrameError {
    double sum = 0.0;
    long rays = 0;
    void add(const glm::vec3& a, const glm::vec3& b) {
        sum += (std::abs(a.x - b.x) + std::abs(a.y - b.y) + std::abs(a.z - b.z)) / 3.0;
        ++rays;
    }
    double mean() const { return rays ? sum / rays : 0.0; }
};

int run(int face_size, int frames) {
    raycache::CctCube cct(face_size);
    raycache::CdctCube cdct(face_size);
    const raycache::CubeBounds bounds{mirror_centre, mirror_radius};
    const raycache::ReliefParameters relief{0.1f, 0.01f, 2048, 100.0f};
    const int width = 320, height = 240;

    std::printf("RayCache %s demo: one mirror sphere, %dx%d camera, %d frames orbiting 2 degrees a frame\n",
                raycache::version_string(), width, height, frames);
    std::printf("cube faces %d x %d: CCT %.2f MiB, CDCT %.2f MiB of texels\n\n", face_size, face_size,
                cct.texel_bytes() / 1048576.0, cdct.texel_bytes() / 1048576.0);
    std::printf("frame | mirror rays | CCT hits  filled  mean err | CDCT hits  filled  mean err  texels/lookup\n");
    for (int frame = 0; frame < frames; ++frame) {
        const float angle = glm::radians(2.0f * frame);
        const glm::vec3 eye(3.5f * std::sin(angle), 1.0f, 3.5f * std::cos(angle));
        const glm::vec3 forward = glm::normalize(mirror_centre - eye);
        const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0, 1, 0)));
        const glm::vec3 up = glm::cross(right, forward);
        FrameError cct_error, cdct_error;
        long texels_read = 0;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const float u = (2.0f * (x + 0.5f) / width - 1.0f) * 0.35f * width / height;
                const float v = (1.0f - 2.0f * (y + 0.5f) / height) * 0.35f;
                const glm::vec3 ray = glm::normalize(forward + u * right + v * up);
                const float t = hit_sphere(eye, ray, mirror_centre, mirror_radius);
                if (t <= 0.0f) continue;
                const glm::vec3 p = eye + t * ray;
                const glm::vec3 n = glm::normalize(p - mirror_centre);
                const glm::vec3 r = glm::reflect(ray, n);
                const raycache::TracedRay reference = trace_world(p, r);
                const glm::vec3 from_cct = raycache::cached_trace(cct, r, [&] { return reference.color; });
                int read = 0;
                const glm::vec3 from_cdct =
                    raycache::cdct_cached_trace(cdct, bounds, p, r, relief, [&] { return reference; }, &read);
                texels_read += read;
                cct_error.add(from_cct, reference.color);
                cdct_error.add(from_cdct, reference.color);
            }
        const raycache::CubeStatistics a = cct.begin_frame();
        const raycache::CubeStatistics b = cdct.begin_frame();
        std::printf("%5d | %11ld | %7.1f%%  %5.1f%%  %8.4f | %8.1f%%  %5.1f%%  %8.4f  %13.1f\n", frame,
                    static_cast<long>(a.lookups), 100.0 * a.hit_rate(), 100.0 * a.valid_fraction(), cct_error.mean(),
                    100.0 * b.hit_rate(), 100.0 * b.valid_fraction(), cdct_error.mean(),
                    b.lookups ? static_cast<double>(texels_read) / b.lookups : 0.0);
    }
    std::printf("\nhits: rays answered by the cube instead of traced (frame 0 is cold: every ray is traced).\n"
                "mean err: mean absolute colour difference from tracing every ray (0..1 scale).\n"
                "The CCT ignores where a ray starts (no parallax); the CDCT searches its depth for that.\n");
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    try {
        const int face_size = argc > 1 ? std::atoi(argv[1]) : 128;
        const int frames = argc > 2 ? std::atoi(argv[2]) : 16;
        if (frames < 1) {
            std::fprintf(stderr, "raycache_demo: frames must be at least 1\nusage: raycache_demo [face_size=128] [frames=16]\n");
            return 2;
        }
        return run(face_size, frames);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raycache_demo: %s\nusage: raycache_demo [face_size=128] [frames=16]\n", e.what());
        return 2;
    }
}
