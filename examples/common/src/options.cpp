// What the shared options mean: the cache modes and invalidation policies by name, and the scene and
// camera path the options ask for. Parsing the command line is rcx/command_line.hpp's job.
#include "rcx/options.hpp"

#include <stdexcept>
#include <string>

namespace rcx {

const char* to_string(CacheMode mode) {
    switch (mode) {
    case CacheMode::off: return "off";
    case CacheMode::cct: return "cct";
    case CacheMode::cdct: return "cdct";
    case CacheMode::ceiling: return "ceiling";
    }
    return "?";
}

CacheMode parse_cache_mode(const std::string& text) {
    if (text == "off") return CacheMode::off;
    if (text == "cct") return CacheMode::cct;
    if (text == "cdct") return CacheMode::cdct;
    if (text == "ceiling") return CacheMode::ceiling;
    throw UsageError("--cache: unknown mode '" + text + "'; use off, cct, cdct or ceiling");
}

const char* to_string(InvalidationPolicy policy) {
    switch (policy) {
    case InvalidationPolicy::none: return "none";
    case InvalidationPolicy::all: return "all";
    case InvalidationPolicy::exact: return "exact";
    }
    return "?";
}

InvalidationPolicy parse_invalidation(const std::string& text) {
    if (text == "none") return InvalidationPolicy::none;
    if (text == "all") return InvalidationPolicy::all;
    if (text == "exact") return InvalidationPolicy::exact;
    throw UsageError("--invalidate: unknown policy '" + text + "'; use none, all or exact");
}

SceneParams scene_params(const Options& options) {
    SceneParams p;
    if (!options.mesh.empty()) p.mesh_path = options.mesh;
    return p;
}

void apply_options(Scene& scene, const Options& options) {
    if (options.frames) scene.path.frames = *options.frames;
    if (options.step_degrees) scene.path.step_degrees = *options.step_degrees;
    if (options.path) scene.path.kind = *options.path;
    if (options.depth) scene.max_depth = *options.depth;
    scene.light.samples = options.light_samples;
    scene.light.radius = options.light_samples > 1 ? options.light_radius : 0.0f;
}

Scene scene_from_options(const Options& options) {
    Scene scene = make_scene(options.scene, scene_params(options));
    apply_options(scene, options);
    ensure_writable_directory(options.out);
    // A --save-cache folder that cannot take the file fails now, not after the last frame.
    if (!options.save_cache.empty()) {
        try {
            ensure_writable_folder_of(options.save_cache);
        } catch (const std::exception& e) {
            throw std::runtime_error(std::string("--save-cache: ") + e.what());
        }
    }
    return scene;
}

} // namespace rcx
