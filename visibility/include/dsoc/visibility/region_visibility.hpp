#pragma once
// The interest manager's view of a culler: conservative visibility from a whole
// region of eyes (a client's reachable eye positions), not from a point.

#include "dsoc/visibility/box_visibility.hpp"
#include "dsoc/visibility/geometry.hpp"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

namespace dsoc::visibility {

/// Region-independent facts a culler may precompute for a box once and then reuse for
/// every region it is built for, by every client: e.g. which clusters of the map's PVS
/// the box touches. Filled by RegionVisibility::prepare(); opaque to everyone else.
struct PreparedBox {
    Aabb box;
    std::vector<std::int32_t> keys;
    bool prepared = false; ///< keys are meaningful; false: tests fall back to `box` alone
    /// With two prepared stages in a row (a baked table, then the map's PVS): the next
    /// stage's preparation of the same box (0 or 1 element). Only the first stage's
    /// keys may be merged (TBV groups); a culler uses `inner` only for a box it
    /// prepared itself.
    std::vector<PreparedBox> inner;
};

/// A tick's prepared boxes side by side, for RegionVisibility::coarse_hidden_all(): the
/// keys of box i are keys[key_start[i] .. key_start[i + 1]), so that a pass over all
/// of them reads memory in order instead of each box's own vectors.
struct PackedPreparedBoxes {
    std::vector<const PreparedBox*> boxes; ///< null: no box to answer
    std::vector<std::uint8_t> prepared;    ///< boxes[i]->prepared (0 for a null box)
    std::vector<std::int32_t> keys;
    std::vector<std::uint32_t> key_start{0}; ///< boxes.size() + 1 entries

    void clear() {
        boxes.clear();
        prepared.clear();
        keys.clear();
        key_start.assign(1, 0);
    }
    /// Appends `box` (may be null), copying its keys; `box` must outlive the pack.
    void add(const PreparedBox* box) {
        boxes.push_back(box);
        prepared.push_back(box != nullptr && box->prepared ? 1 : 0);
        if (box != nullptr) {
            keys.insert(keys.end(), box->keys.begin(), box->keys.end());
        }
        key_start.push_back(static_cast<std::uint32_t>(keys.size()));
    }
    [[nodiscard]] std::size_t size() const { return boxes.size(); }
};

class RegionVisibility {
public:
    virtual ~RegionVisibility() = default;
    /// Prepares answers for eyes anywhere in `region` (a closed box). May reuse memory.
    virtual void build(const Aabb& region) = 0;
    /// `occluded` only when `box` is hidden from EVERY point of the last built region;
    /// `visible` otherwise (may be a false positive). Const and thread-safe after build.
    [[nodiscard]] virtual Visibility test_box(const Aabb& box) const = 0;
    /// A cheaper test with the same guarantee (`occluded` is never wrong) that may
    /// prove less; used for entities that were visible last tick, most of which still
    /// are. Defaults to test_box().
    [[nodiscard]] virtual Visibility test_box_quick(const Aabb& box) const { return test_box(box); }

    /// True when prepare() precomputes something, so that test_prepared*() are cheaper
    /// than test_box() and test_prepared_coarse() is the culler's cheap first stage.
    [[nodiscard]] virtual bool has_prepared_stage() const { return false; }
    /// Fills `out` for `box`. Needs no build(): the answer does not depend on the region,
    /// so one culler may prepare boxes for every client. Const and thread-safe.
    virtual void prepare(const Aabb& box, PreparedBox& out) const {
        out.box = box;
        out.keys.clear();
        out.prepared = false;
    }
    /// test_box(p.box) and test_box_quick(p.box), helped by p's keys: the same answers.
    [[nodiscard]] virtual Visibility test_prepared(const PreparedBox& p) const {
        return test_box(p.box);
    }
    [[nodiscard]] virtual Visibility test_prepared_quick(const PreparedBox& p) const {
        return test_box_quick(p.box);
    }
    /// test_box() / test_prepared() with a hint: `hint` is an opaque value this culler
    /// wrote on an earlier call (0: none), e.g. the occluder that hid the box last tick,
    /// to try first; the culler may update it. The guarantee is test_box()'s
    /// (`occluded` only when hidden from every point of the region); the answer may
    /// prove more or less than without the hint. Defaults ignore the hint.
    [[nodiscard]] virtual Visibility test_box_hinted(const Aabb& box,
                                                     std::uint32_t& /*hint*/) const {
        return test_box(box);
    }
    [[nodiscard]] virtual Visibility test_prepared_hinted(const PreparedBox& p,
                                                          std::uint32_t& hint) const {
        return p.prepared ? test_prepared(p) : test_box_hinted(p.box, hint);
    }
    /// Makes `into` (prepared by this culler) stand for the union of its box and
    /// `more`'s (also prepared by it, `prepared` both): test_prepared_coarse() of the
    /// result is `occluded` only when it is for both. Only the first stage's keys are
    /// merged (a culler that uses `inner` clears it: it was of one box only). The default takes the
    /// sorted union of the keys (a key set such as clusters: hidden when no key is visible); `box`
    /// is the caller's to set.
    virtual void merge_prepared(PreparedBox& into, const PreparedBox& more) const {
        into.keys.insert(into.keys.end(), more.keys.begin(), more.keys.end());
        std::sort(into.keys.begin(), into.keys.end());
        into.keys.erase(std::unique(into.keys.begin(), into.keys.end()), into.keys.end());
    }
    /// False when every test starts with a stage that answers most pairs for a few bit
    /// tests (a baked cell table): the InterestManager's per-pair shortcuts, TBVs and
    /// entity clusters, exist to skip dear tests and then cost more than they save, so
    /// the manager does without them. The answers are the same either way (a TBV proven
    /// by this stage hides only what it would hide); only the cost differs.
    [[nodiscard]] virtual bool pair_shortcuts_pay() const { return true; }
    /// The cheap first stage alone (for long-lived TBVs, re-proven after every rebuild):
    /// `occluded` only when that stage proves it, so it proves less than test_prepared().
    /// Without a prepared stage this is test_prepared().
    [[nodiscard]] virtual Visibility test_prepared_coarse(const PreparedBox& p) const {
        return test_prepared(p);
    }
    /// True when test_prepared(), test_prepared_quick() and test_prepared_hinted() of a
    /// box this culler prepared all give test_prepared_coarse()'s answer, test_box(),
    /// test_box_quick() and test_box_hinted() all give test_box()'s, and no test
    /// touches a hint (a cheap stage with nothing behind it): the caller may then
    /// answer a tick's prepared boxes in bulk with coarse_hidden_all().
    [[nodiscard]] virtual bool prepared_tests_are_coarse() const { return false; }
    /// For every i: hidden[i] = 1 when boxes.boxes[i] (prepared by this culler) is
    /// `occluded` by test_prepared_coarse(), else 0; 0 for a null box. `hidden` has
    /// boxes.size() elements. The default asks box by box; a stage may read the packed
    /// keys instead.
    virtual void coarse_hidden_all(const PackedPreparedBoxes& boxes,
                                   std::span<std::uint8_t> hidden) const {
        for (std::size_t i = 0; i < boxes.size(); ++i) {
            const PreparedBox* box = boxes.boxes[i];
            hidden[i] = box != nullptr && test_prepared_coarse(*box) == Visibility::occluded;
        }
    }
};

/// Makes one RegionVisibility per client (each client owns its buffer).
using RegionVisibilityFactory = std::function<std::unique_ptr<RegionVisibility>()>;

} // namespace dsoc::visibility
