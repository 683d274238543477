// raycache/adaptive_resolution.hpp: choosing a cube's face size from the rays that reach it, and moving
// its contents to a coarser cube without losing a frame.
//
// Why: a cube's hit rate along a moving camera is roughly (rays per frame) / (texels those rays spread
// over). A fixed 512 x 512 cube on a sphere that receives 5,000 leaving rays has 1.5 million texels for
// them: each frame's rays land on texels no earlier ray touched, and the cache only costs. Matching the
// texel to the ray's footprint (about `rays_per_texel` rays of a frame per texel) makes the next frame's
// rays land on texels this frame filled. A mirror sphere seen through a pinhole spreads its pixels
// almost evenly over the directions it reflects (the mirror-ball property), so rays per covered texel
// is a good measure of the footprint for the objects RayCache caches.
//
// How: DirectionCoverage marks, on a coarse 16 x 16 grid per face, which directions this frame's
// leaving rays took; the covered fraction times 6 N^2 is the texel area they spread over at face size N.
// adaptive_face_size() picks N so that area holds rays / rays_per_texel texels, on a ladder of sizes a
// half octave apart. resample_into() fills a coarser cube from a finer one (each coarse texel takes the
// valid fine texel nearest its centre, and each coarse tile the origins of the fine tiles it drew from),
// so shrinking a cube keeps it warm.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "raycache/cache_cube.hpp"
#include "raycache/cube_face.hpp"
#include "raycache/shared/coverage.h"
#include "raycache/shared/origin_rule.h"
#include "raycache/statistics.hpp"

namespace raycache {

// The face sizes an adaptive cube moves between: 8 * 2^(i/2) rounded, up to 4096 (8, 11, 16, 23, 32, ...).
inline int face_size_step(int i) noexcept {
    return static_cast<int>(std::lround(8.0 * std::exp2(0.5 * static_cast<double>(i))));
}

// How an adaptive cube picks its face size.
struct AdaptiveResolution {
    float rays_per_texel = 1.0f; // leaving rays of one frame per covered texel aimed at (> 0)
    int min_face_size = 8;       // never coarser
    int max_face_size = 1024;    // never finer (the largest step <= this)
    int first_face_size = 256;   // before any frame has been counted (SceneCache lowers it when its cubes
                                 // could not all fill theirs within the budget: first_face_size_within)
    // The face size moves only when the ideal size is this many half-octave steps away (>= 1): a
    // change costs the finer texels (a shrink keeps the rest) or a cold frame (a growth), so a size
    // hovering between two steps must not flip back and forth.
    int hysteresis_steps = 2;
    // Once a cube's rays hold still (a still camera: for still_frames frames in a row at most 5% of its
    // lookups found texels nobody had stored, whether the others hit or met colour edges), it takes the finer
    // faces of this many rays a texel: the same rays come back to the same texels, so finer faces cost
    // them nothing but a cold frame and answer each ray with a colour closer to its own. It goes back to
    // rays_per_texel when more than 20% of its lookups find texels nobody stored (the rays moved on).
    // >= rays_per_texel: off.
    float still_rays_per_texel = 0.1f;
    int still_frames = 3;
};

// Throws std::invalid_argument naming the field when `a` cannot be used.
inline void validate(const AdaptiveResolution& a) {
    if (!(a.rays_per_texel > 0.0f) || !std::isfinite(a.rays_per_texel))
        throw std::invalid_argument("RayCache: AdaptiveResolution::rays_per_texel must be a finite number > 0");
    if (!is_valid_face_size(a.min_face_size) || !is_valid_face_size(a.max_face_size) || a.min_face_size > a.max_face_size)
        throw std::invalid_argument("RayCache: AdaptiveResolution needs 1 <= min_face_size <= max_face_size <= 4096");
    if (!is_valid_face_size(a.first_face_size))
        throw std::invalid_argument("RayCache: AdaptiveResolution::first_face_size must be 1 to 4096");
    if (a.first_face_size < a.min_face_size || a.first_face_size > a.max_face_size)
        throw std::invalid_argument("RayCache: AdaptiveResolution::first_face_size (" + std::to_string(a.first_face_size) +
                                    ") must lie within min_face_size (" + std::to_string(a.min_face_size) + ") and max_face_size (" +
                                    std::to_string(a.max_face_size) + ")");
    if (a.hysteresis_steps < 1)
        throw std::invalid_argument("RayCache: AdaptiveResolution::hysteresis_steps must be at least 1");
    if (!(a.still_rays_per_texel > 0.0f) || !std::isfinite(a.still_rays_per_texel))
        throw std::invalid_argument("RayCache: AdaptiveResolution::still_rays_per_texel must be a finite number > 0");
    if (a.still_frames < 1)
        throw std::invalid_argument("RayCache: AdaptiveResolution::still_frames must be at least 1");
}

// Which of 6 x 16 x 16 direction cells a frame's rays took. mark() from any number of threads at once
// (a relaxed load, and an atomic OR only the first time a cell is met); fraction() and reset() between frames.
class DirectionCoverage {
public:
    static constexpr int cells_per_edge = RAYCACHE_COVERAGE_CELLS_PER_EDGE;
    static constexpr int cell_count = static_cast<int>(RAYCACHE_COVERAGE_CELLS);

    // The cell of shared/coverage.h, as the GPU's frame buffer marks it.
    void mark(const glm::vec3& direction) noexcept {
        const std::uint32_t cell = shared::raycache_coverage_cell(direction);
        if (cell != RAYCACHE_NO_COVERAGE_CELL) mark_cell(cell);
    }
    // mark() for a ray already found to fall in texel `t` of a cube of `face_size`: spares the second face
    // choice. A texel of a face of 16 texels or more marks the cell its centre falls in; a larger texel
    // every cell it overlaps.
    void mark(const TexelAddress& t, int face_size) noexcept {
        if (face_size >= cells_per_edge) {
            mark_cell(shared::raycache_coverage_cell_of_texel({t.face, t.column, t.row}, face_size));
            return;
        }
        const int c0 = t.column * cells_per_edge / face_size, c1 = ((t.column + 1) * cells_per_edge + face_size - 1) / face_size;
        const int r0 = t.row * cells_per_edge / face_size, r1 = ((t.row + 1) * cells_per_edge + face_size - 1) / face_size;
        for (int row = r0; row < r1; ++row)
            for (int column = c0; column < c1; ++column)
                mark_cell(shared::raycache_texel_linear_index({t.face, column, row}, cells_per_edge));
    }
    // The marked cells as bits (cell (face, column, row) is bit (face * 16 + row) * 16 + column).
    std::array<std::uint64_t, cell_count / 64> marked_cells() const noexcept {
        std::array<std::uint64_t, cell_count / 64> bits{};
        for (std::size_t i = 0; i < bits.size(); ++i) bits[i] = words_[i].load(std::memory_order_relaxed);
        return bits;
    }
    // The share of the cells marked since the last reset(), 0..1.
    double fraction() const noexcept {
        int marked = 0;
        for (const auto& w : words_) {
            std::uint64_t bits = w.load(std::memory_order_relaxed);
            for (; bits; bits &= bits - 1) ++marked;
        }
        return static_cast<double>(marked) / cell_count;
    }
    void reset() noexcept {
        for (auto& w : words_) w.store(0, std::memory_order_relaxed);
    }

private:
    void mark_cell(std::uint32_t cell) noexcept {
        const std::uint64_t bit = std::uint64_t{1} << (cell % 64);
        std::atomic<std::uint64_t>& word = words_[cell / 64];
        if (!(word.load(std::memory_order_relaxed) & bit)) word.fetch_or(bit, std::memory_order_relaxed);
    }
    std::atomic<std::uint64_t> words_[cell_count / 64] = {};
};

// The ideal face size (not yet on the ladder) for `rays` leaving rays of one frame spread over
// `covered_fraction` (0..1) of all directions: sqrt(rays / (rays_per_texel * 6 * covered_fraction)).
// 0 when no ray came (nothing to go by).
inline double ideal_face_size(std::uint64_t rays, double covered_fraction, float rays_per_texel) noexcept {
    if (rays == 0 || !(covered_fraction > 0.0)) return 0.0;
    return std::sqrt(static_cast<double>(rays) / (static_cast<double>(rays_per_texel) * RAYCACHE_FACE_COUNT * covered_fraction));
}

// The ladder step nearest (in octaves) to `ideal`, clamped to [min_face_size, max_face_size].
inline int nearest_face_size_step(double ideal, const AdaptiveResolution& a) noexcept {
    int best = a.min_face_size;
    double best_distance = std::numeric_limits<double>::infinity();
    for (int i = 0;; ++i) {
        const int size = face_size_step(i);
        if (size > a.max_face_size || size > RAYCACHE_MAX_FACE_SIZE) break;
        if (size < a.min_face_size) continue;
        const double distance = std::abs(std::log2(static_cast<double>(size) / ideal));
        if (distance < best_distance) {
            best_distance = distance;
            best = size;
        }
    }
    return best;
}

// The face size an adaptive cube of face size `current` should have after a frame in which `rays`
// leaving rays covered `covered_fraction` of the directions: `current` unless the ideal size is at
// least hysteresis_steps half octaves away. A frame without rays keeps `current`.
inline int next_face_size(int current, std::uint64_t rays, double covered_fraction, const AdaptiveResolution& a) noexcept {
    const double ideal = ideal_face_size(rays, covered_fraction, a.rays_per_texel);
    if (ideal <= 0.0) return current;
    const double half_octaves = 2.0 * std::abs(std::log2(ideal / static_cast<double>(current)));
    if (half_octaves < static_cast<double>(a.hysteresis_steps) - 1e-9) return current;
    return nearest_face_size_step(ideal, a);
}

// The face size for a cube after the first frame its rays were counted in: the nearest step to the ideal,
// without hysteresis (the cube holds only that cold frame's texels, so moving costs nearly nothing and
// waiting would keep a first guess for the whole walkthrough). A frame without rays keeps `current`.
inline int first_face_size(int current, std::uint64_t rays, double covered_fraction, const AdaptiveResolution& a) noexcept {
    const double ideal = ideal_face_size(rays, covered_fraction, a.rays_per_texel);
    return ideal > 0.0 ? nearest_face_size_step(ideal, a) : current;
}

// The face size of an adaptive cube after a frame in which `rays` leaving rays covered `covered_fraction`
// of the directions: first_face_size() while no frame with rays has sized it yet (`sized` false),
// next_face_size() after.
inline int adapted_face_size(int current, bool sized, std::uint64_t rays, double covered_fraction,
                             const AdaptiveResolution& a) noexcept {
    return sized ? next_face_size(current, rays, covered_fraction, a) : first_face_size(current, rays, covered_fraction, a);
}

// Whether a cube's rays hold still, from frame to frame (AdaptiveResolution::still_rays_per_texel).
struct StillRays {
    int settled_frames = 0; // frames in a row whose lookups looked still
    bool fine = false;      // the cube takes still_rays_per_texel
    bool resized = false;   // the cube was resized (or made) before the frame being judged
    bool refined = false;   // sized at still_rays_per_texel since it became fine (still_face_size())
};

// The state after a frame in which the cube made `looked_up` lookups (its resting rays left out), `empty`
// of them missing on texels nobody had stored. The rays came back to the texels they stored when few did:
// texels at colour edges count as come back to (the confidence test traces them), and finer faces are what
// thins those edges. A frame right after a resize says nothing (a grown cube starts empty, a shrunk one
// coarser): the state stays. Deterministic.
inline StillRays next_still_rays(StillRays s, std::uint64_t looked_up, std::uint64_t empty, const AdaptiveResolution& a) noexcept {
    if (s.resized) {
        s.resized = false;
        return s;
    }
    const double n = static_cast<double>(looked_up);
    const bool settled = looked_up > 0 && static_cast<double>(empty) <= 0.05 * n;
    s.settled_frames = settled ? s.settled_frames + 1 : 0;
    if (s.settled_frames >= a.still_frames) s.fine = true;
    if (looked_up > 0 && static_cast<double>(empty) > 0.2 * n) s.fine = false;
    return s;
}

// The face size of an adaptive cube of face size `current` after a frame of `rays` leaving rays over
// `covered_fraction` of the directions, given `next`, adapted_face_size()'s at a.rays_per_texel. While its
// rays hold still (`still.fine`), the size they call for at a.still_rays_per_texel instead: at once, without
// the hysteresis, when they have just come to hold still (still.refined was false: the rays came back to the
// same texels for still_frames frames), and with it after (still.refined), so that it does not flip between
// neighbouring sizes. Never coarser than `next`. Sets still.refined.
inline int still_face_size(int current, int next, StillRays& still, std::uint64_t rays, double covered_fraction,
                           const AdaptiveResolution& a) noexcept {
    if (!still.fine || !(a.still_rays_per_texel < a.rays_per_texel)) {
        still.refined = false;
        return next;
    }
    const double ideal = ideal_face_size(rays, covered_fraction, a.still_rays_per_texel);
    if (ideal <= 0.0) return next; // no ray came: nothing to go by
    AdaptiveResolution fine = a;
    fine.rays_per_texel = a.still_rays_per_texel;
    const int size = still.refined ? next_face_size(current, rays, covered_fraction, fine) : nearest_face_size_step(ideal, a);
    still.refined = true;
    return std::max(next, size);
}

// The still rule after a frame of a working (not resting) adaptive cube of face size `current`, whose
// counters were `frame` (lookups, misses on empty texels) over `covered_fraction` of the directions:
// updates `still` (next_still_rays) and, once a frame has sized the cube (`sized`), returns still_face_size()
// of `next`, adapted_face_size()'s; else `next`. SceneCache's and the GPU's sizing (gpu_adaptive.hpp) both.
inline int face_size_with_still_rule(int current, int next, bool sized, const CubeStatistics& frame, double covered_fraction,
                                     StillRays& still, const AdaptiveResolution& a) noexcept {
    still = next_still_rays(still, frame.looked_up(), frame.misses_by[static_cast<std::size_t>(MissReason::empty)], a);
    return sized ? still_face_size(current, next, still, frame.lookups, covered_fraction, a) : next;
}

// The tiles (16 x 16 texels) of a cube of `face_size`: 6 ceil(N / 16)^2.
inline std::size_t cube_tile_count(int face_size) noexcept { return shared::raycache_origin_tile_count(face_size); }

// The bytes a cube of `face_size` takes from its budget once every one of its tiles is allocated: its tile
// table (`entry_bytes` a tile), its tiles (`tile_bytes` each) and what every cube holds whatever its size
// (`cube_bytes`; CacheCube::fixed_bytes_per_tile and fixed_bytes_per_cube() bound a CacheCube's).
inline std::size_t full_cube_bytes(int face_size, std::size_t tile_bytes, std::size_t entry_bytes, std::size_t cube_bytes = 0) noexcept {
    return cube_tile_count(face_size) * (tile_bytes + entry_bytes) + cube_bytes;
}

// The bytes a cube of `face_size` takes once its rays, covering `covered_fraction` of the directions (the
// share of DirectionCoverage's cells they marked), have reached every tile of those directions: its whole
// tile table, that share of its tiles and `cube_bytes` (as in full_cube_bytes()). An estimate from above
// when they cover the cells they mark densely, as a still camera's rays at still_rays_per_texel do.
inline std::size_t rays_cube_bytes(int face_size, double covered_fraction, std::size_t tile_bytes, std::size_t entry_bytes,
                                   std::size_t cube_bytes = 0) noexcept {
    const std::size_t tiles = cube_tile_count(face_size);
    const double covered = std::min(std::max(covered_fraction, 0.0), 1.0);
    return tiles * entry_bytes + static_cast<std::size_t>(std::ceil(covered * static_cast<double>(tiles * tile_bytes))) + cube_bytes;
}

// The largest ladder step in (floor, wanted] whose cube fits `room` bytes by rays_cube_bytes(); `floor`
// when none does. The still rule's finer faces take only what the budget has room for: a cube that cannot
// hold its rays' tiles keeps missing on empty texels, which reads as rays that moved on, so it would
// shrink and refine again every few frames, each time with a cold frame.
inline int largest_face_size_within(int floor, int wanted, double covered_fraction, std::size_t room, std::size_t tile_bytes,
                                    std::size_t entry_bytes, std::size_t cube_bytes = 0) noexcept {
    int best = floor;
    for (int i = 0;; ++i) {
        const int size = face_size_step(i);
        if (size > wanted || size > RAYCACHE_MAX_FACE_SIZE) break;
        if (size > floor && rays_cube_bytes(size, covered_fraction, tile_bytes, entry_bytes, cube_bytes) <= room) best = size;
    }
    return best;
}

// The face size adaptive cubes start at when `cubes` of them share a budget of `budget_bytes`:
// a.first_face_size, or the largest ladder step below it (not below a.min_face_size) at which each
// cube could fill every tile within an equal share of the budget. So a cold frame's stores fit however the
// rays spread (a frame that outgrows the budget keeps none of its new tiles: raycache/memory_budget.hpp);
// after it, each cube takes the size its rays call for. a.min_face_size when even that does not fit.
// (`cube_bytes` as in full_cube_bytes().)
inline int first_face_size_within(const AdaptiveResolution& a, std::size_t cubes, std::size_t budget_bytes,
                                  std::size_t tile_bytes, std::size_t entry_bytes, std::size_t cube_bytes = 0) noexcept {
    const std::size_t share = budget_bytes / std::max<std::size_t>(cubes, 1);
    if (full_cube_bytes(a.first_face_size, tile_bytes, entry_bytes, cube_bytes) <= share) return a.first_face_size;
    int best = a.min_face_size;
    for (int i = 0;; ++i) {
        const int size = face_size_step(i);
        if (size >= a.first_face_size) break;
        if (size >= a.min_face_size && full_cube_bytes(size, tile_bytes, entry_bytes, cube_bytes) <= share) best = size;
    }
    return best;
}

// Fills the empty texels of `coarse` from `fine` (a cube of a larger face size): each coarse texel takes
// the value of the valid fine texel whose centre direction falls in it nearest to its centre (ties: the
// first in linear order), so the value stands for the coarse texel's centre as well as the fine cube
// allows. The stores become visible at coarse's next begin_frame(). Between frames only (both cubes).
// Returns the texels stored.
template <class Texel>
std::size_t resample_into(const CacheCube<Texel>& fine, CacheCube<Texel>& coarse) {
    const int n = coarse.face_size();
    const int fine_n = fine.face_size();
    struct Best { // 8 bytes: one per coarse texel, and cubes may be resampled on several threads at once
        float distance2 = std::numeric_limits<float>::infinity();
        std::uint32_t source = 0; // the fine texel's linear index
    };
    std::vector<Best> best(coarse.texel_count());
    fine.for_each_valid_texel([&](const TexelAddress& t) {
        const glm::vec3 d = texel_direction(t, fine_n);
        const shared::raycache_texel_address a = shared::raycache_texel_of(d, n);
        if (a.face == RAYCACHE_NO_FACE) return;
        // Where d falls on the coarse face, in coarse texels, as the texel choice computes it.
        const glm::vec2 st = shared::raycache_face_coordinates(d, a.face);
        const float scale = 0.5f / shared::raycache_major_magnitude(d, a.face);
        const float u = shared::raycache_texel_position(st.x, scale, n) - (static_cast<float>(a.column) + 0.5f);
        const float v = shared::raycache_texel_position(st.y, scale, n) - (static_cast<float>(a.row) + 0.5f);
        Best& b = best[shared::raycache_texel_linear_index(a, n)];
        const float distance2 = u * u + v * v;
        if (distance2 < b.distance2) b = Best{distance2, static_cast<std::uint32_t>(texel_linear_index(t, fine_n))};
    });
    // Each coarse tile's origins: the union of the boxes, and the nearest distance, of the fine tiles its
    // texels came from, so the coarse tile answers the rays its values suit and no others.
    struct Origins {
        bool any = false;
        glm::vec3 lo{0.0f}, hi{0.0f};
        float nearest = std::numeric_limits<float>::infinity();
    };
    const int tiles_per_edge = (n + CacheCube<Texel>::tile_edge - 1) / CacheCube<Texel>::tile_edge;
    std::vector<Origins> origins(std::size_t{RAYCACHE_FACE_COUNT} * tiles_per_edge * tiles_per_edge);
    auto tile_of = [&](const TexelAddress& t) -> Origins& {
        return origins[(static_cast<std::size_t>(t.face) * tiles_per_edge + t.row / CacheCube<Texel>::tile_edge) * tiles_per_edge +
                       t.column / CacheCube<Texel>::tile_edge];
    };
    std::size_t stored = 0;
    for (std::size_t i = 0; i < best.size(); ++i) {
        if (!std::isfinite(best[i].distance2)) continue;
        const TexelAddress target = texel_at_linear_index(i, n), source = texel_at_linear_index(best[i].source, fine_n);
        if (coarse.load(target)) continue;
        if (!coarse.store_at(target, *fine.load(source))) continue;
        ++stored;
        if (const auto box = fine.origin_box(source)) {
            Origins& o = tile_of(target);
            o.lo = o.any ? glm::min(o.lo, box->first) : box->first;
            o.hi = o.any ? glm::max(o.hi, box->second) : box->second;
            o.any = true;
            o.nearest = std::min(o.nearest, fine.nearest_hit(source));
        }
    }
    for (int face = 0; face < RAYCACHE_FACE_COUNT; ++face)
        for (int row = 0; row < tiles_per_edge; ++row)
            for (int column = 0; column < tiles_per_edge; ++column) {
                const TexelAddress first{face, column * CacheCube<Texel>::tile_edge, row * CacheCube<Texel>::tile_edge};
                const Origins& o = tile_of(first);
                if (o.any) coarse.set_origin_box(first, o.lo, o.hi, o.nearest);
            }
    return stored;
}

} // namespace raycache
