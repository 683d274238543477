// raycache/cdct_cache.hpp: one object's CDCT cache: its cube, where the cube sits, how it is searched, and
// the depth pyramid the relief walk skips empty space with, kept current by begin_frame().
//
//     raycache::CdctCache cache(256, raycache::CubeBounds{centre, half_size});
//     // per leaving ray, on any thread:
//     glm::vec3 c = cache.cached_trace(origin, direction, [&] { return trace(origin, direction); }); // TracedRay
//     // between frames, on one thread:
//     cache.begin_frame();
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <cstddef>
#include <memory>
#include <stdexcept>
#include <utility>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"
#include "raycache/cdct.hpp"
#include "raycache/depth_pyramid.hpp"
#include "raycache/memory_budget.hpp"

namespace raycache {

class CdctCache {
public:
    // An empty cube of face_size texels per edge around `bounds`, drawing its tiles on `budget` (may be null:
    // no limit). With use_pyramid and parameters.search == DepthSearch::relief, a DepthPyramid speeds the
    // relief walk up (6 N^2 x 1.33 bytes, outside the budget); the secant search needs none. Throws
    // std::invalid_argument for a face size outside 1..4096, bounds without a finite centre and a half-size
    // > 0, or parameters validate() refuses.
    CdctCache(int face_size, const CubeBounds& bounds, const ReliefParameters& parameters = {}, bool use_pyramid = true,
              std::shared_ptr<MemoryBudget> budget = nullptr)
        : CdctCache(std::make_unique<CdctCube>(face_size, std::move(budget)), bounds, parameters, use_pyramid) {}

    // Takes over `cube` as it is (a loaded or resampled one; its pyramid is built from its texels). Throws
    // as above, and for a null cube.
    CdctCache(std::unique_ptr<CdctCube> cube, const CubeBounds& bounds, const ReliefParameters& parameters = {},
              bool use_pyramid = true)
        : cube_(std::move(cube)), bounds_(bounds), parameters_(parameters) {
        if (!cube_) throw std::invalid_argument("RayCache: CdctCache needs a cube");
        if (!detail::is_usable(bounds_))
            throw std::invalid_argument("RayCache: CdctCache bounds need a finite centre and a half-size > 0");
        validate(parameters_);
        if (use_pyramid && parameters_.search == DepthSearch::relief) {
            pyramid_ = std::make_unique<DepthPyramid>(cube_->face_size());
            pyramid_->rebuild(*cube_);
        }
    }

    // Algorithm 1: the search the parameters name answers when it can; otherwise trace() (`TracedRay
    // trace()`, or `TracedRay trace(PathRecord&)` to record what the path saw for exact invalidation) runs,
    // what it brought back is stored (store()) and its colour returned. `texels_read`, when given, receives
    // the search's texel count, `found` its outcome. Thread-safe.
    template <class Trace>
    glm::vec3 cached_trace(const glm::vec3& origin, const glm::vec3& direction, Trace&& trace, int* texels_read = nullptr,
                           ReliefResult* found = nullptr) {
        return cdct_cached_trace(*cube_, bounds_, origin, direction, parameters_, std::forward<Trace>(trace), texels_read,
                                 pyramid_.get(), found);
    }

    // The search alone (depth_search over the pyramid): one lookup counted. Thread-safe.
    ReliefResult lookup(const glm::vec3& origin, const glm::vec3& direction) noexcept {
        return depth_search(*cube_, bounds_, origin, direction, parameters_, pyramid_.get());
    }

    // Stores what a ray traced from origin along direction brought back (store_traced). Thread-safe.
    bool store(const glm::vec3& origin, const glm::vec3& direction, const TracedRay& traced) noexcept {
        return store_traced(*cube_, bounds_, origin, direction, traced, parameters_);
    }
    // store() with what the traced path saw (raycache/path_record.hpp). Thread-safe.
    bool store(const glm::vec3& origin, const glm::vec3& direction, const TracedRay& traced, const PathRecord& path) noexcept {
        return store_traced(*cube_, bounds_, origin, direction, traced, parameters_, &path);
    }

    // Ends a frame: brings the pyramid up to this frame's stores, then makes them visible (CacheCube::
    // begin_frame). Between frames.
    CubeStatistics begin_frame() {
        cube_->settle_budget(); // the tiles the frame keeps, before the pyramid reads them
        if (pyramid_) pyramid_->update(*cube_); // before the frame's stores stop being marked
        return cube_->begin_frame();
    }

    // Empties the cube (and its pyramid). Between frames.
    void clear() {
        cube_->clear();
        if (pyramid_) pyramid_->rebuild(*cube_);
    }

    // Re-centres the cube on `bounds` (its object moved): its texels keep their directions and distances from
    // the centre, so they now describe surroundings that moved with the object (empty the cube, or invalidate
    // what the move changed, unless that is what you want). Between frames. Throws std::invalid_argument
    // for bounds without a finite centre and a half-size > 0.
    void move_to(const CubeBounds& bounds) {
        if (!detail::is_usable(bounds))
            throw std::invalid_argument("RayCache: CdctCache bounds need a finite centre and a half-size > 0");
        cube_->assert_between_frames();
        bounds_ = bounds;
    }

    // Recomputes the pyramid from the cube, after the cube was changed other than by stores (invalidate(),
    // store_word_at() of a load). Between frames.
    void rebuild_pyramid() {
        if (pyramid_) pyramid_->rebuild(*cube_);
    }

    CdctCube& cube() noexcept { return *cube_; }
    const CdctCube& cube() const noexcept { return *cube_; }
    const CubeBounds& bounds() const noexcept { return bounds_; }
    const ReliefParameters& parameters() const noexcept { return parameters_; }
    // The pyramid, or null when the cache keeps none.
    const DepthPyramid* pyramid() const noexcept { return pyramid_.get(); }
    std::size_t pyramid_bytes() const noexcept { return pyramid_ ? pyramid_->bytes() : 0; }

private:
    std::unique_ptr<CdctCube> cube_;
    CubeBounds bounds_;
    ReliefParameters parameters_;
    std::unique_ptr<DepthPyramid> pyramid_;
};

} // namespace raycache
