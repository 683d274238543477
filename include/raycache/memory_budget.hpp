// raycache/memory_budget.hpp: MemoryBudget, a byte limit shared by the caching cubes that draw on it.
//
// Cubes allocate their texels in tiles, on a tile's first store. A cube given a budget asks it before
// each allocation; when the tile would take the budget past its limit, the allocation is refused, the
// store is refused (counted in CubeStatistics::refused_stores) and the ray is simply traced, as without
// a cache. Nothing already stored is dropped to make room: what a budget protects is the user's memory,
// not the hit rate. A cube's fixed part (CacheCube::fixed_bytes(): its tile table, bitmaps and counters)
// is charged too, and always granted to the cube; SceneCache makes no cube whose fixed part does not fit
// (attach() throws, a cube keeps its size rather than grow past the budget), so its cubes' bytes never
// pass the limit.
//
// Which tiles of a frame get the last bytes depends on which thread asked first, so a frame in which the
// budget refused anything keeps none of the tiles it allocated (CacheCube::begin_frame(): they are given
// back, and the tiles the frame wanted are allocated again, empty, in tile order while they fit); the
// budget counts its refusals so that every cube drawing on it can tell.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace raycache {

class MemoryBudget {
public:
    // A budget of `limit_bytes` bytes (std::numeric_limits<std::size_t>::max(): no limit).
    explicit MemoryBudget(std::size_t limit_bytes) noexcept : limit_(limit_bytes) {}
    MemoryBudget(const MemoryBudget&) = delete;
    MemoryBudget& operator=(const MemoryBudget&) = delete;

    // Takes `bytes` from the budget when they fit under the limit; false (and nothing taken) otherwise.
    // Thread-safe, lock-free.
    // A refusal is counted (refusals()) unless count_refusal is false.
    bool try_reserve(std::size_t bytes, bool count_refusal = true) noexcept {
        std::size_t used = used_.load(std::memory_order_relaxed);
        do {
            if (bytes > limit_ || used > limit_ - bytes) {
                if (count_refusal) refusals_.fetch_add(1, std::memory_order_relaxed);
                return false;
            }
        } while (!used_.compare_exchange_weak(used, used + bytes, std::memory_order_relaxed));
        return true;
    }
    // Takes `bytes` whatever the limit (for the fixed part of a cube). Thread-safe.
    void reserve_always(std::size_t bytes) noexcept { used_.fetch_add(bytes, std::memory_order_relaxed); }
    // Gives back bytes taken by try_reserve() or reserve_always(). Thread-safe.
    void release(std::size_t bytes) noexcept { used_.fetch_sub(bytes, std::memory_order_relaxed); }

    std::size_t limit() const noexcept { return limit_; }
    std::size_t used() const noexcept { return used_.load(std::memory_order_relaxed); }
    // The bytes left under the limit now (0 once reserve_always() has passed it).
    std::size_t room() const noexcept {
        const std::size_t u = used();
        return limit_ > u ? limit_ - u : 0;
    }
    // Counted refusals since the budget was made.
    std::uint64_t refusals() const noexcept { return refusals_.load(std::memory_order_relaxed); }

private:
    const std::size_t limit_;
    std::atomic<std::size_t> used_{0};
    std::atomic<std::uint64_t> refusals_{0};
};

} // namespace raycache
