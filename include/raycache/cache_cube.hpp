// raycache/cache_cube.hpp: CacheCube<Texel>, the six N x N texel faces around one cached object.
//
// Frames and determinism. A store becomes visible to lookups from the next begin_frame() on; during the
// frame it was made in, its texel reads as empty. So every lookup of a frame sees the same cube whatever
// the thread timing, and a frame rendered with a cold cube traces every cached ray, exactly as without
// the cache. When several stores reach one texel in the same frame, the smallest packed word wins.
// A texel that is already visible keeps its value until clear() or invalidate().
//
// Threads. lookup(), peek() and store() may run on any number of threads at once, on one cube, without
// locks (lookups are wait-free). begin_frame(), clear() and invalidate() must run between frames, when
// no other thread uses the cube.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <glm/glm.hpp>

#include "raycache/assert.hpp"
#include "raycache/cube_face.hpp"
#include "raycache/statistics.hpp"
#include "raycache/texel.hpp"

namespace raycache {

template <class Texel>
class CacheCube {
    using Traits = TexelTraits<Texel>; // checks the Texel type's requirements

public:
    using Word = typename Traits::Word;
    using Value = typename Traits::Value;

    // A cube of six face_size x face_size faces, every texel invalid.
    // Throws std::invalid_argument unless 1 <= face_size <= 4096.
    explicit CacheCube(int face_size) : face_size_(checked_face_size(face_size)), state_(new State(texel_count())) {}

    int face_size() const noexcept { return face_size_; }
    // 6 * N * N.
    std::size_t texel_count() const noexcept { return std::size_t{RAYCACHE_FACE_COUNT} * face_size_ * face_size_; }
    // Bytes of texel storage, 6 * N * N * sizeof(Word): the thesis's memory per cube.
    std::size_t texel_bytes() const noexcept { return texel_count() * sizeof(Word); }
    // Every byte the cube holds: texels, the frame's written-texel bits, counters.
    std::size_t bytes() const noexcept {
        return sizeof(*this) + sizeof(State) + texel_bytes() + bit_word_count() * sizeof(std::uint64_t);
    }

    // The value cached for `direction`, counted as a hit or a miss. std::nullopt (a miss) when the
    // texel is empty, was written this frame, or `direction` is not a direction. Thread-safe, wait-free.
    std::optional<Value> lookup(const glm::vec3& direction) noexcept {
        std::optional<Value> value = peek(direction);
        record_lookup(value.has_value());
        return value;
    }

    // lookup() without counting, for searches that read many texels per ray (count them with record_lookup()).
    std::optional<Value> peek(const glm::vec3& direction) const noexcept {
        const shared::raycache_texel_address a = shared::raycache_texel_of(direction, face_size_);
        if (a.face == RAYCACHE_NO_FACE) return std::nullopt;
        return visible_value(shared::raycache_texel_linear_index(a, face_size_));
    }

    // Counts one lookup made of peek() calls as a hit or a miss.
    void record_lookup(bool hit) noexcept {
        state_->counters.add(hit ? hits : misses);
    }

    // Caches `value` in the texel of `direction`; returns whether it was written. Refused (false) when
    // `direction` is not a direction, the value cannot be encoded, the texel already holds a visible
    // value, or a smaller word was stored into it this frame. Visible from the next begin_frame().
    // Thread-safe, lock-free.
    bool store(const glm::vec3& direction, const Value& value) noexcept {
        const shared::raycache_texel_address a = shared::raycache_texel_of(direction, face_size_);
        if (a.face == RAYCACHE_NO_FACE) return refuse();
        return store_word(shared::raycache_texel_linear_index(a, face_size_), Texel::encode(value));
    }

    // store() by address (named apart so that a braced {face, column, row} never reads as a direction);
    // `texel` must lie on the cube (asserted).
    bool store_at(const TexelAddress& texel, const Value& value) noexcept {
        RAYCACHE_ASSERT(contains(texel));
        if (!contains(texel)) return refuse();
        return store_word(texel_linear_index(texel, face_size_), Texel::encode(value));
    }

    // The value in `texel` whether or not it is visible yet; std::nullopt when empty. No counting.
    // `texel` must lie on the cube (asserted).
    std::optional<Value> load(const TexelAddress& texel) const noexcept {
        RAYCACHE_ASSERT(contains(texel));
        if (!contains(texel)) return std::nullopt;
        const Word word = state_->texels[texel_linear_index(texel, face_size_)].load(std::memory_order_acquire);
        if (!Texel::is_valid(word)) return std::nullopt;
        return Texel::decode(word);
    }

    // Empties one texel. Between frames only.
    void invalidate(const TexelAddress& texel) noexcept {
        RAYCACHE_ASSERT(contains(texel));
        if (!contains(texel)) return;
        const std::size_t index = texel_linear_index(texel, face_size_);
        if (Texel::is_valid(state_->texels[index].exchange(Texel::invalid, std::memory_order_relaxed)))
            state_->valid_texels.fetch_sub(1, std::memory_order_relaxed);
    }

    // Empties every texel and resets the counters. Between frames only.
    void clear() noexcept {
        for (std::size_t i = 0; i < texel_count(); ++i) state_->texels[i].store(Texel::invalid, std::memory_order_relaxed);
        clear_written_bits();
        state_->valid_texels.store(0, std::memory_order_relaxed);
        state_->counters.reset();
    }

    // Ends a frame: this frame's stores become visible; returns the frame's counters and resets them.
    // Between frames only.
    CubeStatistics begin_frame() noexcept {
        const CubeStatistics finished = statistics();
        if (state_->written_this_frame.exchange(false, std::memory_order_relaxed)) clear_written_bits();
        state_->counters.reset();
        return finished;
    }

    // The counters since the last reset (approximate while other threads are counting).
    CubeStatistics statistics() const noexcept {
        CubeStatistics s;
        s.hits = state_->counters.sum(hits);
        s.misses = state_->counters.sum(misses);
        s.lookups = s.hits + s.misses;
        s.stores = state_->counters.sum(stores);
        s.refused_stores = state_->counters.sum(refused_stores);
        s.valid_texels = valid_texels();
        s.texel_count = texel_count();
        return s;
    }

    void reset_statistics() noexcept { state_->counters.reset(); }

    // Calls f(address) for every texel stored during the current frame, in linear-index order
    // (for structures derived from the cube, updated before begin_frame()). Between frames only.
    template <class F>
    void for_each_written_texel(F&& f) const {
        if (!state_->written_this_frame.load(std::memory_order_relaxed)) return;
        const std::size_t n = static_cast<std::size_t>(face_size_);
        for (std::size_t w = 0; w < bit_word_count(); ++w) {
            std::uint64_t bits = state_->written[w].load(std::memory_order_relaxed);
            while (bits) {
                const std::size_t index = w * 64 + static_cast<std::size_t>(count_trailing_zeros(bits));
                bits &= bits - 1;
                f(TexelAddress{static_cast<int>(index / (n * n)), static_cast<int>(index % n),
                               static_cast<int>(index / n % n)});
            }
        }
    }

    // Texels holding a value, visible or written this frame.
    std::size_t valid_texels() const noexcept {
        return static_cast<std::size_t>(state_->valid_texels.load(std::memory_order_relaxed));
    }
    double valid_fraction() const noexcept {
        return static_cast<double>(valid_texels()) / static_cast<double>(texel_count());
    }

    bool contains(const TexelAddress& t) const noexcept { return is_on_cube(t, face_size_); }

private:
    enum Counter : std::size_t { hits, misses, stores, refused_stores, counter_count };

    struct State {
        explicit State(std::size_t count)
            : texels(new std::atomic<Word>[count]), written(new std::atomic<std::uint64_t>[(count + 63) / 64]) {
            for (std::size_t i = 0; i < count; ++i) texels[i].store(Texel::invalid, std::memory_order_relaxed);
            for (std::size_t i = 0; i < (count + 63) / 64; ++i) written[i].store(0, std::memory_order_relaxed);
        }
        std::unique_ptr<std::atomic<Word>[]> texels;
        // One bit per texel: written during the current frame (so not visible yet).
        std::unique_ptr<std::atomic<std::uint64_t>[]> written;
        std::atomic<bool> written_this_frame{false};
        std::atomic<std::int64_t> valid_texels{0};
        detail::StripedCounters<counter_count> counters;
    };

    static int checked_face_size(int face_size) {
        if (!is_valid_face_size(face_size))
            throw std::invalid_argument("RayCache: a caching cube's face size must be 1 to 4096 texels, got " +
                                        std::to_string(face_size) +
                                        " (the thesis studies 128, 256 and 512; memory is 6 * N * N texels)");
        return face_size;
    }

    std::size_t bit_word_count() const noexcept { return (texel_count() + 63) / 64; }

    static int count_trailing_zeros(std::uint64_t bits) noexcept {
        int n = 0;
        while (!(bits & 1u)) {
            bits >>= 1;
            ++n;
        }
        return n;
    }

    bool written_this_frame(std::size_t index) const noexcept {
        return (state_->written[index / 64].load(std::memory_order_relaxed) >> (index % 64)) & 1u;
    }

    void clear_written_bits() noexcept {
        for (std::size_t i = 0; i < bit_word_count(); ++i) state_->written[i].store(0, std::memory_order_relaxed);
    }

    std::optional<Value> visible_value(std::size_t index) const noexcept {
        // Acquire pairs with the store's release: a word written this frame comes with its written bit,
        // and the cube's written_this_frame flag, set. The flag spares frames without stores the bit load.
        const Word word = state_->texels[index].load(std::memory_order_acquire);
        if (!Texel::is_valid(word)) return std::nullopt;
        if (state_->written_this_frame.load(std::memory_order_relaxed) && written_this_frame(index)) return std::nullopt;
        return Texel::decode(word);
    }

    bool refuse() noexcept {
        state_->counters.add(refused_stores);
        return false;
    }

    bool store_word(std::size_t index, Word word) noexcept {
        if (!Texel::is_valid(word)) return refuse();
        std::atomic<Word>& texel = state_->texels[index];
        Word old = texel.load(std::memory_order_acquire);
        if (Texel::is_valid(old) && !written_this_frame(index)) return refuse(); // visible: kept
        // Mark the texel as this frame's before writing it, so no reader can see the new word as visible.
        state_->written[index / 64].fetch_or(std::uint64_t{1} << (index % 64), std::memory_order_relaxed);
        if (!state_->written_this_frame.load(std::memory_order_relaxed))
            state_->written_this_frame.store(true, std::memory_order_relaxed);
        for (;;) {
            if (Texel::is_valid(old) && !(word < old)) return refuse(); // same frame: the smaller word wins
            if (texel.compare_exchange_weak(old, word, std::memory_order_acq_rel, std::memory_order_acquire)) {
                if (!Texel::is_valid(old)) state_->valid_texels.fetch_add(1, std::memory_order_relaxed);
                state_->counters.add(stores);
                return true;
            }
        }
    }

    int face_size_;
    std::unique_ptr<State> state_;
};

using CctCube = CacheCube<CctTexel>;
using CdctCube = CacheCube<CdctTexel>;

} // namespace raycache
