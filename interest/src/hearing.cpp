#include "dsoc/interest/hearing.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstring>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dsoc::interest {

void Hearing::begin_tick(const WorldView& world) {
    ids_.clear();
    for (auto* v : {&min_x_, &min_y_, &min_z_, &max_x_, &max_y_, &max_z_, &range_squared_}) {
        v->clear();
    }
    for (std::size_t i = 0; i < world.entity_count(); ++i) {
        const EntityView e = world.entity(i);
        if (e.sound_range > 0.0f) {
            ids_.push_back(e.id);
            min_x_.push_back(e.box.min.x);
            min_y_.push_back(e.box.min.y);
            min_z_.push_back(e.box.min.z);
            max_x_.push_back(e.box.max.x);
            max_y_.push_back(e.box.max.y);
            max_z_.push_back(e.box.max.z);
            range_squared_.push_back(e.sound_range * e.sound_range);
        }
    }
}

namespace {

/// Bit s % 64 of bits[s / 64] says whether box s (one array per coordinate, `n` of them)
/// has its nearest point to `eye` within the squared range: within_radius() for all
/// sounding entities at once, four to an SSE instruction where there is SSE.
void in_range_bits(std::size_t n, const float* min_x, const float* min_y, const float* min_z,
                   const float* max_x, const float* max_y, const float* max_z,
                   const float* range_squared, glm::vec3 eye, std::uint64_t* bits) {
    std::fill(bits, bits + (n + 63) / 64, std::uint64_t{0});
    std::size_t s = 0;
#if defined(__SSE2__)
    const __m128 ex = _mm_set1_ps(eye.x);
    const __m128 ey = _mm_set1_ps(eye.y);
    const __m128 ez = _mm_set1_ps(eye.z);
    const __m128 zero = _mm_setzero_ps();
    const auto gap = [zero](__m128 lo, __m128 x, __m128 hi) { // 0 inside [lo, hi]
        return _mm_max_ps(_mm_max_ps(_mm_sub_ps(lo, x), _mm_sub_ps(x, hi)), zero);
    };
    for (; s + 4 <= n; s += 4) {
        const __m128 dx = gap(_mm_loadu_ps(min_x + s), ex, _mm_loadu_ps(max_x + s));
        const __m128 dy = gap(_mm_loadu_ps(min_y + s), ey, _mm_loadu_ps(max_y + s));
        const __m128 dz = gap(_mm_loadu_ps(min_z + s), ez, _mm_loadu_ps(max_z + s));
        const __m128 d2 =
            _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
        const auto four = static_cast<std::uint64_t>(
            _mm_movemask_ps(_mm_cmple_ps(d2, _mm_loadu_ps(range_squared + s))));
        bits[s / 64] |= four << (s % 64); // s is a multiple of 4: the four bits stay in a word
    }
#endif
    for (; s < n; ++s) {
        const float dx = std::max({min_x[s] - eye.x, 0.0f, eye.x - max_x[s]});
        const float dy = std::max({min_y[s] - eye.y, 0.0f, eye.y - max_y[s]});
        const float dz = std::max({min_z[s] - eye.z, 0.0f, eye.z - max_z[s]});
        if (dx * dx + dy * dy + dz * dz <= range_squared[s]) {
            bits[s / 64] |= std::uint64_t{1} << (s % 64);
        }
    }
}

/// An Interest's bytes as one word: the id, then the tier, then zeros where its padding
/// is (checked below), so that one store writes a whole entry.
constexpr std::uint64_t as_word(std::uint32_t id, std::uint8_t tier) {
    return static_cast<std::uint64_t>(id) | static_cast<std::uint64_t>(tier) << 32;
}
static_assert(std::endian::native == std::endian::little && sizeof(Interest) == 8 &&
              offsetof(Interest, id) == 0 && offsetof(Interest, tier) == 4 &&
              std::is_trivially_copyable_v<Interest>);

/// A merge of part of a policy's answer (increasing ids) with heard ids (increasing) into
/// `to`: the answer's entries as they are, the heard ids it lacks on kHeardTier. Each step
/// is arithmetic, not a branch (the two lists interleave at random), and an entry moves
/// as one 8-byte word (as_word), picked by a mask; what bounds a step is then
/// the latency of the loads its pointers wait for, so add_heard() runs several merges
/// side by side.
struct HeardMerge {
    const Interest* sent;
    const Interest* sent_end;
    const std::uint32_t* heard;
    const std::uint32_t* heard_end;
    Interest* to;

    [[nodiscard]] bool both_left() const { return sent != sent_end && heard != heard_end; }
    void step() {
        const std::uint32_t sent_id = sent->id;
        const std::uint32_t heard_id = *heard;
        const bool take_sent = sent_id <= heard_id;
        // Both words made, one kept by a mask: a select, never a branch.
        const std::uint64_t keep_sent = std::uint64_t{0} - static_cast<std::uint64_t>(take_sent);
        const std::uint64_t word = (as_word(sent_id, sent->tier) & keep_sent) |
                                   (as_word(heard_id, kHeardTier) & ~keep_sent);
        std::memcpy(static_cast<void*>(to++), &word, sizeof word); // one store
        sent += static_cast<std::ptrdiff_t>(take_sent);
        heard += static_cast<std::ptrdiff_t>(heard_id <= sent_id); // both when equal
    }
    /// Steps while both lists last, then copies what is left; returns the end of `to`.
    Interest* finish() {
        while (both_left()) {
            step();
        }
        to = std::copy(sent, sent_end, to);
        for (; heard != heard_end; ++heard) {
            *to++ = {*heard, kHeardTier};
        }
        return to;
    }
};

} // namespace

std::size_t Hearing::add_heard(const Viewer& viewer, const InterestPolicy& policy,
                               std::vector<Interest>& out) const {
    // Per thread, so that no call allocates once warm; `merged` only grows, so that no
    // call initializes it either.
    thread_local std::vector<std::uint64_t> bits_of_thread;
    thread_local std::vector<std::uint32_t> heard_of_thread;
    thread_local std::vector<Interest> merged_of_thread;
    std::vector<std::uint64_t>& bits = bits_of_thread; // one TLS lookup per call
    std::vector<std::uint32_t>& heard = heard_of_thread;
    std::vector<Interest>& merged = merged_of_thread;
    const std::size_t n = ids_.size();
    bits.resize((n + 63) / 64);
    in_range_bits(n, min_x_.data(), min_y_.data(), min_z_.data(), max_x_.data(), max_y_.data(),
                  max_z_.data(), range_squared_.data(), viewer.eye, bits.data());
    // The sounding ids in range but the viewer's own, increasing, less what the policy
    // denies.
    if (const auto own = std::lower_bound(ids_.begin(), ids_.end(), viewer.entity_id);
        own != ids_.end() && *own == viewer.entity_id) {
        const auto s = static_cast<std::size_t>(own - ids_.begin());
        bits[s / 64] &= ~(std::uint64_t{1} << (s % 64));
    }
    std::size_t count = 0;
    for (const std::uint64_t w : bits) {
        count += static_cast<std::size_t>(std::popcount(w));
    }
    heard.resize(count);
    std::uint32_t* to_heard = heard.data();
    for (std::size_t word = 0; word < bits.size(); ++word) {
        for (std::uint64_t w = bits[word]; w != 0; w &= w - 1) {
            *to_heard++ = ids_[word * 64 + static_cast<std::size_t>(std::countr_zero(w))];
        }
    }
    policy.erase_denied(viewer.client_id, heard);
    if (heard.empty()) {
        return 0;
    }
    // The two lists merged in kParts parts, split at even points of the policy's answer
    // (an id and the heard ids at or above it fall in the part it starts, so an entity
    // both sent and heard is met once); the parts' steps interleave, so that their loads
    // overlap.
    constexpr std::size_t kParts = 4;
    merged.resize(std::max(merged.size(), out.size() + heard.size()));
    std::array<HeardMerge, kParts> parts{};
    std::array<Interest*, kParts> part_start{};
    {
        const Interest* sent_from = out.data();
        const Interest* const sent_end = out.data() + out.size();
        const std::uint32_t* heard_from = heard.data();
        const std::uint32_t* const heard_end = heard.data() + heard.size();
        Interest* to = merged.data();
        for (std::size_t p = 0; p < kParts; ++p) {
            const Interest* sent_to = out.data() + out.size() * (p + 1) / kParts;
            const std::uint32_t* heard_to =
                sent_to == sent_end ? heard_end
                                    : std::lower_bound(heard_from, heard_end, sent_to->id);
            parts[p] = {sent_from, sent_to, heard_from, heard_to, to};
            part_start[p] = to;
            to += (sent_to - sent_from) + (heard_to - heard_from);
            sent_from = sent_to;
            heard_from = heard_to;
        }
    }
    while (std::all_of(parts.begin(), parts.end(),
                       [](const HeardMerge& m) { return m.both_left(); })) {
        for (HeardMerge& m : parts) {
            m.step();
        }
    }
    std::size_t merged_size = 0;
    for (std::size_t p = 0; p < kParts; ++p) {
        merged_size += static_cast<std::size_t>(parts[p].finish() - part_start[p]);
    }
    const std::size_t added = merged_size - out.size();
    if (added == 0) {
        return 0;
    }
    out.clear();
    for (std::size_t p = 0; p < kParts; ++p) {
        out.insert(out.end(), part_start[p], parts[p].to);
    }
    return added;
}

} // namespace dsoc::interest
