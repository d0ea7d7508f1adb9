#pragma once
// Hearing: entities a client cannot see but can hear are sent to it on the heard tier
// (kHeardTier): a coarse position and no view angles, enough to place a sound and not
// to aim at. The rule (sim/sounds.hpp says how sound travels): an entity sounding with
// range R (EntityView::sound_range) is heard by a viewer whose eye is within R of its
// box. Hearing adds to a policy's answer and never takes from it: an entity the policy
// sends for sight (or for its team) keeps its tier, so it is precise the tick it is
// seen, and the sight guarantee is the policy's alone. A pair the policy denies
// (InterestPolicy::erase_denied: a `never` rule) is not heard either.
//
// Threading: begin_tick() is serial; add_heard() may then run concurrently for
// distinct viewers (it only reads what begin_tick() took).

#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/interest/world_view.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dsoc::interest {

class Hearing {
public:
    /// Takes this tick's sounding entities of `world` (sound_range > 0).
    void begin_tick(const WorldView& world);

    /// Adds to `out` (a policy's answer for `viewer`: increasing ids) every sounding
    /// entity the viewer hears that `out` lacks, on kHeardTier, keeping the order; the
    /// viewer's own entity and what `policy` denies are left out. Returns how many it
    /// added.
    std::size_t add_heard(const Viewer& viewer, const InterestPolicy& policy,
                          std::vector<Interest>& out) const;

    /// How many entities sound this tick.
    [[nodiscard]] std::size_t sounding() const { return ids_.size(); }

private:
    // This tick's sounding entities, in increasing id order, one array per coordinate of
    // their boxes (so the range test over all of them vectorizes), and the squared ranges.
    std::vector<std::uint32_t> ids_;
    std::vector<float> min_x_, min_y_, min_z_, max_x_, max_y_, max_z_;
    std::vector<float> range_squared_;
};

} // namespace dsoc::interest
