#include "dsoc/interest/hearing.hpp"

#include <algorithm>
#include <bit>

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

} // namespace

std::size_t Hearing::add_heard(const Viewer& viewer, const InterestPolicy& policy,
                               std::vector<Interest>& out) const {
    // Per thread, so that no call allocates once warm.
    thread_local std::vector<std::uint64_t> bits_of_thread;
    thread_local std::vector<Interest> merged_of_thread;
    std::vector<std::uint64_t>& bits = bits_of_thread; // one TLS lookup per call
    std::vector<Interest>& merged = merged_of_thread;
    const std::size_t n = ids_.size();
    bits.resize((n + 63) / 64);
    in_range_bits(n, min_x_.data(), min_y_.data(), min_z_.data(), max_x_.data(), max_y_.data(),
                  max_z_.data(), range_squared_.data(), viewer.eye, bits.data());
    // One pass over the policy's answer and the sounding ids in range (both increasing):
    // what the policy sent as it is, then what is heard and not sent, on the heard tier.
    std::size_t in_range = 0;
    for (const std::uint64_t w : bits) {
        in_range += static_cast<std::size_t>(std::popcount(w));
    }
    merged.resize(out.size() + in_range);
    Interest* to = merged.data();
    const Interest* from = out.data();
    const Interest* const end = from + out.size();
    std::size_t added = 0;
    for (std::size_t word = 0; word < bits.size(); ++word) {
        for (std::uint64_t w = bits[word]; w != 0; w &= w - 1) {
            const std::uint32_t id =
                ids_[word * 64 + static_cast<std::size_t>(std::countr_zero(w))];
            while (from != end && from->id < id) {
                *to++ = *from++;
            }
            if ((from != end && from->id == id) || id == viewer.entity_id ||
                policy.denies(viewer.client_id, id)) {
                continue;
            }
            *to++ = {id, kHeardTier};
            ++added;
        }
    }
    if (added == 0) {
        return 0;
    }
    to = std::copy(from, end, to);
    merged.resize(static_cast<std::size_t>(to - merged.data()));
    out.swap(merged); // the two buffers trade places; both keep their capacity
    return added;
}

} // namespace dsoc::interest
