// raycache/gpu_resting.hpp and the frame buffer's resting words (raycache/gpu_frame.hpp), against values
// worked out by hand from the rule written in raycache/resting.hpp:
// - the start words put cube k's resting word in word 8 + 55 k + 5 and 0 elsewhere among the counters;
// - a frame's rested rays are misses of reason `resting`, beside the lookups' own misses, so that the
//   looked-up rays are hits + misses of lookups alone;
// - with min_hit_rate 0.5: a cube's first frame (started empty) decides nothing whatever it hit; 10 hits of
//   100 looked up then rest it; a resting frame whose 40 probes hit 30 times (0.75) makes it work again, and
//   the frame after that (refilling) decides nothing even at 0 hits; frames without probes decide nothing
//   for 7 frames and the 8th such frame makes it work again; a wake whose first judged frame rests the cube
//   again counts as wrong (backoff); a resting cube judged from 64 probes of one frame probes half as many
//   directions the next (resting word one higher).
#include <doctest/doctest.h>

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "raycache/gpu_adaptive.hpp"
#include "raycache/gpu_resting.hpp"

using namespace raycache;

namespace {

// A frame buffer read back with these counters for cube k (hits, misses of lookups, stores, rays rested).
struct FrameWords {
    explicit FrameWords(std::uint32_t cubes) : layout(gpu_frame_layout(cubes, 4)), words(gpu_frame_start_words(layout)) {}
    FrameWords& cube(std::uint32_t k, std::uint32_t hits, std::uint32_t misses, std::uint32_t stores, std::uint32_t rested = 0) {
        words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_HITS)] = hits;
        words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_MISSES)] = misses;
        words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_STORES)] = stores;
        words[shared::raycache_frame_counter_word(k, RAYCACHE_FRAME_RESTED)] = rested;
        return *this;
    }
    GpuFrameStatistics read() const { return read_gpu_statistics(words.data(), layout); }
    GpuFrameLayout layout;
    std::vector<std::uint32_t> words;
};

} // namespace

TEST_CASE("the start words carry each cube's resting word, and refuse another number of words") {
    const GpuFrameLayout f = gpu_frame_layout(3, 10);
    const std::vector<std::uint32_t> w = gpu_frame_start_words(f, true, {4u, 0u, 7u});
    REQUIRE(w.size() == 8u + 3u * 55u);
    for (std::size_t i = 8; i < w.size(); ++i) {
        const std::uint32_t expected = i == 8 + 5 ? 4u : i == 8 + 2 * 55 + 5 ? 7u : 0u; // cubes 0 and 2
        CHECK(w[i] == expected);
    }
    const std::vector<std::uint32_t> none = gpu_frame_start_words(f, true, {0u, 0u, 0u});
    for (std::uint32_t k = 0; k < 3; ++k) CHECK(none[8 + 55 * k + 5] == 0u);
    CHECK_THROWS_AS(gpu_frame_start_words(f, true, {4u, 0u}), std::invalid_argument);
}

TEST_CASE("GPU statistics count a resting cube's rays as misses of reason resting, apart from its lookups") {
    FrameWords frame(2);
    frame.cube(0, 30, 10, 4, 600).cube(1, 5, 5, 5, 0);
    frame.words[shared::raycache_frame_counter_word(0, RAYCACHE_FRAME_RESTING)] = 1u;
    const GpuFrameStatistics s = frame.read();
    CHECK(s.resting == std::vector<bool>{true, false});
    CHECK(s.cubes[0].lookups == 640u);
    CHECK(s.cubes[0].misses == 610u);
    CHECK(s.cubes[0].misses_by[static_cast<std::size_t>(MissReason::resting)] == 600u);
    CHECK(s.cubes[0].looked_up() == 40u);
    CHECK(s.cubes[1].looked_up() == 10u);
    CHECK(s.total.lookups == 650u);
    CHECK(s.total.misses_by[static_cast<std::size_t>(MissReason::resting)] == 600u);
    CHECK(s.total.looked_up() == 50u);
}

TEST_CASE("GpuResting: a cube rests after a frame that answered too few, works again when its probes answer, as the rule says") {
    GpuResting resting(2, 0.5f);
    CHECK(resting.resting() == std::vector<bool>{false, false});
    // Frame 1: both cubes started empty: nothing decided, though cube 0 hit nothing.
    resting.after_frame(FrameWords(2).cube(0, 0, 100, 100).cube(1, 0, 100, 100).read());
    CHECK(resting.resting_count() == 0u);
    // Frame 2: cube 0 answers 10 of 100 (rests), cube 1 60 of 100 (works).
    resting.after_frame(FrameWords(2).cube(0, 10, 90, 90).cube(1, 60, 40, 40).read());
    CHECK(resting.resting() == std::vector<bool>{true, false});
    // Frame 3: cube 0's 40 probes hit 30 (0.75 >= 0.5): it works again, and refills first.
    resting.after_frame(FrameWords(2).cube(0, 30, 10, 10, 560).cube(1, 60, 40, 40).read());
    CHECK(resting.resting() == std::vector<bool>{false, false});
    CHECK(resting.state(0).refilling);
    // Frame 4, the refill: nothing decided even at 0 hits.
    resting.after_frame(FrameWords(2).cube(0, 0, 100, 100).cube(1, 60, 40, 40).read());
    CHECK(resting.resting() == std::vector<bool>{false, false});
    // Frame 5: 10 of 100 again: rests, probing one direction in 16 (word 4); its wake was wrong, so it rests
    // at least 2 frames. Then frames without a probe (unjudged) keep it resting, at word 4 (probes already
    // at their most), and the 8th makes it work.
    resting.after_frame(FrameWords(2).cube(0, 10, 90, 90).cube(1, 60, 40, 40).read());
    CHECK(resting.resting_words() == std::vector<std::uint32_t>{4u, 0u});
    CHECK(resting.state(0).backoff == 1);
    for (int f = 1; f <= resting_max_unjudged_frames; ++f) {
        CAPTURE(f);
        resting.after_frame(FrameWords(2).cube(0, 0, 0, 0, 500).cube(1, 60, 40, 40).read());
        CHECK(resting.resting()[0] == (f < resting_max_unjudged_frames));
        if (f < resting_max_unjudged_frames) CHECK(resting.resting_words()[0] == 4u);
    }
    // Frame 14: the refill. Frame 15: 5 of 100 (a wrong wake again: backoff 2). Frames 16 to 18: its
    // 64 probes find 8 hits each: it rests on, probing half as many directions each frame (words 5, 6, 7).
    resting.after_frame(FrameWords(2).cube(0, 0, 100, 100).cube(1, 60, 40, 40).read());
    resting.after_frame(FrameWords(2).cube(0, 5, 95, 95).cube(1, 60, 40, 40).read());
    CHECK(resting.state(0).backoff == 2);
    for (std::uint32_t word : {5u, 6u, 7u}) {
        resting.after_frame(FrameWords(2).cube(0, 8, 56, 56, 900).cube(1, 60, 40, 40).read());
        CHECK(resting.resting_words() == std::vector<std::uint32_t>{word, 0u});
    }
    CHECK_THROWS_AS(resting.after_frame(FrameWords(3).read()), std::invalid_argument);
}

TEST_CASE("GpuResting: a cube that grew, or was cleared, starts empty, so its next frame decides nothing, and a loaded one works") {
    GpuResting resting(2, 0.5f);
    resting.after_frame(FrameWords(2).cube(0, 0, 100, 100).cube(1, 0, 100, 100).read()); // both now hold texels
    const GpuBufferLayout from = gpu_buffer_layout<CctTexel>({GpuCubeShape{16, {}}, GpuCubeShape{16, {}}});
    const GpuBufferLayout to = gpu_buffer_layout<CctTexel>({GpuCubeShape{32, {}}, GpuCubeShape{8, {}}});
    resting.resized(from, to); // cube 0 grew (empty), cube 1 shrank (resampled: holds texels)
    resting.after_frame(FrameWords(2).cube(0, 0, 100, 100).cube(1, 0, 100, 100).read());
    CHECK(resting.resting() == std::vector<bool>{false, true});
    resting.restart(1, false); // cleared: it works again, and its next frame, started empty, decides nothing
    CHECK(resting.resting() == std::vector<bool>{false, false});
    resting.after_frame(FrameWords(2).cube(0, 90, 10, 10).cube(1, 0, 100, 100).read());
    CHECK(resting.resting() == std::vector<bool>{false, false});
    resting.restart(0, true); // loaded from a cache file with texels: it works, and its next frame decides
    resting.after_frame(FrameWords(2).cube(0, 0, 100, 100).cube(1, 0, 100, 100).read());
    CHECK(resting.resting() == std::vector<bool>{true, true});
    const GpuBufferLayout three = gpu_buffer_layout<CctTexel>({GpuCubeShape{16, {}}, GpuCubeShape{16, {}}, GpuCubeShape{16, {}}});
    CHECK_THROWS_AS(resting.resized(from, three), std::invalid_argument);
    CHECK_THROWS_AS(resting.resized(three, three), std::invalid_argument); // index 2 is not one of its cubes
    CHECK_THROWS_AS(resting.restart(2, true), std::out_of_range);
}

TEST_CASE("GpuResting: min_hit_rate 0 never rests a cube, and a negative or NaN one is refused") {
    GpuResting never(1, 0.0f);
    for (int f = 0; f < 3; ++f) never.after_frame(FrameWords(1).cube(0, 0, 100, 100).read());
    CHECK(never.resting_count() == 0u);
    CHECK_THROWS_AS(GpuResting(1, -0.1f), std::invalid_argument);
    CHECK_THROWS_AS(GpuResting(1, std::numeric_limits<float>::quiet_NaN()), std::invalid_argument);
}

TEST_CASE("a GPU cube that rested keeps its face size: its cells are its probes' alone") {
    const GpuBufferLayout layout = gpu_buffer_layout<CctTexel>({GpuCubeShape{256, {}}, GpuCubeShape{256, {}}});
    std::vector<bool> sized(2, true);
    FrameWords frame(2);
    frame.cube(0, 50, 50, 50, 1500).cube(1, 50, 50, 50, 1500); // the same counts, only cube 0 rested
    frame.words[shared::raycache_frame_counter_word(0, RAYCACHE_FRAME_RESTING)] = 1u;
    for (std::uint32_t w = 0; w < RAYCACHE_COVERAGE_WORDS; ++w)
        frame.words[shared::raycache_frame_coverage_word(0, w)] = frame.words[shared::raycache_frame_coverage_word(1, w)] = 0xFFFFFFFFu;
    const GpuFaceSizes next = next_gpu_face_sizes<CctTexel>(AdaptiveResolution{}, layout, frame.read(), sized, 1u << 30);
    CHECK(next.face_sizes[0] == 256);
    CHECK(next.face_sizes[1] <= 32); // 1600 rays over every cell: about 270 texels a face at one ray a texel
}
