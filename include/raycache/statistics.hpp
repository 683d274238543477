// raycache/statistics.hpp: per-cube counters of lookups, hits, misses and stores, cheap to bump from many threads.
#pragma once

#include "raycache/requires_cpp17.hpp"
#include "raycache/shared/language.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <mutex>
#include <vector>

namespace raycache {

// Why a lookup missed, so that a cache that pays less than expected says what to change. The CCT's miss
// is its texel's state; a CDCT search's, that of the texel whose read ended it, or `search` when it read
// only usable texels and still found no consistent crossing.
enum class MissReason : std::uint8_t {
    empty,     // the texel holds no value: never stored, dropped (a stale tile, a move), or refused by the budget
    fresh,     // the texel was stored this frame: stores are visible from the next frame on
    doubtful,  // the texel lies at a colour edge (the confidence test): traced rather than answered
    origin,    // CCT: the ray left from further than the allowed drift from its tile's origins (it refills)
    search,    // CDCT (secant or relief search): no consistent crossing within its reads, or a gap behind an
               // edge; also a caller's record_lookup(false), which gives no cause
    outside,   // not a direction, bad input (a texel off the cube, a box no search can use), or a ray from
               // outside what the last exact invalidation checked
    resting,   // not looked up: the cube rests, since it answered too few of its rays (raycache/resting.hpp)
};
inline constexpr std::size_t miss_reason_count = 7;

// Of `lookups` with misses `misses_by` (by MissReason), those a cube really made: its resting misses left
// out. (CubeStatistics::looked_up() and the Embree adapter's totals.)
inline std::uint64_t looked_up_count(std::uint64_t lookups, const std::array<std::uint64_t, miss_reason_count>& misses_by) noexcept {
    const std::uint64_t rested = misses_by[static_cast<std::size_t>(MissReason::resting)];
    return lookups >= rested ? lookups - rested : 0;
}

// A snapshot of one cube's counters since they were last reset (begin_frame() resets them).
struct CubeStatistics {
    std::uint64_t lookups = 0;          // hits + misses
    std::uint64_t hits = 0;             // lookups answered by a visible, valid texel
    std::uint64_t misses = 0;           // lookups that found nothing usable (the caller traced the ray)
    // misses by MissReason (their sum is `misses` for C++ cubes; GPU frames count only MissReason::resting and
    // MissReason::empty)
    std::array<std::uint64_t, miss_reason_count> misses_by{};
    std::uint64_t stores = 0;           // stores that wrote a texel
    std::uint64_t refused_stores = 0;   // stores ignored: bad key or value, visible texel kept, lost a same-frame tie
    std::size_t valid_texels = 0;       // texels holding a value now (including this frame's stores)
    std::size_t texel_count = 0;        // 6 * N * N
    // What the rays that filled texels reported they cost (TracedRay::work), and how many reported it
    // (raycache/resting.hpp).
    std::uint64_t filled_work = 0;
    std::uint64_t work_reports = 0;

    double valid_fraction() const noexcept {
        return texel_count ? static_cast<double>(valid_texels) / static_cast<double>(texel_count) : 0.0;
    }
    double hit_rate() const noexcept {
        return lookups ? static_cast<double>(hits) / static_cast<double>(lookups) : 0.0;
    }
    // The mean work of a ray that filled a texel and reported it; 0 when none did.
    double mean_filled_work() const noexcept {
        return work_reports ? static_cast<double>(filled_work) / static_cast<double>(work_reports) : 0.0;
    }
    // Lookups the cube made: its resting misses (raycache/resting.hpp) left out, since it read nothing for them.
    std::uint64_t looked_up() const noexcept { return looked_up_count(lookups, misses_by); }
    // The share of the lookups that missed for `why`, 0..1 (on GPU statistics 0 for every cause but resting and
    // empty).
    double miss_share(MissReason why) const noexcept {
        return lookups ? static_cast<double>(misses_by[static_cast<std::size_t>(why)]) / static_cast<double>(lookups) : 0.0;
    }
};

// A lower-case name of a miss reason ("empty", "fresh", "doubtful", "origin", "search", "outside", "resting").
inline const char* to_string(MissReason why) noexcept {
    switch (why) {
    case MissReason::empty: return "empty";
    case MissReason::fresh: return "fresh";
    case MissReason::doubtful: return "doubtful";
    case MissReason::origin: return "origin";
    case MissReason::search: return "search";
    case MissReason::outside: return "outside";
    case MissReason::resting: return "resting";
    }
    return "?";
}

namespace detail {

// CounterCount counters spread over cache-line-sized slots, owned_slots of them owned and one shared. A
// thread that counts takes the smallest number no living counting thread holds and gives it back when it
// ends, so a pool, or threads made and joined frame after frame, keep to the first numbers. Threads
// numbered below owned_slots own a slot and bump it with a plain load and store (no locked instruction on
// the lookup path); the rest (more counting threads alive at once) share the last slot and bump it with
// fetch_add. Sums are exact; a snapshot taken while other threads count is a moment's approximation. The
// slots sit inside the counters (no pointer to follow on every count): 17 x 128 bytes for a cube's thirteen
// counters, which a scene holds once per cube.
template <std::size_t CounterCount>
class StripedCounters {
public:
    StripedCounters() = default;
    StripedCounters(const StripedCounters&) = delete;
    StripedCounters& operator=(const StripedCounters&) = delete;

    RAYCACHE_HOT_FN void add(std::size_t counter, std::uint64_t amount = 1) noexcept {
        const std::size_t slot = std::min(this_thread_index(), owned_slots);
        std::atomic<std::uint64_t>& value = slots_[slot].values[counter];
        if (slot < owned_slots)
            value.store(value.load(std::memory_order_relaxed) + amount, std::memory_order_relaxed); // only writer
        else
            value.fetch_add(amount, std::memory_order_relaxed);
    }
    std::uint64_t sum(std::size_t counter) const noexcept {
        std::uint64_t total = 0;
        for (const Slot& slot : slots_) total += slot.values[counter].load(std::memory_order_relaxed);
        return total;
    }
    // Not concurrent with add().
    void reset() noexcept {
        for (Slot& slot : slots_)
            for (auto& value : slot.values) value.store(0, std::memory_order_relaxed);
    }
    // Threads with a slot of their own at once.
    static constexpr std::size_t owned_slots = 16;

private:
    struct alignas(64) Slot {
        std::array<std::atomic<std::uint64_t>, CounterCount> values{};
    };
    // The numbers living threads hold, and those given back. Never destroyed: threads may end after the
    // process's statics are gone.
    struct Numbers {
        std::mutex lock;
        std::vector<std::size_t> free;
        std::size_t next = 0;
    };
    static Numbers& numbers() noexcept {
        static Numbers* const n = new Numbers;
        return *n;
    }
    // A thread's number, held while it lives (the shared slot's if the numbers cannot be kept).
    struct Ticket {
        std::size_t index = std::numeric_limits<std::size_t>::max();
        Ticket() noexcept {
            try {
                Numbers& n = numbers();
                const std::lock_guard<std::mutex> hold(n.lock);
                if (n.free.empty()) {
                    index = n.next++;
                } else {
                    const auto smallest = std::min_element(n.free.begin(), n.free.end());
                    index = *smallest;
                    n.free.erase(smallest);
                }
            } catch (...) {
            }
        }
        ~Ticket() {
            if (index == std::numeric_limits<std::size_t>::max()) return;
            try {
                Numbers& n = numbers();
                const std::lock_guard<std::mutex> hold(n.lock);
                n.free.push_back(index);
            } catch (...) {
            }
        }
        Ticket(const Ticket&) = delete;
        Ticket& operator=(const Ticket&) = delete;
    };
    // A constant-initialized thread_local on the counting path (no guard to test); the ticket, whose
    // destructor gives the number back, is made on a thread's first count only.
    static std::size_t this_thread_index() noexcept {
        thread_local std::size_t index = unnumbered;
        if (index == unnumbered) index = take_number();
        return index;
    }
    static constexpr std::size_t unnumbered = std::numeric_limits<std::size_t>::max() - 1;
    static std::size_t take_number() noexcept {
        thread_local const Ticket ticket;
        return ticket.index;
    }
    std::array<Slot, owned_slots + 1> slots_{};
};

} // namespace detail
} // namespace raycache
