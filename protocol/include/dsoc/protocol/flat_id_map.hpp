#pragma once
// A map from 32-bit entity ids to small values, stored flat: one array of slots,
// open addressing with linear probing and backward-shift deletion. It replaces
// std::unordered_map on the per-client snapshot paths (the server's encoder
// baselines, the client's replica), where a lookup per entity per tick made the
// node-based map's pointer chasing a tenth of the server's tick.
//
// Contract: any id is a valid key (0 and 0xffffffff included). Lookups and erasures
// are O(1) on average: the load stays at most 1/2. Memory: fewer than 4 * (the
// largest size() it has had) + 16 slots of sizeof(T) + 8 bytes; it never shrinks
// (clear() keeps the capacity). Iteration order is unspecified.
// Insertion and erasure invalidate pointers to values.
//
// Threading: none; one per connection, like the encoder and decoder that hold it.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace dsoc::protocol {

template <class T>
class FlatIdMap {
public:
    [[nodiscard]] std::size_t size() const { return size_; }
    [[nodiscard]] bool empty() const { return size_ == 0; }
    [[nodiscard]] bool contains(std::uint32_t id) const { return find(id) != nullptr; }

    /// The value of `id`, or nullptr.
    [[nodiscard]] T* find(std::uint32_t id) {
        return const_cast<T*>(std::as_const(*this).find(id));
    }
    [[nodiscard]] const T* find(std::uint32_t id) const {
        if (slots_.empty()) {
            return nullptr;
        }
        for (std::size_t i = home(id);; i = (i + 1) & mask()) {
            const Slot& s = slots_[i];
            if (!s.used) {
                return nullptr;
            }
            if (s.id == id) {
                return &s.value;
            }
        }
    }

    /// Asks the cache for the slot where a lookup of `id` starts (a hint; no effect on
    /// the contents): a caller that knows which ids it will look up next hides the
    /// miss behind the work before.
    void prefetch(std::uint32_t id) const {
        if (!slots_.empty()) {
            __builtin_prefetch(&slots_[home(id)]);
        }
    }

    /// Inserts `value` under `id` unless `id` is present. Returns the stored value and
    /// whether it was inserted.
    std::pair<T*, bool> try_emplace(std::uint32_t id, const T& value) {
        if (2 * (size_ + 1) > slots_.size()) {
            grow();
        }
        std::size_t i = home(id);
        for (; slots_[i].used; i = (i + 1) & mask()) {
            if (slots_[i].id == id) {
                return {&slots_[i].value, false};
            }
        }
        slots_[i] = Slot{id, true, value};
        ++size_;
        return {&slots_[i].value, true};
    }

    /// The value of `id`, inserted value-initialized when absent.
    T& operator[](std::uint32_t id) { return *try_emplace(id, T{}).first; }

    /// Removes `id`; returns whether it was present.
    bool erase(std::uint32_t id) {
        if (slots_.empty()) {
            return false;
        }
        std::size_t i = home(id);
        for (;; i = (i + 1) & mask()) {
            if (!slots_[i].used) {
                return false;
            }
            if (slots_[i].id == id) {
                break;
            }
        }
        // Backward shift: move later members of the probe run into the hole when the
        // hole lies on their way from their home slot, so no tombstones are needed.
        for (std::size_t j = (i + 1) & mask();; j = (j + 1) & mask()) {
            if (!slots_[j].used) {
                break;
            }
            const std::size_t h = home(slots_[j].id);
            const bool hole_on_path = ((j - h) & mask()) >= ((j - i) & mask());
            if (hole_on_path) {
                slots_[i] = slots_[j];
                i = j;
            }
        }
        slots_[i].used = false;
        --size_;
        return true;
    }

    /// Removes every entry; keeps the capacity.
    void clear() {
        for (Slot& s : slots_) {
            s.used = false;
        }
        size_ = 0;
    }

    /// Calls f(id, value) for every entry, in unspecified order. `f` must not insert
    /// or erase.
    template <class F>
    void for_each(F&& f) const {
        for (const Slot& s : slots_) {
            if (s.used) {
                f(s.id, s.value);
            }
        }
    }

private:
    struct Slot {
        std::uint32_t id = 0;
        bool used = false;
        T value{};
    };

    [[nodiscard]] std::size_t mask() const { return slots_.size() - 1; }
    /// The id's low bits, offset by a Fibonacci hash of its high bits: ids below the
    /// capacity sit in their own slot, and any run of consecutive ids in consecutive
    /// slots, so visiting ids in increasing order (what every snapshot does) walks the
    /// array in order - the hardware prefetches it. (Scattering them cost a cache miss
    /// per lookup: 500 clients' tables do not fit in cache.)
    [[nodiscard]] std::size_t home(std::uint32_t id) const {
        const int bits = std::countr_zero(slots_.size());
        const std::uint64_t high = std::uint64_t{id} >> bits;
        const std::uint64_t offset = (high * 0x9E3779B97F4A7C15ull) >> 32;
        return static_cast<std::size_t>((id + offset) & mask());
    }

    void grow() {
        std::vector<Slot> old;
        old.swap(slots_);
        slots_.assign(old.empty() ? 16 : 2 * old.size(), Slot{});
        size_ = 0;
        for (const Slot& s : old) {
            if (s.used) {
                try_emplace(s.id, s.value);
            }
        }
    }

    std::vector<Slot> slots_; // size 0 or a power of two >= 16
    std::size_t size_ = 0;
};

} // namespace dsoc::protocol
