// raycache/memory_budget.hpp: MemoryBudget, a byte limit shared by the caching cubes that draw on it.
//
// Cubes allocate their texels in tiles, on a tile's first store. A cube given a budget asks it before
// each allocation; when the tile would take the budget past its limit, the allocation is refused, the
// store is refused (counted in CubeStatistics::refused_stores) and the ray is simply traced, as without
// a cache. Nothing already stored is dropped to make room: what a budget protects is the user's memory,
// not the hit rate. A cube's fixed part (its tile table) is charged too, and is always granted.
#pragma once

#include "raycache/requires_cpp17.hpp"

#include <atomic>
#include <cstddef>
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
    bool try_reserve(std::size_t bytes) noexcept {
        std::size_t used = used_.load(std::memory_order_relaxed);
        do {
            if (bytes > limit_ || used > limit_ - bytes) return false;
        } while (!used_.compare_exchange_weak(used, used + bytes, std::memory_order_relaxed));
        return true;
    }
    // Takes `bytes` whatever the limit (for the fixed part of a cube). Thread-safe.
    void reserve_always(std::size_t bytes) noexcept { used_.fetch_add(bytes, std::memory_order_relaxed); }
    // Gives back bytes taken by try_reserve() or reserve_always(). Thread-safe.
    void release(std::size_t bytes) noexcept { used_.fetch_sub(bytes, std::memory_order_relaxed); }

    std::size_t limit() const noexcept { return limit_; }
    std::size_t used() const noexcept { return used_.load(std::memory_order_relaxed); }

private:
    const std::size_t limit_;
    std::atomic<std::size_t> used_{0};
};

} // namespace raycache
