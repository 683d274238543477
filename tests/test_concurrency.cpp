// Many threads on one cube (the library's guarantee: any number of threads may look up and store into one
// cube at once, free of data races). Runs under ThreadSanitizer in CI (CTest label "concurrency"); sized
// to take a few seconds there on two cores.
//
// What the frame rule promises (cache_cube.hpp) and these tests check under real contention:
//  - the cube's content after a frame does not depend on how the stores were split over threads or ordered;
//  - a lookup never sees a value stored in the same frame;
//  - the counters add up exactly to the operations issued.
#include <doctest/doctest.h>

#include "test_random.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <optional>
#include <thread>
#include <type_traits>
#include <vector>

#include "raycache/invalidation.hpp"
#include "raycache/raycache.hpp"
#include "test_bits.hpp"

namespace {

using raycache::CctCube;
using raycache::CctTexel;
using raycache::CubeStatistics;
using raycache::TexelAddress;

constexpr int face_size = 64;
constexpr int texel_count = 6 * face_size * face_size;
constexpr int thread_count = 4;

// The direction through the centre of texel (face, column, row), from the spec's face table:
// sc = 2 (column + 0.5) / N - 1 is t'u / |m|, tc likewise t'v / |m|, with |m| = 1.
glm::vec3 centre_direction(int face, int column, int row) {
    const float sc = 2.0f * (static_cast<float>(column) + 0.5f) / face_size - 1.0f;
    const float tc = 2.0f * (static_cast<float>(row) + 0.5f) / face_size - 1.0f;
    switch (face) {
    case 0: return glm::vec3(1.0f, -tc, -sc);  // +X: t'u = -z, t'v = -y
    case 1: return glm::vec3(-1.0f, -tc, sc);  // -X: t'u = +z, t'v = -y
    case 2: return glm::vec3(sc, 1.0f, tc);    // +Y: t'u = +x, t'v = +z
    case 3: return glm::vec3(sc, -1.0f, -tc);  // -Y: t'u = +x, t'v = -z
    case 4: return glm::vec3(sc, -tc, 1.0f);   // +Z: t'u = +x, t'v = -y
    default: return glm::vec3(-sc, -tc, -1.0f); // -Z: t'u = -x, t'v = -y
    }
}

TexelAddress address_of(int linear) {
    return TexelAddress{linear / (face_size * face_size), linear % face_size, (linear / face_size) % face_size};
}

// Runs body(thread_index) on `threads` threads that start together.
void run_threads(int threads, const std::function<void(int)>& body) {
    std::atomic<int> ready{0};
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) {
        pool.emplace_back([&, t] {
            ready.fetch_add(1);
            while (ready.load() < threads) std::this_thread::yield();
            body(t);
        });
    }
    for (std::thread& th : pool) th.join();
}

// Every texel's content as a word (CctTexel::invalid when empty), read with load().
std::vector<std::uint32_t> snapshot(const CctCube& cube) {
    std::vector<std::uint32_t> words(texel_count, CctTexel::invalid);
    for (int i = 0; i < texel_count; ++i)
        if (const std::optional<glm::vec3> v = cube.load(address_of(i))) words[i] = CctTexel::encode(*v);
    return words;
}

struct StoreItem {
    glm::vec3 direction;
    glm::vec3 colour;
};

std::vector<StoreItem> make_store_list(int count) {
    Lcg rng{2024};
    std::vector<StoreItem> items;
    items.reserve(static_cast<std::size_t>(count));
    while (static_cast<int>(items.size()) < count) {
        const glm::vec3 d(rng.signed_uniform(), rng.signed_uniform(), rng.signed_uniform());
        if (std::max(std::fabs(d.x), std::max(std::fabs(d.y), std::fabs(d.z))) < 1e-3f) continue;
        const float scale = std::ldexp(1.0f, static_cast<int>(rng.next() % 16u) - 5);
        const glm::vec3 colour = glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * scale;
        items.push_back(StoreItem{d, colour});
    }
    return items;
}

// One cold frame of stores (each followed by a lookup of another item's direction), split over threads
// by `order(thread, threads, n)`, which lists the item indices that thread handles, in its order.
struct FrameResult {
    std::vector<std::uint32_t> content;
    CubeStatistics frame;
    std::uint64_t lookups_issued = 0;
    std::uint64_t same_frame_hits = 0;
    std::uint64_t stores_issued = 0;
};

using Order = std::function<std::vector<int>(int thread, int threads, int n)>;

FrameResult store_frame(const std::vector<StoreItem>& items, int threads, const Order& order) {
    CctCube cube(face_size);
    const int n = static_cast<int>(items.size());
    std::vector<std::uint64_t> lookups(threads, 0), hits(threads, 0), stores(threads, 0);
    run_threads(threads, [&](int t) {
        for (int i : order(t, threads, n)) {
            cube.store(items[i].direction, items[i].colour);
            ++stores[t];
            if (cube.lookup(items[(i * 7 + 3) % n].direction)) ++hits[t];
            ++lookups[t];
        }
    });
    FrameResult result;
    for (int t = 0; t < threads; ++t) {
        result.lookups_issued += lookups[t];
        result.same_frame_hits += hits[t];
        result.stores_issued += stores[t];
    }
    result.frame = cube.begin_frame();
    result.content = snapshot(cube);
    return result;
}

std::vector<int> in_order(int, int, int n) {
    std::vector<int> all(n);
    for (int i = 0; i < n; ++i) all[i] = i;
    return all;
}

std::vector<int> interleaved(int t, int threads, int n) {
    std::vector<int> mine;
    for (int i = t; i < n; i += threads) mine.push_back(i);
    return mine;
}

std::vector<int> reversed_chunks(int t, int threads, int n) {
    // Thread t takes chunk (threads - 1 - t) and walks it backwards.
    const int chunk = (n + threads - 1) / threads;
    const int begin = (threads - 1 - t) * chunk;
    const int end = std::min(n, begin + chunk);
    std::vector<int> mine;
    for (int i = end - 1; i >= begin; --i) mine.push_back(i);
    return mine;
}

// A pure function of the direction's ray (the same for d and 2^k d): a colour spanning several exponents.
glm::vec3 trace_colour(const glm::vec3& d) {
    const float m = std::max(std::fabs(d.x), std::max(std::fabs(d.y), std::fabs(d.z)));
    const glm::vec3 u = d / m; // exact for power-of-two scalings of d
    const float brightness = std::ldexp(1.0f, static_cast<int>(std::floor((u.x + 1.0f) * 6.0f)) - 4);
    return brightness * glm::vec3(0.25f + 0.75f * u.y * u.y, 0.5f + 0.5f * u.z, 1.0f / (1.0f + u.x * u.x));
}

} // namespace

TEST_CASE("a frame's stores give the same cube whether made by 1 thread or split over 4") {
    const std::vector<StoreItem> items = make_store_list(60000); // about 2.4 stores per texel of N = 64
    const FrameResult one = store_frame(items, 1, in_order);
    const FrameResult interleaved4 = store_frame(items, thread_count, interleaved);
    const FrameResult reversed4 = store_frame(items, thread_count, reversed_chunks);

    std::size_t filled = 0;
    for (std::uint32_t w : one.content) filled += CctTexel::is_valid(w) ? 1u : 0u;
    CHECK(filled > static_cast<std::size_t>(texel_count) / 2);
    CHECK(one.frame.valid_texels == filled);

    std::size_t differ_interleaved = 0, differ_reversed = 0;
    for (int i = 0; i < texel_count; ++i) {
        differ_interleaved += one.content[i] != interleaved4.content[i] ? 1u : 0u;
        differ_reversed += one.content[i] != reversed4.content[i] ? 1u : 0u;
    }
    CHECK(differ_interleaved == 0u);
    CHECK(differ_reversed == 0u);
    CHECK(interleaved4.frame.valid_texels == filled);
    CHECK(reversed4.frame.valid_texels == filled);

    { // Each texel holds the smallest word stored into it.
        std::vector<std::uint32_t> smallest(texel_count, CctTexel::invalid);
        std::size_t no_texel = 0;
        for (const StoreItem& item : items) {
            const std::optional<TexelAddress> t = raycache::texel_of(item.direction, face_size);
            if (!t) {
                ++no_texel;
                continue;
            }
            const std::size_t i = raycache::texel_linear_index(*t, face_size);
            smallest[i] = std::min(smallest[i], CctTexel::encode(item.colour));
        }
        std::size_t differ = 0;
        for (int i = 0; i < texel_count; ++i) differ += smallest[i] != one.content[i] ? 1u : 0u;
        CHECK(no_texel == 0u);
        CHECK(differ == 0u);
    }
    { // Every run's counters add up to the operations it issued.
        for (const FrameResult* r : {&one, &interleaved4, &reversed4}) {
            CHECK(r->stores_issued == items.size());
            CHECK(r->frame.stores + r->frame.refused_stores == r->stores_issued);
            CHECK(r->frame.stores >= filled);
            CHECK(r->lookups_issued == items.size());
            CHECK(r->frame.lookups == r->lookups_issued);
            CHECK(r->frame.hits + r->frame.misses == r->lookups_issued);
            // A cold frame: nothing stored in it is visible to its lookups.
            CHECK(r->same_frame_hits == 0u);
            CHECK(r->frame.hits == 0u);
        }
    }
}

TEST_CASE("concurrent lookups never see a value stored in the same frame, and the counters add up exactly") {
    CctCube cube(face_size);
    const glm::vec3 old_colour(1.0f);          // word 0x84020100
    const glm::vec3 new_colour(0.25f, 0, 0);    // word 0x70000100: smaller, yet it must not replace a visible texel
    // Frame 0: every even texel gets old_colour.
    int refused = 0;
    for (int i = 0; i < texel_count; i += 2) refused += cube.store_at(address_of(i), old_colour) ? 0 : 1;
    REQUIRE(refused == 0);
    cube.begin_frame();
    REQUIRE(cube.valid_texels() == static_cast<std::size_t>(texel_count / 2));

    // Frame 1: two writers store new_colour everywhere (forwards and backwards); two readers look up every
    // texel, pass after pass, while the writers run.
    std::atomic<int> writers_left{2};
    std::uint64_t lookups[2] = {0, 0}, hits[2] = {0, 0}, expected_hits[2] = {0, 0};
    std::uint64_t wrong[2] = {0, 0}, store_calls[2] = {0, 0};
    run_threads(4, [&](int t) {
        if (t < 2) {
            for (int k = 0; k < texel_count; ++k) {
                const int i = t == 0 ? k : texel_count - 1 - k;
                const TexelAddress a = address_of(i);
                cube.store(centre_direction(a.face, a.column, a.row), new_colour);
                ++store_calls[t];
            }
            writers_left.fetch_sub(1);
            return;
        }
        const int r = t - 2;
        for (int pass = 0; pass < 12 && (pass < 2 || writers_left.load() > 0); ++pass) {
            for (int k = 0; k < texel_count; ++k) {
                const int i = r == 0 ? k : texel_count - 1 - k;
                const TexelAddress a = address_of(i);
                const std::optional<glm::vec3> v = cube.lookup(centre_direction(a.face, a.column, a.row));
                ++lookups[r];
                if (v) ++hits[r];
                if (i % 2 == 0) {
                    ++expected_hits[r];
                    if (!v || !same_bits(*v, old_colour)) ++wrong[r];
                } else if (v) {
                    ++wrong[r]; // a value stored this frame was visible
                }
            }
        }
    });
    CHECK(wrong[0] + wrong[1] == 0u);
    const CubeStatistics frame = cube.begin_frame();
    CHECK(frame.lookups == lookups[0] + lookups[1]);
    CHECK(frame.hits == hits[0] + hits[1]);
    CHECK(frame.hits == expected_hits[0] + expected_hits[1]);
    CHECK(frame.misses == frame.lookups - frame.hits);
    // Odd texels: the first writer to arrive stores, the second writes an equal word and is refused.
    // Even texels: visible, so both writers are refused.
    CHECK(frame.stores == static_cast<std::uint64_t>(texel_count / 2));
    CHECK(frame.refused_stores == store_calls[0] + store_calls[1] - texel_count / 2);
    CHECK(frame.valid_texels == static_cast<std::size_t>(texel_count));

    // Frame 2: every texel visible, old colour on even texels, new on odd, seen alike by 4 threads.
    std::uint64_t wrong2[4] = {0, 0, 0, 0};
    run_threads(4, [&](int t) {
        for (int k = 0; k < texel_count; ++k) {
            const int i = (k * 4 + t) % texel_count;
            const TexelAddress a = address_of(i);
            const std::optional<glm::vec3> v = cube.lookup(centre_direction(a.face, a.column, a.row));
            if (!v || !same_bits(*v, i % 2 == 0 ? old_colour : new_colour)) ++wrong2[t];
        }
    });
    CHECK(wrong2[0] + wrong2[1] + wrong2[2] + wrong2[3] == 0u);
    const CubeStatistics frame2 = cube.statistics();
    CHECK(frame2.hits == static_cast<std::uint64_t>(4 * texel_count));
    CHECK(frame2.misses == 0u);
}

TEST_CASE("cached_trace from many threads: a cold frame returns trace's exact values, a warm one values within the bound") {
    CctCube cube(face_size);
    // Every third texel, each reached by 4 scalings of its centre direction (powers of two, so the ray and
    // hence trace_colour are the same for all four).
    // The colours are computed once, so that trace and the check read the very same floats.
    struct Call {
        glm::vec3 direction;
        glm::vec3 colour;
    };
    std::vector<Call> calls;
    int texels_used = 0;
    for (int i = 0; i < texel_count; i += 3, ++texels_used) {
        const TexelAddress a = address_of(i);
        const glm::vec3 d = centre_direction(a.face, a.column, a.row);
        for (float s : {1.0f, 2.0f, 0.5f, 4.0f}) calls.push_back(Call{d * s, trace_colour(d * s)});
    }
    const int n = static_cast<int>(calls.size());
    std::atomic<std::uint64_t> traces{0};
    auto frame = [&](std::uint64_t* mismatches, bool cold) {
        run_threads(thread_count, [&](int t) {
            for (int k = 0; k < n; ++k) {
                // Each thread walks every call, starting at a different place; odd threads go backwards.
                const int j = (t % 2 == 0 ? k : n - 1 - k);
                const Call& call = calls[(j + t * (n / thread_count)) % n];
                const glm::vec3 got = raycache::cached_trace(cube, call.direction, [&] {
                    traces.fetch_add(1, std::memory_order_relaxed);
                    return call.colour;
                });
                const glm::vec3& want = call.colour;
                if (cold) {
                    if (!same_bits(got, want)) ++mismatches[t];
                } else {
                    // Documented bound: 2^-9 of the brightest channel (or 2^-25 absolute below 2^-16).
                    const float brightest = std::max(want.x, std::max(want.y, want.z));
                    const float bound = std::max(brightest * (1.0f / 512.0f), std::ldexp(1.0f, -25));
                    for (int c = 0; c < 3; ++c)
                        if (!(std::fabs(got[c] - want[c]) <= bound)) {
                            ++mismatches[t];
                            break;
                        }
                }
            }
        });
    };

    std::uint64_t cold_mismatches[thread_count] = {};
    frame(cold_mismatches, true);
    std::uint64_t total = 0;
    for (std::uint64_t m : cold_mismatches) total += m;
    CHECK(total == 0u);
    const std::uint64_t calls_per_frame = static_cast<std::uint64_t>(thread_count) * static_cast<std::uint64_t>(n);
    CHECK(traces.load() == calls_per_frame);
    const CubeStatistics cold = cube.begin_frame();
    CHECK(cold.misses == calls_per_frame);
    CHECK(cold.hits == 0u);
    // Every call into a texel stores the same word: the first one wins, the rest are refused as equal.
    CHECK(cold.stores == static_cast<std::uint64_t>(texels_used));
    CHECK(cold.refused_stores == calls_per_frame - static_cast<std::uint64_t>(texels_used));
    CHECK(cold.valid_texels == static_cast<std::size_t>(texels_used));

    traces.store(0);
    std::uint64_t warm_mismatches[thread_count] = {};
    frame(warm_mismatches, false);
    total = 0;
    for (std::uint64_t m : warm_mismatches) total += m;
    CHECK(total == 0u);
    CHECK(traces.load() == 0u);
    const CubeStatistics warm = cube.begin_frame();
    CHECK(warm.hits == calls_per_frame);
    CHECK(warm.misses == 0u);
    CHECK(warm.stores + warm.refused_stores == 0u);
}

TEST_CASE("cubes sharing a budget never exceed it under random concurrent stores, and lose no stored tile") {
    // Three cubes of 64 x 64 faces (16 tiles a face, 288 tiles in all) on a budget that holds about a third
    // of their tiles; four threads store random texels into random cubes while a fifth watches the budget.
    using raycache::MemoryBudget;
    constexpr int cubes_n = 3;
    const std::size_t tables = cubes_n * CctCube::fixed_bytes(face_size); // each cube's table, bitmaps and counters
    const std::size_t limit = tables + 100 * CctCube::tile_bytes() + CctCube::tile_bytes() / 2;
    auto budget = std::make_shared<MemoryBudget>(limit);
    std::vector<std::unique_ptr<CctCube>> cubes;
    for (int c = 0; c < cubes_n; ++c) cubes.push_back(std::make_unique<CctCube>(face_size, budget));
    std::atomic<bool> done{false};
    std::atomic<std::size_t> worst{0};
    std::thread watcher([&] {
        while (!done.load()) {
            const std::size_t used = budget->used();
            if (used > worst.load()) worst.store(used);
        }
    });
    std::atomic<std::uint64_t> accepted{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < thread_count; ++t)
        threads.emplace_back([&, t] {
            Lcg random{0x5eed0000u + static_cast<std::uint64_t>(t)};
            for (int i = 0; i < 20000; ++i) {
                CctCube& cube = *cubes[random.next() % cubes_n];
                const TexelAddress texel{static_cast<int>(random.next() % 6), static_cast<int>(random.next() % face_size),
                                         static_cast<int>(random.next() % face_size)};
                if (cube.store_at(texel, glm::vec3(random.uniform()))) accepted.fetch_add(1);
            }
        });
    for (std::thread& th : threads) th.join();
    done.store(true);
    watcher.join();
    CHECK(worst.load() <= limit);
    CHECK(budget->used() <= limit);
    std::size_t tiles = 0, valid = 0;
    for (const auto& cube : cubes) {
        tiles += cube->allocated_tiles();
        valid += cube->valid_texels();
    }
    CHECK(tiles == 100u); // the budget's whole room, and not a tile more
    CHECK(budget->used() == tables + tiles * CctCube::tile_bytes());
    // Every accepted store is in a tile that stayed: the valid texels are the distinct texels accepted,
    // and each can be loaded back.
    std::size_t loadable = 0;
    for (const auto& cube : cubes) cube->for_each_valid_texel([&](const TexelAddress& t) { loadable += cube->load(t).has_value(); });
    CHECK(loadable == valid);
    CHECK(valid <= accepted.load());
    cubes.clear();
    CHECK(budget->used() == 0u);
}

TEST_CASE("stores with path records from 4 threads, then exact invalidation between frames on 4 threads: the same texels survive as with 1 thread") {
    // Each store's path hit the object numbered by its direction's face at a point along its direction;
    // object 3 then moves. Concurrent record merging (atomic or, min, max) must give tiles the same records, so the
    // pass, which reads only those and the texels, empties the same texels; and the pass, its runs of tiles
    // spread over the same threads, must empty them with the same counts.
    const std::vector<StoreItem> items = make_store_list(40000);
    std::size_t tiles = 0;
    auto build = [&](int threads) {
        auto cube = std::make_unique<raycache::CctCube>(face_size);
        run_threads(threads, [&](int t) {
            for (std::size_t i = static_cast<std::size_t>(t); i < items.size(); i += static_cast<std::size_t>(threads)) {
                raycache::PathRecord path;
                path.hit(static_cast<std::uint64_t>(raycache::shared::raycache_face_of(items[i].direction)),
                         4.0f * glm::normalize(items[i].direction));
                path.lit = i % 3 == 0;
                cube->store(items[i].direction, items[i].colour, path);
            }
        });
        cube->begin_frame();
        raycache::SceneChanges changes;
        changes.moved.push_back({3, {glm::vec3(3.0f, 0.5f, 0.0f), 0.4f}, {glm::vec3(3.0f, 0.8f, 0.2f), 0.4f}});
        changes.lights.push_back(glm::vec3(0.0f, 8.0f, 0.0f));
        auto parallel_for = [threads](std::size_t count, const std::function<void(std::size_t)>& f) {
            run_threads(threads, [&](int t) {
                for (std::size_t i = static_cast<std::size_t>(t); i < count; i += static_cast<std::size_t>(threads)) f(i);
            });
        };
        const raycache::InvalidationCounts counts =
            raycache::invalidate_changes(*cube, {{glm::vec3(0.0f), 1.0f}, 0.1f}, changes, parallel_for);
        tiles = cube->allocated_tiles();
        std::vector<std::uint32_t> content(static_cast<std::size_t>(texel_count));
        cube->for_each_valid_texel([&](const TexelAddress& a) {
            content[raycache::texel_linear_index(a, face_size)] = CctTexel::encode(*cube->load(a));
        });
        return std::make_pair(counts, content);
    };
    const auto one = build(1);
    const auto four = build(thread_count);
    CHECK(one.first.dropped > 0);
    CHECK(one.first.dropped < one.first.valid_before);
    CHECK(one.first.dropped == four.first.dropped);
    CHECK(one.first.blocks_by_path == four.first.blocks_by_path);
    CHECK(one.first.blocks_by_texel == four.first.blocks_by_texel);
    CHECK(one.first.dropped_by_path == four.first.dropped_by_path);
    CHECK(one.first.dropped_by_cone == four.first.dropped_by_cone);
    CHECK(one.first.blocks == four.first.blocks); // the same tiles' blocks read
    CHECK(tiles > 4 * 16);                        // more than four runs of tiles to share
    CHECK(one.second == four.second);
}

TEST_CASE("the passes of two cubes, their runs dealt from one list to 4 threads in reverse, empty what each cube's serial invalidation empties") {
    // As SceneCache spreads every cube's runs over its threads at once: the CCT cube above and a CDCT cube
    // filled from the same store list; object 3 moves. Expected: the texels and counts of invalidate_changes()
    // on one thread, cube by cube.
    const std::vector<StoreItem> items = make_store_list(40000);
    const raycache::CubeBounds bounds{glm::vec3(0.0f), 1.0f};
    const raycache::ReliefParameters relief{};
    auto fill = [&](auto& cube) {
        for (const StoreItem& item : items) {
            raycache::PathRecord path;
            path.hit(static_cast<std::uint64_t>(raycache::shared::raycache_face_of(item.direction)), 4.0f * glm::normalize(item.direction));
            path.lit = true;
            if constexpr (std::is_same_v<std::decay_t<decltype(cube)>, raycache::CdctCube>)
                cube.store(item.direction, raycache::DepthSample{item.colour, 4.0f}, path);
            else
                cube.store(item.direction, item.colour, path);
        }
        cube.begin_frame();
    };
    raycache::SceneChanges changes;
    changes.moved.push_back({3, {glm::vec3(3.0f, 0.5f, 0.0f), 0.4f}, {glm::vec3(3.0f, 0.8f, 0.2f), 0.4f}});
    changes.lights.push_back(glm::vec3(0.0f, 8.0f, 0.0f));
    auto contents = [&](const auto& cube) {
        std::vector<std::uint64_t> content(static_cast<std::size_t>(texel_count));
        cube.for_each_valid_texel([&](const TexelAddress& a) { content[raycache::texel_linear_index(a, face_size)] = 1u + cube.load_word(a); });
        return content;
    };
    raycache::CctCube cct_serial(face_size), cct_pooled(face_size);
    raycache::CdctCube cdct_serial(face_size), cdct_pooled(face_size);
    fill(cct_serial), fill(cct_pooled), fill(cdct_serial), fill(cdct_pooled);
    const raycache::CubeRays cct_rays{bounds, 0.1f};
    const raycache::InvalidationCounts cct_expected = raycache::invalidate_changes(cct_serial, cct_rays, changes);
    const raycache::InvalidationCounts cdct_expected = raycache::invalidate_changes(cdct_serial, bounds, relief, changes);

    std::vector<std::unique_ptr<raycache::InvalidationPass>> passes;
    passes.push_back(raycache::make_invalidation_pass(cct_pooled, cct_rays, changes));
    passes.push_back(raycache::make_invalidation_pass(cdct_pooled, raycache::CubeRays{bounds}, relief, changes));
    std::vector<std::pair<std::size_t, std::size_t>> runs;
    for (std::size_t p = 0; p < passes.size(); ++p)
        for (std::size_t r = 0; r < passes[p]->runs(); ++r) runs.emplace_back(p, r);
    REQUIRE(passes[0]->runs() > 4);
    REQUIRE(passes[1]->runs() > 4);
    std::reverse(runs.begin(), runs.end());
    run_threads(thread_count, [&](int t) {
        for (std::size_t i = static_cast<std::size_t>(t); i < runs.size(); i += static_cast<std::size_t>(thread_count))
            passes[runs[i].first]->run(runs[i].second);
    });
    const raycache::InvalidationCounts got[2] = {passes[0]->finish(), passes[1]->finish()};
    const raycache::InvalidationCounts expected[2] = {cct_expected, cdct_expected};
    for (int k = 0; k < 2; ++k) {
        CAPTURE(k);
        CHECK(expected[k].dropped > 0);
        CHECK(expected[k].dropped < expected[k].valid_before);
        CHECK(got[k].valid_before == expected[k].valid_before);
        CHECK(got[k].dropped == expected[k].dropped);
        CHECK(got[k].dropped_by_path == expected[k].dropped_by_path);
        CHECK(got[k].dropped_by_cone == expected[k].dropped_by_cone);
        CHECK(got[k].blocks == expected[k].blocks);
        CHECK(got[k].blocks_by_path == expected[k].blocks_by_path);
        CHECK(got[k].blocks_by_texel == expected[k].blocks_by_texel);
    }
    CHECK(contents(cct_pooled) == contents(cct_serial));
    CHECK(contents(cdct_pooled) == contents(cdct_serial));
}

TEST_CASE("the confidence test spread over bands on 4 threads marks exactly the pairs a brute-force pass over every texel finds") {
    // Frame A fills random texels, frame B fills some of the rest; then B's stores are tested band by band,
    // bands dealt round-robin to 4 threads, each walking its bands in reverse. Expected: a texel is marked
    // iff a filled neighbour on its face (left, right, up, down) differs by more than the threshold and one
    // of the two was stored in B (A's pairs are not tested: the test runs for B's stores only). Grey levels
    // 0.5 and 0.52 differ by less than the threshold 0.1, either and 0.9 by more (rgb9e5 keeps them within
    // 0.002).
    constexpr int n = 40; // tile rows of 16, 16 and 8 texels
    const float levels[3] = {0.5f, 0.52f, 0.9f};
    std::vector<int> level(static_cast<std::size_t>(6 * n * n), -1), frame(level.size(), -1);
    CctCube cube(n);
    Lcg rng{7};
    for (int f = 0; f < 2; ++f) {
        for (int i = 0; i < 6 * n * n; ++i) {
            if (frame[static_cast<std::size_t>(i)] >= 0 || rng.next() % 3 != 0) continue;
            const TexelAddress t{i / (n * n), i % n, (i / n) % n};
            const int l = static_cast<int>(rng.next() % 3);
            REQUIRE(cube.store_at(t, glm::vec3(levels[l])));
            level[static_cast<std::size_t>(i)] = l;
            frame[static_cast<std::size_t>(i)] = f;
        }
        if (f == 0) cube.begin_frame();
    }
    std::vector<bool> expected(level.size(), false);
    std::size_t expected_count = 0;
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column) {
                const std::size_t i = static_cast<std::size_t>((face * n + row) * n + column);
                const int dc[4] = {-1, 1, 0, 0}, dr[4] = {0, 0, -1, 1};
                for (int k = 0; k < 4; ++k) {
                    const int c = column + dc[k], r = row + dr[k];
                    if (c < 0 || c >= n || r < 0 || r >= n) continue;
                    const std::size_t j = static_cast<std::size_t>((face * n + r) * n + c);
                    if (level[i] < 0 || level[j] < 0 || (frame[i] != 1 && frame[j] != 1)) continue;
                    if ((level[i] == 2) != (level[j] == 2)) expected[i] = true;
                }
                expected_count += expected[i];
            }
    REQUIRE(expected_count > 100);
    cube.settle_budget();
    const int bands = cube.tile_bands();
    REQUIRE(bands == 6 * 3);
    run_threads(thread_count, [&](int thread) {
        for (int b = bands - 1; b >= 0; --b)
            if (b % thread_count == thread) raycache::mark_doubtful_edges_in_bands(cube, 0.1f, b, b + 1);
    });
    CHECK(cube.doubtful_texels() == expected_count);
    std::size_t wrong = 0;
    for (int i = 0; i < 6 * n * n; ++i)
        wrong += cube.is_doubtful(TexelAddress{i / (n * n), i % n, (i / n) % n}) != expected[static_cast<std::size_t>(i)];
    CHECK(wrong == 0u);
}

TEST_CASE("the counters add up exactly when more threads count at once than there are slots of their own") {
    // Three rounds of threads made and joined: a thread's number is given back when it ends, and two
    // living threads must never share a slot of their own (counts would be lost; TSan would see a race).
    // Six more threads than there are such slots make the rest share the last one.
    const int threads = static_cast<int>(raycache::detail::StripedCounters<1>::owned_slots) + 6;
    const int each = 20000, rounds = 3;
    CctCube cube(8);
    for (int round = 0; round < rounds; ++round)
        run_threads(threads, [&](int t) {
            for (int k = 0; k < each; ++k) {
                cube.record_hit();
                cube.record_miss(static_cast<raycache::MissReason>(t % static_cast<int>(raycache::miss_reason_count)));
            }
        });
    const CubeStatistics s = cube.statistics();
    CHECK(s.hits == static_cast<std::uint64_t>(rounds) * threads * each);
    CHECK(s.misses == static_cast<std::uint64_t>(rounds) * threads * each);
    for (std::size_t r = 0; r < raycache::miss_reason_count; ++r) {
        std::uint64_t expected = 0;
        for (int t = 0; t < threads; ++t)
            expected += static_cast<std::size_t>(t) % raycache::miss_reason_count == r ? static_cast<std::uint64_t>(rounds) * each : 0;
        CHECK(s.misses_by[r] == expected);
    }
}
