// Hearing (interest/hearing.hpp): what a viewer hears and the policy did not send is
// added on the heard tier, in id order; nothing the policy sent changes; beyond a
// sound's range nothing is heard. A randomized test holds add_heard() to the rule
// written plainly (within_radius() of every sounding entity).

#include "dsoc/interest/hearing.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace dsoc::interest {
namespace {

class ListView final : public WorldView {
public:
    explicit ListView(std::vector<EntityView> entities) : entities_(std::move(entities)) {}
    [[nodiscard]] std::size_t entity_count() const override { return entities_.size(); }
    [[nodiscard]] EntityView entity(std::size_t index) const override { return entities_[index]; }

private:
    std::vector<EntityView> entities_;
};

/// A policy that sends nothing and denies what it is told to.
class Denying final : public InterestPolicy {
public:
    explicit Denying(std::vector<std::uint32_t> denied = {}) : denied_(std::move(denied)) {}
    [[nodiscard]] std::string_view name() const override { return "denying"; }
    void select(const WorldView&, const Viewer&, std::vector<Interest>& out) override {
        out.clear();
    }
    void erase_denied(std::uint32_t, std::vector<std::uint32_t>& ids) const override {
        std::erase_if(ids, [this](std::uint32_t id) {
            return std::find(denied_.begin(), denied_.end(), id) != denied_.end();
        });
    }

private:
    std::vector<std::uint32_t> denied_;
};

EntityView at(std::uint32_t id, glm::vec3 centre, float sound_range) {
    EntityView e;
    e.id = id;
    e.box = visibility::Aabb::from_center_half_extents(centre, {15.0f, 15.0f, 28.0f});
    e.sound_range = sound_range;
    return e;
}

Viewer viewer_at(glm::vec3 eye, std::uint32_t own = 1) {
    Viewer v;
    v.client_id = 1;
    v.entity_id = own;
    v.eye = eye;
    return v;
}

TEST(Hearing, AShotWithinItsRangeIsHeardOnTheHeardTierAndBeyondItNot) {
    // Entity 2 fires 1,000 units away (its box's near face 985 away), entity 3 fires
    // 2,000 away, entity 4 is as near but silent.
    const ListView world({at(1, {0, 0, 0}, 0.0f), at(2, {1000, 0, 0}, 1330.0f),
                          at(3, {2000, 0, 0}, 1330.0f), at(4, {500, 0, 0}, 0.0f)});
    Hearing hearing;
    hearing.begin_tick(world);
    EXPECT_EQ(hearing.sounding(), 2u);
    const Denying policy;
    std::vector<Interest> out;
    EXPECT_EQ(hearing.add_heard(viewer_at({0, 0, 0}), policy, out), 1u);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0], (Interest{2, kHeardTier}));
}

TEST(Hearing, WhatThePolicySentKeepsItsTierSoASeenEntityIsPrecise) {
    const ListView world({at(1, {0, 0, 0}, 800.0f), at(2, {100, 0, 0}, 800.0f),
                          at(3, {200, 0, 0}, 800.0f), at(5, {300, 0, 0}, 800.0f),
                          at(7, {400, 0, 0}, 800.0f)});
    Hearing hearing;
    hearing.begin_tick(world);
    const Denying policy;
    // The policy saw 3 (near tier) and 7 (far tier); the viewer is entity 1.
    std::vector<Interest> out{{3, 0}, {7, 2}};
    EXPECT_EQ(hearing.add_heard(viewer_at({0, 0, 0}), policy, out), 2u);
    const std::vector<Interest> expected{{2, kHeardTier}, {3, 0}, {5, kHeardTier}, {7, 2}};
    EXPECT_EQ(out, expected); // its own entity 1 is not added, the order is kept
}

TEST(Hearing, APairThePolicyDeniesIsNotHeard) {
    const ListView world({at(2, {100, 0, 0}, 800.0f), at(3, {200, 0, 0}, 800.0f)});
    Hearing hearing;
    hearing.begin_tick(world);
    const Denying policy({3});
    std::vector<Interest> out;
    hearing.add_heard(viewer_at({0, 0, 0}, 9), policy, out);
    EXPECT_EQ(out, (std::vector<Interest>{{2, kHeardTier}}));
}

TEST(Hearing, AddsExactlyTheSoundingEntitiesWithinRangeTheAnswerLacks) {
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> coord(-3000.0f, 3000.0f);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::size_t added = 0;
    std::size_t kept_out = 0;
    for (int round = 0; round < 200; ++round) {
        std::vector<EntityView> entities;
        for (std::uint32_t id = 1; id <= 120; ++id) {
            const float u = unit(rng);
            const float range = u < 0.4f ? 0.0f : (u < 0.8f ? 800.0f : 1330.0f);
            entities.push_back(at(id * 3, {coord(rng), coord(rng), coord(rng) * 0.1f}, range));
        }
        const ListView world(entities);
        Hearing hearing;
        hearing.begin_tick(world);
        const Viewer viewer = viewer_at({coord(rng), coord(rng), 0.0f}, entities[7].id);
        // Answers from empty to everything, and a few denied pairs every other round.
        const float sent_share = round % 5 == 0 ? 0.0f : unit(rng);
        std::vector<Interest> sent;
        std::vector<std::uint32_t> denied;
        for (const EntityView& e : entities) {
            if (unit(rng) < sent_share) {
                sent.push_back({e.id, static_cast<std::uint8_t>(rng() % 3)});
            }
            if (round % 2 == 1 && unit(rng) < 0.05f) {
                denied.push_back(e.id);
            }
        }
        if (round % 5 == 1) { // answers of a few entries: most of the merge's parts empty
            sent.resize(std::min<std::size_t>(sent.size(), 1 + round % 7));
        }
        const Denying policy(denied);
        // The rule, plainly.
        std::vector<Interest> expected = sent;
        for (const EntityView& e : entities) {
            const bool in_set = std::any_of(sent.begin(), sent.end(),
                                            [&](const Interest& i) { return i.id == e.id; });
            const bool is_denied = std::find(denied.begin(), denied.end(), e.id) != denied.end();
            if (e.sound_range > 0.0f && !in_set && e.id != viewer.entity_id && !is_denied &&
                within_radius(e.box, viewer.eye, e.sound_range)) {
                expected.push_back({e.id, kHeardTier});
            }
            kept_out +=
                e.sound_range > 0.0f && !in_set && !within_radius(e.box, viewer.eye, e.sound_range);
        }
        std::sort(expected.begin(), expected.end(),
                  [](const Interest& a, const Interest& b) { return a.id < b.id; });
        std::vector<Interest> out = sent;
        const std::size_t added_now = hearing.add_heard(viewer, policy, out);
        ASSERT_EQ(out, expected) << "round " << round;
        ASSERT_EQ(added_now, expected.size() - sent.size()) << "round " << round;
        added += added_now;
    }
    // Both sides of the rule were met many times.
    EXPECT_GT(added, 500u);
    EXPECT_GT(kept_out, 1000u);
}

} // namespace
} // namespace dsoc::interest
