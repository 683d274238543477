// Procedural meshes and Assimp loading.
#include "rcx/meshes.hpp"

#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>

#ifndef RCX_HAVE_ASSIMP
#define RCX_HAVE_ASSIMP 1
#endif
#if RCX_HAVE_ASSIMP
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#endif

namespace rcx {

namespace {

constexpr float two_pi = 6.28318530717958647692f;

void check_segments(const char* what, int segments) {
    if (segments < 3)
        throw std::invalid_argument(std::string(what) + ": segments must be >= 3, got " + std::to_string(segments));
}

unsigned add_vertex(Mesh& m, const glm::vec3& p, const glm::vec3& n) {
    m.positions.push_back(p);
    m.normals.push_back(glm::normalize(n));
    return static_cast<unsigned>(m.positions.size() - 1);
}

// Adds a triangle wound counter-clockwise seen from the side its vertex normals point to.
void add_triangle(Mesh& m, unsigned a, unsigned b, unsigned c) {
    const glm::vec3 face = glm::cross(m.positions[b] - m.positions[a], m.positions[c] - m.positions[a]);
    const glm::vec3 n = m.normals[a] + m.normals[b] + m.normals[c];
    if (glm::dot(face, n) < 0.0f) std::swap(b, c);
    m.triangles.emplace_back(a, b, c);
}

glm::vec3 radial(float angle) { return {std::cos(angle), 0.0f, std::sin(angle)}; }

// A flat disc of `segments` triangles at height y facing `normal_y` (+1 up, -1 down).
void add_cap(Mesh& m, float radius, float y, float normal_y, int segments) {
    const glm::vec3 n(0.0f, normal_y, 0.0f);
    const unsigned centre = add_vertex(m, {0.0f, y, 0.0f}, n);
    const unsigned first = static_cast<unsigned>(m.positions.size());
    for (int i = 0; i < segments; ++i)
        add_vertex(m, radius * radial(two_pi * static_cast<float>(i) / static_cast<float>(segments)) + glm::vec3(0.0f, y, 0.0f), n);
    for (int i = 0; i < segments; ++i)
        add_triangle(m, centre, first + static_cast<unsigned>(i), first + static_cast<unsigned>((i + 1) % segments));
}

} // namespace

Mesh make_cone(float radius, float height, int segments) {
    check_segments("make_cone", segments);
    Mesh m;
    m.name = "cone";
    // Side: one base vertex per segment edge, one apex vertex per segment (its normal at the segment's
    // middle angle, so the apex is not a single vertex with an undefined normal).
    const unsigned base0 = static_cast<unsigned>(m.positions.size());
    for (int i = 0; i < segments; ++i) {
        const float a = two_pi * static_cast<float>(i) / static_cast<float>(segments);
        add_vertex(m, radius * radial(a), height * radial(a) + glm::vec3(0.0f, radius, 0.0f));
    }
    for (int i = 0; i < segments; ++i) {
        const float a = two_pi * (static_cast<float>(i) + 0.5f) / static_cast<float>(segments);
        const unsigned apex = add_vertex(m, {0.0f, height, 0.0f}, height * radial(a) + glm::vec3(0.0f, radius, 0.0f));
        add_triangle(m, base0 + static_cast<unsigned>(i), base0 + static_cast<unsigned>((i + 1) % segments), apex);
    }
    add_cap(m, radius, 0.0f, -1.0f, segments);
    return m;
}

Mesh make_cylinder(float radius, float height, int segments) {
    check_segments("make_cylinder", segments);
    Mesh m;
    m.name = "cylinder";
    const unsigned first = static_cast<unsigned>(m.positions.size());
    for (int i = 0; i < segments; ++i) {
        const glm::vec3 n = radial(two_pi * static_cast<float>(i) / static_cast<float>(segments));
        add_vertex(m, radius * n, n);                                    // bottom ring: first + 2i
        add_vertex(m, radius * n + glm::vec3(0.0f, height, 0.0f), n);    // top ring:    first + 2i + 1
    }
    for (int i = 0; i < segments; ++i) {
        const unsigned b0 = first + 2u * static_cast<unsigned>(i), t0 = b0 + 1;
        const unsigned b1 = first + 2u * static_cast<unsigned>((i + 1) % segments), t1 = b1 + 1;
        add_triangle(m, b0, b1, t1);
        add_triangle(m, b0, t1, t0);
    }
    add_cap(m, radius, 0.0f, -1.0f, segments);
    add_cap(m, radius, height, 1.0f, segments);
    return m;
}

Mesh make_torus(float major, float minor, int major_segments, int minor_segments) {
    check_segments("make_torus", major_segments);
    check_segments("make_torus", minor_segments);
    if (!(minor > 0.0f) || !(major > minor))
        throw std::invalid_argument("make_torus: need 0 < minor < major, got major " + std::to_string(major) +
                                    ", minor " + std::to_string(minor));
    Mesh m;
    m.name = "torus";
    for (int i = 0; i < major_segments; ++i) {
        const glm::vec3 out = radial(two_pi * static_cast<float>(i) / static_cast<float>(major_segments));
        for (int j = 0; j < minor_segments; ++j) {
            const float v = two_pi * static_cast<float>(j) / static_cast<float>(minor_segments);
            const glm::vec3 n = std::cos(v) * out + glm::vec3(0.0f, std::sin(v), 0.0f);
            add_vertex(m, major * out + minor * n, n);
        }
    }
    auto index = [&](int i, int j) {
        return static_cast<unsigned>((i % major_segments) * minor_segments + (j % minor_segments));
    };
    for (int i = 0; i < major_segments; ++i)
        for (int j = 0; j < minor_segments; ++j) {
            add_triangle(m, index(i, j), index(i + 1, j), index(i + 1, j + 1));
            add_triangle(m, index(i, j), index(i + 1, j + 1), index(i, j + 1));
        }
    return m;
}

Mesh load_mesh(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw std::runtime_error("cannot read mesh '" + path + "': no such file");
#if RCX_HAVE_ASSIMP
    Assimp::Importer importer;
    // Drop the file's normals, texture coordinates and colours so that vertices shared by faces join
    // and the normals come out smooth (many files, the Wuson among them, store one normal per face).
    importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_NORMALS | aiComponent_TEXCOORDS |
                                                            aiComponent_COLORS | aiComponent_TANGENTS_AND_BITANGENTS);
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    const aiScene* scene = importer.ReadFile(
        path, aiProcess_RemoveComponent | aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                  aiProcess_GenSmoothNormals | aiProcess_PreTransformVertices | aiProcess_SortByPType);
    if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
        throw std::runtime_error("cannot read mesh '" + path + "': " + importer.GetErrorString());
    Mesh out;
    out.name = std::filesystem::path(path).stem().string();
    for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
        const aiMesh* in = scene->mMeshes[mi];
        if (!(in->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) || !in->HasNormals()) continue;
        const unsigned base = static_cast<unsigned>(out.positions.size());
        for (unsigned v = 0; v < in->mNumVertices; ++v) {
            const aiVector3D& p = in->mVertices[v];
            const aiVector3D& n = in->mNormals[v];
            out.positions.emplace_back(p.x, p.y, p.z);
            glm::vec3 normal(n.x, n.y, n.z);
            const float len = glm::length(normal);
            out.normals.push_back(len > 0.0f && std::isfinite(len) ? normal / len : glm::vec3(0.0f, 1.0f, 0.0f));
        }
        for (unsigned f = 0; f < in->mNumFaces; ++f) {
            const aiFace& face = in->mFaces[f];
            if (face.mNumIndices != 3) continue;
            out.triangles.emplace_back(base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]);
        }
    }
    if (out.triangles.empty()) throw std::runtime_error("cannot read mesh '" + path + "': it holds no triangles");
    return out;
#else
    throw std::runtime_error("cannot read mesh '" + path + "': RayCache examples were built without Assimp "
                             "(install libassimp-dev and reconfigure)");
#endif
}

Bounds mesh_bounds(const Mesh& mesh) {
    if (mesh.positions.empty()) return {};
    Bounds b{glm::vec3(std::numeric_limits<float>::max()), glm::vec3(-std::numeric_limits<float>::max())};
    for (const glm::vec3& p : mesh.positions) {
        b.min = glm::min(b.min, p);
        b.max = glm::max(b.max, p);
    }
    return b;
}

void fit_mesh(Mesh& mesh, const glm::vec3& centre, float size) {
    const Bounds b = mesh_bounds(mesh);
    const glm::vec3 extent = b.max - b.min;
    const float largest = std::max(extent.x, std::max(extent.y, extent.z));
    if (mesh.positions.empty() || !(largest > 0.0f) || !std::isfinite(largest))
        throw std::invalid_argument("fit_mesh: mesh '" + mesh.name + "' is empty or degenerate");
    const glm::vec3 middle = 0.5f * (b.min + b.max);
    const float scale = size / largest;
    for (glm::vec3& p : mesh.positions) p = centre + (p - middle) * scale;
}

void rotate_mesh(Mesh& mesh, const glm::vec3& axis, float degrees) {
    const glm::mat3 r(glm::rotate(glm::mat4(1.0f), glm::radians(degrees), glm::normalize(axis)));
    for (glm::vec3& p : mesh.positions) p = r * p;
    for (glm::vec3& n : mesh.normals) n = glm::normalize(r * n);
}

void translate_mesh(Mesh& mesh, const glm::vec3& offset) {
    for (glm::vec3& p : mesh.positions) p += offset;
}

} // namespace rcx
