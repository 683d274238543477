#pragma once
// Cubes that rest while they do not pay.
//
// A lookup, and the store after a miss, cost a good part of what tracing the ray costs (on the Embree
// tracer about 90 ns against about 170 ns a traced leaving ray), so a cube that answers fewer than about
// half of its rays makes a frame slower than no cube would. Along a camera path a mirror can hover there:
// its tiles' origins drift out of the origin test every few frames, or its reflections are mostly colour
// edges. Such a cube rests. Its rays are traced as if it were not there (counted as MissReason::resting
// misses, no lookup, no store), except its probe directions (shared::raycache_is_probe_direction: a
// sixteenth of direction space, in small boxes scattered over it, tested without a face choice), which
// go on looking up and storing, so that the hit rate the whole cube would have stays measured. Each frame
// decides the next: a working cube rests when the rays it looked up found fewer than min_hit_rate hits;
// a resting cube works again when its probes find at least that many, or after resting_max_unjudged_frames
// frames with too few probes to tell. A frame the cube started empty, or refilled in just after resting,
// decides nothing. Decisions follow the frame's counters alone, so frames stay the same with 1 or N
// threads.

#include "raycache/shared/coverage.h"
#include "raycache/statistics.hpp"

#include <glm/vec3.hpp>

#include <algorithm>
#include <cstdint>
#include <optional>

namespace raycache {

// Whether a ray in unit `direction` looks up a resting cube (shared::raycache_is_probe_direction).
inline bool is_probe_direction(const glm::vec3& direction) noexcept { return shared::raycache_is_probe_direction(direction); }

// The threshold a cache uses unless told otherwise, CCT 0.5 and CDCT 0.6: about where a cube starts to pay
// on the Embree example tracer, whose traced leaving ray costs about twice a CCT lookup and store (README
// "Results" has the sweep). A CDCT search costs more than a CCT lookup, so its cubes must answer more to pay.
inline constexpr float default_min_hit_rate(bool cdct) noexcept { return cdct ? 0.6f : 0.5f; }

// Fewer looked-up rays in a frame than this decide nothing (the cube keeps resting or working).
inline constexpr std::uint64_t resting_min_judged_lookups = 32;

// The hit rate of the rays a frame looked up in a cube (its resting misses left out); std::nullopt when
// they were fewer than resting_min_judged_lookups.
inline std::optional<double> looked_up_hit_rate(const CubeStatistics& frame) noexcept {
    const std::uint64_t looked_up = frame.looked_up();
    if (looked_up < resting_min_judged_lookups) return std::nullopt;
    return static_cast<double>(frame.hits) / static_cast<double>(looked_up);
}

// The hit rate a cube must reach in a frame to keep working, when the rays that filled its texels reported
// what they cost (TracedRay::work): `work` over `reports` of them. A hit saves about what its texel's ray
// cost, and every lookup costs `lookup_work` (in the same units, with its share of stores and end-of-frame
// work), so the cube pays from lookup_work / (work / reports) on, clamped to [resting_threshold_floor,
// resting_threshold_ceiling]. A tracer whose rays cost five times the example's then keeps cubes working
// at a fifth of the hit rate. The rays that filled texels, not all it traced: the confidence test traces
// the rays of colour edges every frame, which see more and cost more than the rays its hits stand for.
// Whole-number sums, so the threshold, like the decisions, is the same with 1 or N threads. `fallback`
// when lookup_work <= 0 (or NaN) or fewer than resting_min_judged_lookups rays reported their work.
inline constexpr float resting_threshold_floor = 0.05f;
inline constexpr float resting_threshold_ceiling = 0.9f;
inline float resting_threshold(std::uint64_t work, std::uint64_t reports, float lookup_work, float fallback) noexcept {
    if (!(lookup_work > 0.0f) || reports < resting_min_judged_lookups || work == 0) return fallback;
    const double threshold = static_cast<double>(lookup_work) * static_cast<double>(reports) / static_cast<double>(work);
    return static_cast<float>(std::min<double>(std::max<double>(threshold, resting_threshold_floor), resting_threshold_ceiling));
}

// A resting cube whose probes are too few to judge it this many frames in a row works again for a frame
// (its probes may miss the few directions its rays now take; it must not rest for ever unmeasured).
inline constexpr int resting_max_unjudged_frames = 8;

// One cube's resting state from frame to frame.
struct RestingState {
    bool resting = false;
    int unjudged = 0;       // frames in a row it rested with too few probes to judge it
    bool refilling = false; // it has just stopped resting: its next frame refills what it let through
};

// The state for the next frame of a cube in state `now` after a frame with counters `frame`, which the
// cube started empty when `started_empty`. A frame it started empty, or refilled in, says nothing of what
// it would answer once filled, so it keeps the state (else a cube that stops resting would rest again at
// once). min_hit_rate <= 0 (or NaN): never resting.
inline RestingState next_resting_state(RestingState now, const CubeStatistics& frame, float min_hit_rate,
                                       bool started_empty = false) noexcept {
    if (!(min_hit_rate > 0.0f)) return {};
    if (started_empty || now.refilling) {
        now.refilling = false;
        return now;
    }
    RestingState next;
    if (const std::optional<double> rate = looked_up_hit_rate(frame))
        next.resting = static_cast<float>(*rate) < min_hit_rate; // compared as floats: exactly 0.4 is not below 0.4f
    else if (now.resting && now.unjudged + 1 < resting_max_unjudged_frames)
        next = {true, now.unjudged + 1};
    next.refilling = now.resting && !next.resting;
    return next;
}

} // namespace raycache
