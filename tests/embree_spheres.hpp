// Test helpers: an Embree sphere (RTC_GEOMETRY_TYPE_SPHERE_POINT, one point) attached to a scene, and a
// device with a scene that release themselves.
#pragma once

#include <embree3/rtcore.h>
#include <glm/glm.hpp>

// Attaches a sphere of radius r around c to `scene` (not committed) and returns its geometry id.
inline unsigned add_embree_sphere(RTCDevice device, RTCScene scene, glm::vec3 c, float r) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
    v[0] = c.x, v[1] = c.y, v[2] = c.z, v[3] = r;
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    return id;
}

// A device and a scene, released together: derive a test world from it, attach geometry, commit.
struct EmbreeScene {
    RTCDevice device = rtcNewDevice(nullptr);
    RTCScene scene = rtcNewScene(device);
    EmbreeScene() = default;
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;
    ~EmbreeScene() {
        rtcReleaseScene(scene);
        rtcReleaseDevice(device);
    }
};

// A mirror sphere of radius 1 at the origin (its cube: centre 0, half-size 1) and a small ball far off
// (radius 0.2 at (-6, 0, 0)) for tests to move.
struct MirrorAndBall : EmbreeScene {
    unsigned mirror = 0, ball = 0;
    MirrorAndBall() {
        mirror = add_embree_sphere(device, scene, {0, 0, 0}, 1.0f);
        ball = add_embree_sphere(device, scene, {-6, 0, 0}, 0.2f);
        rtcCommitScene(scene);
    }
};
