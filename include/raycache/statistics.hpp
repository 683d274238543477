// raycache/statistics.hpp: per-cube counters of lookups, hits, misses and stores, cheap to bump from many threads.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <thread>

namespace raycache {

// Why a lookup missed, so that a cache that pays less than expected says what to change. The CCT's miss
// is its texel's state; a CDCT search's, that of the texel whose read ended it, or `search` when it read
// only usable texels and still found no consistent crossing.
enum class MissReason : std::uint8_t {
    empty,     // the texel holds no value: never stored, dropped (a stale tile, a move), or refused by the budget
    fresh,     // the texel was stored this frame: stores are visible from the next frame on
    doubtful,  // the texel lies at a colour edge (the confidence test): traced rather than answered
    origin,    // CCT: the ray left from further than the allowed drift from its tile's origins (it refills)
    search,    // CDCT: no consistent crossing within the read limit, or a gap behind an edge
    outside,   // not a direction, or a ray from outside what the last exact invalidation checked
};
inline constexpr std::size_t miss_reason_count = 6;

// A snapshot of one cube's counters since they were last reset (begin_frame() resets them).
struct CubeStatistics {
    std::uint64_t lookups = 0;          // hits + misses
    std::uint64_t hits = 0;             // lookups answered by a visible, valid texel
    std::uint64_t misses = 0;           // lookups that found nothing usable (the caller traced the ray)
    // misses by MissReason (their sum is `misses` for C++ cubes; GPU frames count misses without reasons)
    std::array<std::uint64_t, miss_reason_count> misses_by{};
    std::uint64_t stores = 0;           // stores that wrote a texel
    std::uint64_t refused_stores = 0;   // stores ignored: bad key or value, visible texel kept, lost a same-frame tie
    std::size_t valid_texels = 0;       // texels holding a value now (including this frame's stores)
    std::size_t texel_count = 0;        // 6 * N * N

    double valid_fraction() const noexcept {
        return texel_count ? static_cast<double>(valid_texels) / static_cast<double>(texel_count) : 0.0;
    }
    double hit_rate() const noexcept {
        return lookups ? static_cast<double>(hits) / static_cast<double>(lookups) : 0.0;
    }
    // The share of the lookups that missed for `why`, 0..1.
    double miss_share(MissReason why) const noexcept {
        return lookups ? static_cast<double>(misses_by[static_cast<std::size_t>(why)]) / static_cast<double>(lookups) : 0.0;
    }
};

// A lower-case name of a miss reason ("empty", "fresh", "doubtful", "origin", "search", "outside").
inline const char* to_string(MissReason why) noexcept {
    switch (why) {
    case MissReason::empty: return "empty";
    case MissReason::fresh: return "fresh";
    case MissReason::doubtful: return "doubtful";
    case MissReason::origin: return "origin";
    case MissReason::search: return "search";
    case MissReason::outside: return "outside";
    }
    return "?";
}

namespace detail {

// CounterCount counters spread over cache-line-sized slots: one a hardware thread, one more (a renderer's
// main thread beside its workers), and one shared. The first threads of the process that count get a
// slot of their own and bump it with a plain load and store (no locked instruction on the lookup path);
// later threads share the last slot and bump it with fetch_add. Sums are exact; a snapshot taken while
// other threads count is a moment's approximation. The slots are sized to the machine, not to the most
// threads any machine has, since a scene may hold a counter set per cube for a thousand cubes.
template <std::size_t CounterCount>
class StripedCounters {
public:
    StripedCounters() : owned_(owned_slot_count()), slots_(new Slot[owned_ + 1]) {}

    void add(std::size_t counter, std::uint64_t amount = 1) noexcept {
        const std::size_t slot = std::min(this_thread_index(), owned_);
        std::atomic<std::uint64_t>& value = slots_[slot].values[counter];
        if (slot < owned_)
            value.store(value.load(std::memory_order_relaxed) + amount, std::memory_order_relaxed); // only writer
        else
            value.fetch_add(amount, std::memory_order_relaxed);
    }
    std::uint64_t sum(std::size_t counter) const noexcept {
        std::uint64_t total = 0;
        for (std::size_t i = 0; i <= owned_; ++i) total += slots_[i].values[counter].load(std::memory_order_relaxed);
        return total;
    }
    // Not concurrent with add().
    void reset() noexcept {
        for (std::size_t i = 0; i <= owned_; ++i)
            for (auto& value : slots_[i].values) value.store(0, std::memory_order_relaxed);
    }
    // Heap bytes of the slots.
    std::size_t bytes() const noexcept { return (owned_ + 1) * sizeof(Slot); }

private:
    struct alignas(64) Slot {
        std::array<std::atomic<std::uint64_t>, CounterCount> values{};
    };
    // Slots of their own: the hardware threads and one more (at most 256; 2 when the count is unknown).
    static std::size_t owned_slot_count() noexcept {
        static const std::size_t count = std::min<std::size_t>(std::max(1u, std::thread::hardware_concurrency()) + 1, 256);
        return count;
    }
    // This thread's number among the threads of the process that counted, from 0.
    static std::size_t this_thread_index() noexcept {
        static std::atomic<std::size_t> next_thread{0};
        thread_local const std::size_t index = next_thread.fetch_add(1, std::memory_order_relaxed);
        return index;
    }
    std::size_t owned_;
    std::unique_ptr<Slot[]> slots_;
};

} // namespace detail
} // namespace raycache
