#pragma once
// Cubes that rest while they do not pay.
//
// A lookup, and the store after a miss, cost a good part of what tracing the ray costs (on the Embree
// tracer about 90 ns against about 170 ns a traced leaving ray), so a cube that answers fewer than about
// half of its rays makes a frame slower than no cube would. Along a camera path a mirror can hover there:
// its tiles' origins drift out of the origin test every few frames, or its reflections are mostly colour
// edges. Such a cube rests. Its rays are traced as if it were not there (counted as MissReason::resting
// misses, no lookup, no store), except its probe directions (shared::raycache_is_probe_direction_of: a
// sixteenth of direction space at first, in small boxes scattered over it, tested without a face choice),
// which go on looking up and storing, so that the hit rate the whole cube would have stays measured. Each
// frame decides the next: a working cube rests when the rays it looked up found fewer than min_hit_rate
// hits; a resting cube works again when its probes find at least that many, or after
// resting_max_unjudged_frames frames with too few probes to tell. A frame the cube started empty, or
// refilled in just after resting, decides nothing. Decisions follow the frame's counters alone, so frames
// stay the same with 1 or N threads.
//
// What resting itself costs is its probes, and its wrong wakes:
// - Probes are counted over frames until they are enough to judge (resting_min_judged_lookups), so a
//   cube with few rays is judged every few frames rather than woken unmeasured. A cube whose probes find
//   again that it does not pay, from one frame's probes with twice the lookups needed, probes half as
//   many directions the next frame, down to one in 2^RAYCACHE_MAX_PROBE_BITS; a frame too short of
//   probes to judge doubles them again. (On the Embree tracer's orbits a resting CDCT's probes cost about
//   3% of a frame at one direction in 16.)
// - Probes see what a cube resting in the same place answers, and a cube that wakes refills and is then
//   judged on its own rays, which on a moving camera can answer fewer than its probes did. A wake whose
//   first judged frame sends the cube back to rest doubles the frames it then rests before its probes
//   may wake it (1, 2, 4, then 8 frames); a judged frame that keeps it working resets that.

#include "raycache/shared/coverage.h"
#include "raycache/statistics.hpp"

#include <glm/vec3.hpp>

#include <algorithm>
#include <cstdint>
#include <optional>

namespace raycache {

// Whether a ray in unit `direction` looks up a cube that has just started resting
// (shared::raycache_is_probe_direction); is_probe_direction(direction, state) below for any resting cube.
inline bool is_probe_direction(const glm::vec3& direction) noexcept { return shared::raycache_is_probe_direction(direction); }

// The threshold a cache uses unless told otherwise, CCT 0.5 and CDCT 0.6: about where a cube starts to pay
// on the Embree example tracer, whose traced leaving ray costs about twice a CCT lookup and store (README
// "Results" has the sweep). A CDCT search costs more than a CCT lookup, so its cubes must answer more to pay.
inline constexpr float default_min_hit_rate(bool cdct) noexcept { return cdct ? 0.6f : 0.5f; }

// Fewer looked-up rays than this decide nothing: a working cube's frame with fewer keeps it working, and a
// resting cube's probes are counted over frames until they reach it.
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

// What the rays that filled a cube's texels reported they cost (TracedRay::work), summed over recent
// frames for resting_threshold: `work` over `reports` rays.
struct WorkEstimate {
    std::uint64_t work = 0, reports = 0;
};

// The estimate after a frame whose rays that filled texels reported `frame_work` over `frame_reports`. A
// frame with at least resting_min_judged_lookups reports halves what came before, so the estimate follows
// the recent frames; a frame with fewer (a resting cube's probes, a warm cube that stores little) adds to
// it without halving, so a cube keeps the threshold it rests by instead of falling back to the fixed one
// once the frames' reports have halved away. Whole numbers: the same with 1 or N threads.
inline WorkEstimate next_work_estimate(WorkEstimate now, std::uint64_t frame_work, std::uint64_t frame_reports) noexcept {
    if (frame_reports >= resting_min_judged_lookups) now.work /= 2, now.reports /= 2;
    return {now.work + frame_work, now.reports + frame_reports};
}

// A resting cube whose probes are too few to judge it this many frames in a row works again for a frame
// (its probes may miss the few directions its rays now take; it must not rest for ever unmeasured).
inline constexpr int resting_max_unjudged_frames = 8;

// Wrong wakes in a row that lengthen a cube's rest: after k of them it rests at least 2^k frames.
inline constexpr int resting_max_backoff = 3;
// The forced wake after resting_max_unjudged_frames unjudged frames does not wait for a minimum rest, so
// the longest minimum rest must not be longer.
static_assert((1 << resting_max_backoff) <= resting_max_unjudged_frames,
              "RayCache: a minimum rest longer than resting_max_unjudged_frames would be cut short");

// One cube's resting state from frame to frame.
struct RestingState {
    bool resting = false;
    int unjudged = 0;       // frames in a row it rested with too few probes to judge it
    bool refilling = false; // it has just stopped resting: its next frame refills what it let through
    // Resting: it probes one direction in 2^probe_bits (shared::raycache_is_probe_direction_of), and its
    // probes' counts of the frames not judged yet.
    unsigned probe_bits = RAYCACHE_PROBE_BITS;
    std::uint64_t probe_hits = 0, probe_lookups = 0;
    // Working: its next judged frame is the first since it woke. Resting: frames it rests whatever its
    // probes find. Both: wrong wakes in a row (0..resting_max_backoff).
    bool woke = false;
    int rest_left = 0;
    int backoff = 0;
};

// Whether a ray in unit `direction` looks up a resting cube in state `state` (one direction in
// 2^state.probe_bits).
inline bool is_probe_direction(const glm::vec3& direction, const RestingState& state) noexcept {
    return shared::raycache_is_probe_direction_of(direction, state.probe_bits);
}

namespace detail {

inline bool below(double hit_rate, float min_hit_rate) noexcept {
    return static_cast<float>(hit_rate) < min_hit_rate; // compared as floats: exactly 0.4 is not below 0.4f
}

// The state of a cube that starts resting after a judged working frame, `backoff` wrong wakes in a row.
inline RestingState starts_resting(int backoff) noexcept {
    RestingState next;
    next.resting = true;
    next.backoff = backoff;
    next.rest_left = (1 << backoff) - 1; // this frame's rest is the first
    return next;
}

// The state of a cube that works again after resting in state `now`: it refills first.
inline RestingState wakes(const RestingState& now) noexcept {
    RestingState next;
    next.refilling = true;
    next.backoff = now.backoff;
    return next;
}

// A resting cube's frame that could not judge it (too few probes so far, or a frame it started empty):
// `next` is its state with the frame's probes counted. After resting_max_unjudged_frames such frames in a
// row it works again (it must not rest for ever unmeasured); else its probes double (down to 1 in 2^
// RAYCACHE_PROBE_BITS) and its minimum rest runs on.
inline RestingState rests_unjudged(const RestingState& now, RestingState next) noexcept {
    if (now.unjudged + 1 >= resting_max_unjudged_frames) return wakes(now);
    next.unjudged = now.unjudged + 1;
    next.rest_left = std::max(now.rest_left - 1, 0);
    next.probe_bits = now.probe_bits > RAYCACHE_PROBE_BITS ? now.probe_bits - 1u : RAYCACHE_PROBE_BITS;
    next.refilling = false;
    return next;
}

} // namespace detail

// The state for the next frame of a cube in state `now` after a frame with counters `frame`, which the
// cube started empty when `started_empty`. A frame it started empty, or refilled in, says nothing of what
// it would answer once filled, so it keeps the state (else a cube that stops resting would rest again at
// once); for a resting cube it counts as an unjudged frame (a cube emptied while resting, whose probes
// alone could refill it, works again after resting_max_unjudged_frames of them). min_hit_rate <= 0 (or
// NaN): never resting.
inline RestingState next_resting_state(RestingState now, const CubeStatistics& frame, float min_hit_rate,
                                       bool started_empty = false) noexcept {
    if (!(min_hit_rate > 0.0f)) return {};
    if (started_empty && now.resting) return detail::rests_unjudged(now, now);
    if (started_empty || now.refilling) {
        now.woke = now.woke || now.refilling; // its next judged frame tells whether waking was right
        now.refilling = false;
        return now;
    }
    if (!now.resting) {
        const std::optional<double> rate = looked_up_hit_rate(frame);
        if (!rate) return now;
        if (!detail::below(*rate, min_hit_rate)) return {}; // it pays: no wrong wake
        return detail::starts_resting(now.woke ? std::min(now.backoff + 1, resting_max_backoff) : 0);
    }
    RestingState next = now;
    next.rest_left = std::max(now.rest_left - 1, 0);
    next.probe_hits += frame.hits;
    next.probe_lookups += frame.looked_up();
    if (next.probe_lookups < resting_min_judged_lookups) return detail::rests_unjudged(now, next);
    const bool pays =
        !detail::below(static_cast<double>(next.probe_hits) / static_cast<double>(next.probe_lookups), min_hit_rate);
    if (pays && now.rest_left == 0) return detail::wakes(now);
    // Judged: it rests on, its probes counted afresh; fewer of them when one frame's were plenty to say so.
    next.unjudged = 0;
    next.probe_hits = next.probe_lookups = 0;
    if (!pays && frame.looked_up() >= 2 * resting_min_judged_lookups)
        next.probe_bits = std::min(now.probe_bits + 1u, static_cast<unsigned>(RAYCACHE_MAX_PROBE_BITS));
    return next;
}

} // namespace raycache
