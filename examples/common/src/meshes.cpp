// Procedural meshes and Assimp loading.
#include "rcx/meshes.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

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

Mesh make_sphere(float radius, int segments, int rings) {
    check_segments("make_sphere", segments);
    if (rings < 2 || !(radius > 0.0f))
        throw std::invalid_argument("make_sphere: need radius > 0 and rings >= 2, got radius " + std::to_string(radius) +
                                    ", rings " + std::to_string(rings));
    Mesh m;
    m.name = "sphere";
    const glm::vec3 up(0.0f, 1.0f, 0.0f);
    const unsigned north = add_vertex(m, radius * up, up);
    // Ring k (1..rings-1) at polar angle pi k / rings; vertex (k, i) is ring_first + (k - 1) segments + i.
    const unsigned ring_first = static_cast<unsigned>(m.positions.size());
    for (int k = 1; k < rings; ++k) {
        const float polar = 0.5f * two_pi * static_cast<float>(k) / static_cast<float>(rings);
        for (int i = 0; i < segments; ++i) {
            const glm::vec3 n = std::sin(polar) * radial(two_pi * static_cast<float>(i) / static_cast<float>(segments)) +
                                std::cos(polar) * up;
            add_vertex(m, radius * n, n);
        }
    }
    const unsigned south = add_vertex(m, -radius * up, -up);
    auto at = [&](int k, int i) {
        return ring_first + static_cast<unsigned>((k - 1) * segments + (i % segments));
    };
    for (int i = 0; i < segments; ++i) {
        add_triangle(m, north, at(1, i), at(1, i + 1));
        for (int k = 1; k + 1 < rings; ++k) {
            add_triangle(m, at(k, i), at(k, i + 1), at(k + 1, i));
            add_triangle(m, at(k, i + 1), at(k + 1, i + 1), at(k + 1, i));
        }
        add_triangle(m, at(rings - 1, i), at(rings - 1, i + 1), south);
    }
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

namespace {

[[noreturn]] void cannot_read(const std::string& path, const std::string& why) {
    throw std::runtime_error("cannot read mesh '" + path + "': " + why);
}

// The file must exist, be a regular file and open for reading; the message says which it is not.
std::string read_whole_file(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status)) cannot_read(path, "no such file");
    if (fs::is_directory(status)) cannot_read(path, "it is a directory, not a mesh file");
    if (!fs::is_regular_file(status)) cannot_read(path, "it is not a regular file (a device, pipe or socket)");
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) cannot_read(path, std::strerror(errno));
    std::string bytes;
    char buffer[65536];
    for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) bytes.append(buffer, n);
    const bool failed = std::ferror(f) != 0;
    std::fclose(f);
    if (failed) cannot_read(path, "reading it failed");
    return bytes;
}

// --- PLY: every element the header declares must be in the file ---------------------------------
// Assimp's PLY reader does not notice a body that ends early: it fills the declared counts by repeating
// the last face or with empty faces (and then aborts in triangulation). So the body is walked here.

struct PlyProperty {
    int size = 0;       // bytes of a scalar, or of each list item
    int count_size = 0; // lists: bytes of the item count; 0 for a scalar
    bool count_signed = false;
};
struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

// Bytes of a PLY scalar type (and whether it is signed); 0 for an unknown type.
int ply_type_size(const std::string& type, bool* is_signed = nullptr) {
    static const struct { const char* name; int size; bool is_signed; } types[] = {
        {"char", 1, true},   {"int8", 1, true},     {"uchar", 1, false},  {"uint8", 1, false},
        {"short", 2, true},  {"int16", 2, true},    {"ushort", 2, false}, {"uint16", 2, false},
        {"int", 4, true},    {"int32", 4, true},    {"uint", 4, false},   {"uint32", 4, false},
        {"float", 4, true},  {"float32", 4, true},  {"double", 8, true},  {"float64", 8, true},
    };
    for (const auto& t : types)
        if (type == t.name) {
            if (is_signed) *is_signed = t.is_signed;
            return t.size;
        }
    return 0;
}

[[noreturn]] void ply_ends_early(const std::string& path, const PlyElement& e, std::uint64_t held) {
    cannot_read(path, "the file ends early (truncated?): its header declares " + std::to_string(e.count) + " '" + e.name +
                          "' elements, the file holds " + std::to_string(held));
}

// Throws when `bytes` is a PLY file whose body holds fewer elements than its header declares, or whose
// header or list counts are malformed. Files that are not PLY, or use types this walk does not know,
// are left to Assimp.
void check_ply_complete(const std::string& path, const std::string& bytes) {
    if (bytes.compare(0, 4, "ply\n") != 0 && bytes.compare(0, 5, "ply\r\n") != 0) return;
    const std::size_t end = bytes.find("end_header");
    if (end == std::string::npos) cannot_read(path, "the PLY header has no end_header line (truncated?)");
    std::size_t body = bytes.find('\n', end);
    if (body == std::string::npos) cannot_read(path, "the file ends after its PLY header (truncated?)");
    ++body;

    std::istringstream header(bytes.substr(0, end));
    std::string line, format;
    std::vector<PlyElement> elements;
    while (std::getline(header, line)) {
        std::istringstream words(line);
        std::string keyword;
        words >> keyword;
        if (keyword == "format") {
            words >> format;
        } else if (keyword == "element") {
            PlyElement e;
            if (!(words >> e.name >> e.count)) cannot_read(path, "malformed PLY header line '" + line + "'");
            elements.push_back(e);
        } else if (keyword == "property") {
            if (elements.empty()) cannot_read(path, "PLY property before any element: '" + line + "'");
            std::string type;
            words >> type;
            PlyProperty p;
            if (type == "list") {
                std::string count_type, item_type;
                words >> count_type >> item_type;
                p.count_size = ply_type_size(count_type, &p.count_signed);
                p.size = ply_type_size(item_type);
                if (p.count_size == 0 || p.size == 0) return; // types Assimp may know better
            } else {
                p.size = ply_type_size(type);
                if (p.size == 0) return;
            }
            elements.back().properties.push_back(p);
        }
    }

    const char* text = bytes.data();
    std::size_t at = body;
    if (format == "ascii") {
        // Whitespace-separated numbers; a list is its item count, then that many items.
        auto next_token = [&](std::string* token) {
            while (at < bytes.size() && std::isspace(static_cast<unsigned char>(text[at]))) ++at;
            if (at == bytes.size()) return false;
            const std::size_t start = at;
            while (at < bytes.size() && !std::isspace(static_cast<unsigned char>(text[at]))) ++at;
            if (token) token->assign(text + start, at - start);
            return true;
        };
        std::string token;
        for (const PlyElement& e : elements)
            for (std::uint64_t i = 0; i < e.count; ++i)
                for (const PlyProperty& p : e.properties) {
                    if (!next_token(p.count_size ? &token : nullptr)) ply_ends_early(path, e, i);
                    if (!p.count_size) continue;
                    char* stop = nullptr;
                    const long long items = std::strtoll(token.c_str(), &stop, 10);
                    if (*stop != '\0' || items < 0)
                        cannot_read(path, "'" + e.name + "' element " + std::to_string(i) + " has a bad list length '" + token + "'");
                    for (long long k = 0; k < items; ++k)
                        if (!next_token(nullptr)) ply_ends_early(path, e, i);
                }
    } else if (format == "binary_little_endian" || format == "binary_big_endian") {
        const bool little = format == "binary_little_endian";
        const std::uint64_t size = bytes.size();
        for (const PlyElement& e : elements) {
            bool has_list = false;
            std::uint64_t fixed = 0;
            for (const PlyProperty& p : e.properties) {
                has_list = has_list || p.count_size;
                fixed += static_cast<std::uint64_t>(p.size);
            }
            if (!has_list) { // every element the same size: no need to walk them
                const std::uint64_t held = fixed ? (size - at) / fixed : e.count;
                if (held < e.count) ply_ends_early(path, e, held);
                at += static_cast<std::size_t>(e.count * fixed);
                continue;
            }
            for (std::uint64_t i = 0; i < e.count; ++i)
                for (const PlyProperty& p : e.properties) {
                    if (!p.count_size) {
                        if (size - at < static_cast<std::uint64_t>(p.size)) ply_ends_early(path, e, i);
                        at += static_cast<std::size_t>(p.size);
                        continue;
                    }
                    if (size - at < static_cast<std::uint64_t>(p.count_size)) ply_ends_early(path, e, i);
                    std::uint64_t items = 0;
                    for (int k = 0; k < p.count_size; ++k) {
                        const std::uint64_t byte = static_cast<unsigned char>(text[at + static_cast<std::size_t>(little ? p.count_size - 1 - k : k)]);
                        items = items << 8 | byte;
                    }
                    if (p.count_signed && (items >> (8 * p.count_size - 1)) & 1u)
                        cannot_read(path, "'" + e.name + "' element " + std::to_string(i) + " has a negative list length");
                    at += static_cast<std::size_t>(p.count_size);
                    if ((size - at) / static_cast<std::uint64_t>(p.size) < items) ply_ends_early(path, e, i);
                    at += static_cast<std::size_t>(items * static_cast<std::uint64_t>(p.size));
                }
        }
    }
}

#if RCX_HAVE_ASSIMP
// What post-processing must not be given (Assimp's triangulation asserts on faces without indices):
// faces with no index or an index past the mesh's vertices, and vertices that are not finite.
void check_imported(const std::string& path, const aiScene& scene) {
    for (unsigned mi = 0; mi < scene.mNumMeshes; ++mi) {
        const aiMesh& mesh = *scene.mMeshes[mi];
        const std::string where = scene.mNumMeshes > 1 ? " of mesh " + std::to_string(mi) : std::string();
        for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
            const aiVector3D& p = mesh.mVertices[v];
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                cannot_read(path, "vertex " + std::to_string(v) + where + " is not a finite point");
        }
        for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
            const aiFace& face = mesh.mFaces[f];
            if (face.mNumIndices == 0 || !face.mIndices)
                cannot_read(path, "face " + std::to_string(f) + where + " has no vertices (the file is damaged or truncated)");
            for (unsigned k = 0; k < face.mNumIndices; ++k)
                if (face.mIndices[k] >= mesh.mNumVertices)
                    cannot_read(path, "face " + std::to_string(f) + where + " uses vertex " + std::to_string(face.mIndices[k]) +
                                          " of " + std::to_string(mesh.mNumVertices));
        }
    }
}
#endif

} // namespace

Mesh load_mesh(const std::string& path) {
    const std::string bytes = read_whole_file(path);
    check_ply_complete(path, bytes);
#if RCX_HAVE_ASSIMP
    Assimp::Importer importer;
    // Drop the file's normals, texture coordinates and colours so that vertices shared by faces join
    // and the normals come out smooth (many files, the Wuson among them, store one normal per face).
    importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_NORMALS | aiComponent_TEXCOORDS |
                                                            aiComponent_COLORS | aiComponent_TANGENTS_AND_BITANGENTS);
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    // Read and validate first, check what Assimp's checks let through, and only then post-process.
    const aiScene* raw = importer.ReadFile(path, aiProcess_ValidateDataStructure);
    if (!raw || (raw->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) cannot_read(path, importer.GetErrorString());
    check_imported(path, *raw);
    const aiScene* scene = importer.ApplyPostProcessing(
        aiProcess_RemoveComponent | aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_GenSmoothNormals |
        aiProcess_PreTransformVertices | aiProcess_SortByPType);
    if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) cannot_read(path, importer.GetErrorString());
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
    if (out.triangles.empty()) cannot_read(path, "it holds no triangles");
    return out;
#else
    cannot_read(path, "RayCache examples were built without Assimp (install libassimp-dev and reconfigure)");
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

void validate_mesh(const Mesh& m, const std::string& who) {
    if (m.normals.size() != m.positions.size())
        throw std::invalid_argument(who + ": mesh '" + m.name + "' needs one normal per vertex");
    for (const glm::uvec3& tri : m.triangles)
        if (tri.x >= m.positions.size() || tri.y >= m.positions.size() || tri.z >= m.positions.size())
            throw std::invalid_argument(who + ": mesh '" + m.name + "' has a vertex index out of range");
}

void fit_mesh(Mesh& mesh, const glm::vec3& centre, float size) {
    const Bounds b = mesh_bounds(mesh);
    const glm::vec3 extent = b.max - b.min;
    const float largest = std::max(extent.x, std::max(extent.y, extent.z));
    if (mesh.positions.empty() || !(largest > 0.0f))
        throw std::invalid_argument("fit_mesh: mesh '" + mesh.name + "' is empty or degenerate (all its vertices in one point)");
    if (!std::isfinite(largest))
        throw std::invalid_argument("fit_mesh: mesh '" + mesh.name + "' is too large: its extent overflows a float");
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
