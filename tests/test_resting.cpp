// Resting cubes (raycache/resting.hpp): which directions probe a resting cube, and how a frame's counters
// decide whether the cube rests in the next.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include <raycache/raycache.hpp>

using raycache::CubeStatistics;
using raycache::MissReason;

namespace {

// A frame's counters: `hits` of `lookups`, `rested` of the misses resting ones.
CubeStatistics frame(std::uint64_t lookups, std::uint64_t hits, std::uint64_t rested = 0) {
    CubeStatistics s;
    s.lookups = lookups;
    s.hits = hits;
    s.misses = lookups - hits;
    s.misses_by[static_cast<std::size_t>(MissReason::resting)] = rested;
    s.misses_by[static_cast<std::size_t>(MissReason::empty)] = lookups - hits - rested;
    return s;
}

// Whether a cube working (or resting, `resting`) in a judged frame with counters `f` rests next.
bool rests(bool resting, const CubeStatistics& f, float min_hit_rate) {
    return raycache::next_resting_state(raycache::RestingState{resting, 0, false}, f, min_hit_rate).resting;
}

} // namespace

TEST_CASE("probe directions are a sixteenth of all directions, spread over every quarter of every cube face") {
    // Uniformly random unit directions (normalised Gaussian vectors); each quarter of a face (8 x 8 of the
    // 16 x 16 direction cells) must hold probes in about the same share.
    std::mt19937 rng(7);
    std::normal_distribution<float> gaussian;
    const int n = 200000;
    int probes = 0;
    int per_quarter[24][2] = {}; // directions, probes
    for (int i = 0; i < n; ++i) {
        const glm::vec3 d = glm::normalize(glm::vec3(gaussian(rng), gaussian(rng), gaussian(rng)));
        const bool probe = raycache::is_probe_direction(d);
        probes += probe ? 1 : 0;
        const std::uint32_t cell = raycache::shared::raycache_coverage_cell(d);
        const int quarter = static_cast<int>(cell / 256 * 4 + cell % 256 / 16 / 8 * 2 + cell % 16 / 8);
        ++per_quarter[quarter][0];
        per_quarter[quarter][1] += probe ? 1 : 0;
    }
    CHECK(probes > n / 20);
    CHECK(probes < n * 3 / 40);
    for (int q = 0; q < 24; ++q) {
        CAPTURE(q);
        const double share = static_cast<double>(per_quarter[q][1]) / per_quarter[q][0];
        CHECK(share > 0.03);
        CHECK(share < 0.12);
    }
}

TEST_CASE("a probe is a box of directions: the low mantissa bits of a component never change the answer") {
    // The boxes are cut by each component's sign, exponent and three first mantissa bits (its float's top
    // 12 bits), so changing any of the 20 bits below moves a direction within its box.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> component(-1.0f, 1.0f);
    std::uniform_int_distribution<std::uint32_t> low(0, (1u << 20) - 1);
    auto with_low_bits = [&](float x) {
        std::uint32_t bits;
        std::memcpy(&bits, &x, sizeof bits);
        bits = (bits & ~((1u << 20) - 1)) | low(rng);
        std::memcpy(&x, &bits, sizeof bits);
        return x;
    };
    int probes = 0;
    for (int i = 0; i < 20000; ++i) {
        const glm::vec3 d(component(rng), component(rng), component(rng));
        const bool probe = raycache::is_probe_direction(d);
        probes += probe ? 1 : 0;
        CHECK(raycache::is_probe_direction(glm::vec3(with_low_bits(d.x), with_low_bits(d.y), with_low_bits(d.z))) == probe);
    }
    CHECK(probes > 0); // the comparison saw both answers
    CHECK(probes < 20000);
}

TEST_CASE("a working cube rests after a frame whose hit rate fell below min_hit_rate, and not at it") {
    CHECK(rests(false, frame(100, 40), 0.5f));
    CHECK(rests(false, frame(100, 49), 0.5f));
    CHECK_FALSE(rests(false, frame(100, 50), 0.5f)); // 50 %: not below
    CHECK_FALSE(rests(false, frame(100, 40), 0.4f));
    CHECK_FALSE(rests(false, frame(100, 90), 0.5f));
    CHECK(rests(false, frame(1000, 0), 0.01f));
}

TEST_CASE("a resting cube is judged by the rays it looked up (its probes), not by the rays it let through") {
    // 1000 rays, 940 let through resting: 60 probes, 30 hits, 50 %.
    CHECK(raycache::looked_up_hit_rate(frame(1000, 30, 940)).value() == doctest::Approx(0.5));
    CHECK_FALSE(rests(true, frame(1000, 30, 940), 0.5f)); // works again
    CHECK(rests(true, frame(1000, 29, 940), 0.5f));       // 48 %: rests on
    // (Judged over all 1000 rays, 3 %, it would rest for ever.)
}

TEST_CASE("too few looked-up rays decide nothing: the cube keeps resting or working") {
    const std::uint64_t few = raycache::resting_min_judged_lookups - 1;
    CHECK_FALSE(raycache::looked_up_hit_rate(frame(few, 0)).has_value());
    CHECK_FALSE(rests(false, frame(few, 0), 0.5f));
    CHECK(rests(true, frame(few, few), 0.5f));
    CHECK(rests(true, frame(1000, 0, 1000), 0.5f)); // no probe at all: rests on
    CHECK(raycache::looked_up_hit_rate(frame(few + 1, 0)).has_value());
}

TEST_CASE("a resting cube too few of whose rays probe works again after resting_max_unjudged_frames frames") {
    const CubeStatistics unprobed = frame(1000, 0, 1000); // every ray let through: nothing to judge by
    raycache::RestingState state{true, 0, false};
    for (int f = 1; f < raycache::resting_max_unjudged_frames; ++f) {
        CAPTURE(f);
        state = raycache::next_resting_state(state, unprobed, 0.5f);
        CHECK(state.resting);
        CHECK(state.unjudged == f);
    }
    state = raycache::next_resting_state(state, unprobed, 0.5f);
    CHECK_FALSE(state.resting);
    CHECK(state.unjudged == 0);
    // A frame that judges it starts the count again, resting or not.
    CHECK(raycache::next_resting_state({true, 5, false}, frame(1000, 10, 900), 0.5f).unjudged == 0);
    CHECK(raycache::next_resting_state({true, 5, false}, frame(1000, 10, 900), 0.5f).resting);
    // A working cube with too few rays to judge keeps working, and counts nothing.
    CHECK(raycache::next_resting_state({false, 0, false}, frame(3, 0), 0.5f).unjudged == 0);
}

TEST_CASE("the work estimate halves at a frame with 32 reports or more, and only adds a frame with fewer") {
    using raycache::WorkEstimate;
    WorkEstimate e = raycache::next_work_estimate(WorkEstimate{}, 200, 100);
    CHECK(e.work == 200u);
    CHECK(e.reports == 100u);
    for (int f = 0; f < 10; ++f) e = raycache::next_work_estimate(e, 0, 0); // a warm or resting cube storing nothing
    CHECK(e.work == 200u);
    CHECK(e.reports == 100u);
    e = raycache::next_work_estimate(e, 62, 31); // a few probes' stores: added, nothing halved
    CHECK(e.work == 262u);
    CHECK(e.reports == 131u);
    e = raycache::next_work_estimate(e, 400, 32); // a frame that says enough: what came before counts half
    CHECK(e.work == 131u + 400u);
    CHECK(e.reports == 65u + 32u);
}

TEST_CASE("a resting cube's probes are counted over frames until they are enough to judge it") {
    using raycache::RestingState;
    // 20 probes a frame (fewer than 32): the first frame decides nothing and keeps its counts.
    const RestingState resting{true, 0, false};
    RestingState one = raycache::next_resting_state(resting, frame(1000, 5, 980), 0.5f);
    CHECK(one.resting);
    CHECK(one.unjudged == 1);
    CHECK(one.probe_lookups == 20u);
    CHECK(one.probe_hits == 5u);
    // A second frame of 20 probes, 15 hits: 20 of 40 (0.5, not below), so it works again, though that frame
    // alone (15 of 20) is too few to judge and the first alone (5 of 20) would have said rest.
    const RestingState woke = raycache::next_resting_state(one, frame(1000, 15, 980), 0.5f);
    CHECK_FALSE(woke.resting);
    CHECK(woke.refilling);
    // With 10 hits instead: 15 of 40 (0.375) rests on, counts started afresh.
    const RestingState on = raycache::next_resting_state(one, frame(1000, 10, 980), 0.5f);
    CHECK(on.resting);
    CHECK(on.unjudged == 0);
    CHECK(on.probe_lookups == 0u);
    CHECK(on.probe_hits == 0u);
}

TEST_CASE("a cube that goes on not paying probes half as many directions each judged frame, down to 1 in 256") {
    using raycache::RestingState;
    RestingState state{true, 0, false};
    CHECK(state.probe_bits == 4u);
    // Judged from one frame's 64 probes (twice the 32 needed), 10 hits: one bit more each frame, up to 8.
    for (unsigned expected : {5u, 6u, 7u, 8u, 8u}) {
        state = raycache::next_resting_state(state, frame(1000, 10, 936), 0.5f);
        CHECK(state.resting);
        CHECK(state.probe_bits == expected);
    }
    // 63 probes judge it but do not thin its probes.
    CHECK(raycache::next_resting_state(RestingState{true, 0, false}, frame(1000, 10, 937), 0.5f).probe_bits == 4u);
    // A frame without enough probes doubles them again, down to one in 16.
    for (unsigned expected : {7u, 6u, 5u, 4u, 4u}) {
        state = raycache::next_resting_state(state, frame(1000, 0, 1000), 0.5f);
        CHECK(state.probe_bits == expected);
    }
    // A cube starting to rest probes one direction in 16.
    CHECK(raycache::next_resting_state(RestingState{}, frame(1000, 10), 0.5f).probe_bits == 4u);
}

TEST_CASE("the probes at one more bit are half of those at one bit fewer, and the bits are clamped to 4..8") {
    std::mt19937 rng(5);
    std::normal_distribution<float> gaussian;
    const int n = 400000;
    int probes[10] = {};
    for (int i = 0; i < n; ++i) {
        const glm::vec3 d = glm::normalize(glm::vec3(gaussian(rng), gaussian(rng), gaussian(rng)));
        for (unsigned bits = 4; bits <= 8; ++bits) {
            const bool probe = raycache::shared::raycache_is_probe_direction_of(d, bits);
            probes[bits] += probe ? 1 : 0;
            if (bits > 4 && probe) CHECK(raycache::shared::raycache_is_probe_direction_of(d, bits - 1)); // a subset
        }
        CHECK(raycache::shared::raycache_is_probe_direction_of(d, 0u) == raycache::is_probe_direction(d));
        CHECK(raycache::shared::raycache_is_probe_direction_of(d, 40u) == raycache::shared::raycache_is_probe_direction_of(d, 8u));
    }
    // About n / 2^bits each; the boxes are coarse (a few thousand over the sphere), so within a factor 1.6.
    for (unsigned bits = 4; bits <= 8; ++bits) {
        CAPTURE(bits);
        const double expected = static_cast<double>(n) / static_cast<double>(1u << bits);
        CHECK(probes[bits] > expected / 1.6);
        CHECK(probes[bits] < expected * 1.6);
    }
}

TEST_CASE("a wake its first judged frame proves wrong doubles the next rest (2, 4, then 8 frames), and a wake that pays resets it") {
    using raycache::RestingState;
    const CubeStatistics poor = frame(1000, 100);          // a working frame: 10 %, rests
    const CubeStatistics good = frame(1000, 500);          // a working frame: 50 %, works on
    const CubeStatistics promising = frame(1000, 40, 920); // a resting frame: its 80 probes hit 40 (0.5): wake
    // Frames a cube that woke and failed `wrong` times rests before it works again, counted by running the
    // rule; then it refills and is judged by `judged`.
    RestingState state = raycache::next_resting_state(RestingState{}, poor, 0.5f); // it worked a while, then rests
    CHECK(state.resting);
    CHECK(state.backoff == 0);
    auto rest_length = [&] {
        int frames = 0;
        while (state.resting) {
            state = raycache::next_resting_state(state, promising, 0.5f);
            ++frames;
            REQUIRE(frames < 100);
        }
        CHECK(state.refilling);
        state = raycache::next_resting_state(state, poor, 0.5f); // the refill decides nothing
        CHECK_FALSE(state.resting);
        return frames;
    };
    CHECK(rest_length() == 1); // a first rest: its probes wake it after one frame
    state = raycache::next_resting_state(state, poor, 0.5f); // the wake was wrong
    CHECK(state.backoff == 1);
    CHECK(rest_length() == 2);
    state = raycache::next_resting_state(state, poor, 0.5f);
    CHECK(rest_length() == 4);
    state = raycache::next_resting_state(state, poor, 0.5f);
    CHECK(rest_length() == 8);
    state = raycache::next_resting_state(state, poor, 0.5f);
    CHECK(state.backoff == raycache::resting_max_backoff);
    CHECK(rest_length() == 8); // no longer
    // A wake that pays: it works on, and its next rest is one frame again.
    state = raycache::next_resting_state(state, good, 0.5f);
    CHECK_FALSE(state.resting);
    CHECK(state.backoff == 0);
    state = raycache::next_resting_state(state, good, 0.5f);
    state = raycache::next_resting_state(state, poor, 0.5f);
    CHECK(state.backoff == 0);
    CHECK(rest_length() == 1);
}

TEST_CASE("a resting cube whose frames start empty counts them as unjudged and works again after 8 of them") {
    using raycache::RestingState;
    // Emptied while resting (its probes alone could refill it): those frames decide nothing, but they count
    // towards resting_max_unjudged_frames, thicken its probes back (8 -> 4 bits) and run its minimum rest
    // down, so it cannot rest unmeasured for ever.
    RestingState state{true, 0, false};
    state.probe_bits = 8u;
    state.rest_left = 3;
    const CubeStatistics probes_hit = frame(1000, 60, 920); // 80 probes, 60 hits: ignored, the cube was empty
    for (int f = 1; f < raycache::resting_max_unjudged_frames; ++f) {
        CAPTURE(f);
        state = raycache::next_resting_state(state, probes_hit, 0.5f, true);
        CHECK(state.resting);
        CHECK(state.unjudged == f);
        CHECK(state.probe_bits == static_cast<unsigned>(std::max(8 - f, 4)));
        CHECK(state.rest_left == std::max(3 - f, 0));
        CHECK(state.probe_lookups == 0u);
    }
    state = raycache::next_resting_state(state, probes_hit, 0.5f, true);
    CHECK_FALSE(state.resting);
    CHECK(state.refilling);
}

TEST_CASE("a frame the cube started empty, or refilled in after resting, decides nothing") {
    using raycache::RestingState;
    const CubeStatistics missed_all = frame(1000, 0); // a working cube's frame: no hit at all
    // Started empty: its misses say nothing; the state stays.
    CHECK_FALSE(raycache::next_resting_state(RestingState{}, missed_all, 0.5f, true).resting);
    const RestingState resting{true, 3, false};
    const RestingState kept = raycache::next_resting_state(resting, frame(1000, 10, 900), 0.5f, true);
    CHECK(kept.resting); // a resting cube keeps resting, the frame counted as one it could not judge
    CHECK(kept.unjudged == 4);
    // A resting cube whose probes hit works again, and refills first: that frame decides nothing either.
    RestingState state = raycache::next_resting_state(resting, frame(1000, 90, 900), 0.5f); // 90 % of the probes
    CHECK_FALSE(state.resting);
    CHECK(state.refilling);
    state = raycache::next_resting_state(state, missed_all, 0.5f);
    CHECK_FALSE(state.resting); // refilled, not judged
    CHECK_FALSE(state.refilling);
    state = raycache::next_resting_state(state, missed_all, 0.5f);
    CHECK(state.resting); // judged again
    CHECK_FALSE(state.refilling);
    // Resting after too many unjudged frames also ends in a refill.
    const RestingState given_up = raycache::next_resting_state(
        RestingState{true, raycache::resting_max_unjudged_frames - 1, false}, frame(1000, 0, 1000), 0.5f);
    CHECK_FALSE(given_up.resting);
    CHECK(given_up.refilling);
}

TEST_CASE("min_hit_rate 0 (or not a number) never rests a cube, whatever its hit rate") {
    CHECK_FALSE(rests(false, frame(1000, 0), 0.0f));
    CHECK_FALSE(rests(true, frame(1000, 0, 900), 0.0f));
    CHECK_FALSE(rests(false, frame(1000, 0), std::numeric_limits<float>::quiet_NaN()));
    CHECK_FALSE(rests(false, frame(1000, 0), -1.0f));
}

TEST_CASE("a resting miss has a name and a counter slot of its own") {
    CHECK(std::string(raycache::to_string(MissReason::resting)) == "resting");
    CHECK(static_cast<std::size_t>(MissReason::resting) + 1 == raycache::miss_reason_count);
    raycache::CctCube cube(8);
    cube.record_miss(MissReason::resting);
    cube.record_miss(MissReason::resting);
    cube.record_miss(MissReason::empty);
    const CubeStatistics s = cube.begin_frame();
    CHECK(s.lookups == 3);
    CHECK(s.misses == 3);
    CHECK(s.misses_by[static_cast<std::size_t>(MissReason::resting)] == 2);
    CHECK(s.miss_share(MissReason::resting) == doctest::Approx(2.0 / 3.0));
}

TEST_CASE("with reported work, a cube pays from lookup_work / (mean work of a ray that filled a texel) on, clamped") {
    using raycache::resting_threshold;
    // `reports` rays filled texels, `work` rays in all: thresholds worked out by hand.
    CHECK(resting_threshold(400, 100, 1.0f, 0.5f) == doctest::Approx(0.25)); // 4 rays a trace
    CHECK(resting_threshold(400, 100, 1.5f, 0.5f) == doctest::Approx(0.375));
    CHECK(resting_threshold(128, 64, 1.2f, 0.5f) == doctest::Approx(0.6));
    // Clamped: rays 100 times a lookup still need 5% hits; rays cheaper than a lookup 90%.
    CHECK(resting_threshold(10000, 100, 1.0f, 0.5f) == raycache::resting_threshold_floor);
    CHECK(resting_threshold(50, 100, 1.0f, 0.5f) == raycache::resting_threshold_ceiling);
    // Too few reports to tell, no report, or no lookup_work: the fallback.
    const std::uint64_t few = raycache::resting_min_judged_lookups;
    CHECK(resting_threshold(400, few - 1, 1.0f, 0.5f) == 0.5f);
    CHECK(resting_threshold(4 * few, few, 1.0f, 0.5f) == doctest::Approx(0.25));
    CHECK(resting_threshold(0, 0, 1.0f, 0.6f) == 0.6f);
    CHECK(resting_threshold(400, 100, 0.0f, 0.6f) == 0.6f);
    CHECK(resting_threshold(400, 100, std::numeric_limits<float>::quiet_NaN(), 0.6f) == 0.6f);
}

TEST_CASE("a cube counts the work the rays that filled its texels report, and not a ray that reported none") {
    raycache::CctCube cube(8);
    cube.record_filled_work(3);
    cube.record_filled_work(0);
    cube.record_filled_work(5);
    const CubeStatistics s = cube.statistics();
    CHECK(s.filled_work == 8);
    CHECK(s.work_reports == 2);
    CHECK(s.mean_filled_work() == doctest::Approx(4.0));
    CHECK(CubeStatistics{}.mean_filled_work() == 0.0);
}
