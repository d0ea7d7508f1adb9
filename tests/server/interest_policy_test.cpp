#include "dsoc/interest/culling_policy.hpp"
#include "dsoc/interest/hearing.hpp"
#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/server/interest_setup.hpp"
#include "support/test_maps.hpp"

#include "dsoc/maps/map_source.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <memory>
#include <optional>
#include <string>

namespace dsoc::server {
namespace {

using interest::BroadcastPolicy;
using interest::DistancePolicy;
using interest::Entity;
using interest::GameWorld;
using interest::Interest;
using interest::PvsPolicy;
using interest::Viewer;

bool contains(const std::vector<Interest>& set, std::uint32_t id) {
    return std::any_of(set.begin(), set.end(), [&](const Interest& i) { return i.id == id; });
}

ServerConfig bots(int n) {
    ServerConfig c;
    c.bots = n;
    c.baked_stage = false; // the exact stages unless a test asks for the table
    return c;
}

/// 200 bots, policy `kind`, and `distance`'s radius (the hiding policies' tests).
ServerConfig bots_under(interest::PolicyKind kind, float distance_radius) {
    ServerConfig c = bots(200);
    c.policy = kind;
    c.distance_radius = distance_radius;
    return c;
}

/// oa_dm4, or null when it is not installed (the caller skips).
std::shared_ptr<const maps::Map> oa_dm4() {
    auto loaded = maps::load_map("oa_dm4", maps::MapSearch::from_environment());
    return loaded ? std::make_shared<const maps::Map>(std::move(loaded).value()) : nullptr;
}
constexpr const char* kNoOaDm4 = "oa_dm4 not available (scripts/setup installs openarena-081-maps)";

/// The policies a rule beyond sight must hold for: every one that can hide something.
constexpr interest::PolicyKind kHidingPolicies[] = {
    interest::PolicyKind::distance, interest::PolicyKind::pvs, interest::PolicyKind::dsoc,
    interest::PolicyKind::occlusion};

TEST(InterestPolicy, BroadcastSelectsEverything) {
    GameWorld world(world_settings(bots(25)), testing::rooms_map());
    BroadcastPolicy policy;
    std::vector<Interest> out;
    policy.begin_tick(world, 1);
    policy.select(world, Viewer{1, 1, {0, 0, 0}}, out);
    EXPECT_EQ(out.size(), 25u);
    EXPECT_TRUE(std::is_sorted(out.begin(), out.end(),
                               [](const Interest& a, const Interest& b) { return a.id < b.id; }));
}

TEST(InterestPolicy, DistanceKeepsExactlyTheEntitiesWithinRadius) {
    GameWorld world(world_settings(bots(300)), testing::rooms_map());
    for (int i = 0; i < 60; ++i) { // let the bots spread out
        world.step(1.0f / 30.0f);
    }
    const float radius = 1000.0f;
    DistancePolicy policy(radius);
    std::vector<Interest> out;
    const glm::vec3 eye = world.eye_of(world.entities().front());
    policy.begin_tick(world, 60);
    policy.select(world, Viewer{1, 0, eye}, out);
    std::size_t expected = 0;
    for (const Entity& e : world.entities()) {
        const auto box = world.box_of(e);
        const bool inside = glm::length(glm::clamp(eye, box.min, box.max) - eye) <= radius;
        expected += inside ? 1 : 0;
        EXPECT_EQ(contains(out, e.id), inside) << "entity " << e.id;
    }
    EXPECT_EQ(out.size(), expected);
    // The policy must actually cull something in this world, and keep something.
    EXPECT_LT(out.size(), world.entities().size());
    EXPECT_GT(out.size(), 0u);
}

/// oa_dm4 with 200 bots after 3 s of wandering (skipped when the map is not installed).
class InterestPolicyOnOaDm4 : public ::testing::Test {
protected:
    void SetUp() override {
        auto loaded = maps::load_map("oa_dm4", maps::MapSearch::from_environment());
        if (!loaded) {
            GTEST_SKIP() << "oa_dm4 not available (scripts/setup installs openarena-081-maps): "
                         << loaded.error().message();
        }
        map_ = std::make_shared<const maps::Map>(std::move(loaded).value());
        world_ = std::make_unique<GameWorld>(world_settings(bots(200)), map_);
        for (int i = 0; i < 90; ++i) {
            world_->step(1.0f / 30.0f);
        }
    }
    std::shared_ptr<const maps::Map> map_;
    std::unique_ptr<GameWorld> world_;
};

/// One tick of `config`'s policy for the first 16 entities as viewers: each viewer's
/// set, and their total size.
struct ViewerSets {
    std::vector<std::vector<Interest>> sets;
    std::size_t total = 0;
};
ViewerSets sets_of(const ServerConfig& config, const GameWorld& world) {
    auto policy = make_policy(config, world);
    for (std::uint32_t v = 0; v < 16; ++v) {
        policy->add_viewer(v, world.entities()[v].id);
    }
    policy->begin_tick(world, 1);
    ViewerSets out;
    for (std::uint32_t v = 0; v < 16; ++v) {
        const Entity& viewer = world.entities()[v];
        std::vector<Interest> set;
        policy->select(world, Viewer{v, viewer.id, world.eye_of(viewer)}, set);
        out.total += set.size();
        out.sets.push_back(std::move(set));
    }
    return out;
}

/// Every viewer's `smaller` set is part of its `larger` set.
void expect_subsets(const ViewerSets& smaller, const ViewerSets& larger) {
    for (std::size_t v = 0; v < smaller.sets.size(); ++v) {
        for (const Interest& i : smaller.sets[v]) {
            EXPECT_TRUE(contains(larger.sets[v], i.id)) << "viewer " << v << " entity " << i.id;
        }
    }
}

TEST_F(InterestPolicyOnOaDm4, PvsKeepsTheViewersClusterAndCullsOthers) {
    const GameWorld& world = *world_;
    const std::shared_ptr<const maps::Map>& map = map_;
    PvsPolicy policy(map->pvs);
    policy.begin_tick(world, 1);
    std::size_t total = 0;
    std::vector<std::int32_t> clusters;
    std::vector<std::int32_t> scratch;
    std::vector<std::uint8_t> rows;
    for (int v = 0; v < 20; ++v) {
        const Entity& viewer = world.entities()[static_cast<std::size_t>(v)];
        std::vector<Interest> out;
        policy.select(world, Viewer{1, viewer.id, world.eye_of(viewer)}, out);
        EXPECT_TRUE(contains(out, viewer.id)) << "own cluster";
        total += out.size();
        // The clusters cached per tick give exactly the answer of asking the PVS about
        // every entity's box directly (what the policy did before the cache).
        const glm::vec3 eye = world.eye_of(viewer);
        ASSERT_TRUE(map->pvs->clusters_of(visibility::Aabb{eye, eye}, clusters));
        map->pvs->union_of_rows(clusters, rows);
        std::vector<Interest> direct;
        for (const Entity& e : world.entities()) {
            if (map->pvs->may_see(rows, world.box_of(e), scratch)) {
                direct.push_back({e.id, 0});
            }
        }
        EXPECT_EQ(out, direct) << "viewer " << viewer.id;
    }
    // The map's vis data culls a good share on oa_dm4 (latency-safety.md: ~45% pass).
    EXPECT_LT(total, 20u * world.entities().size() * 8 / 10);
    EXPECT_GT(total, 20u * world.entities().size() / 10);
}

TEST_F(InterestPolicyOnOaDm4, PortalDepthReachesTheCullerAndOnlyAddsProofs) {
    const GameWorld& world = *world_;
    // `occlusion`: no temporal coherence, so each set is this tick's culler verdict.
    ViewerSets runs[2];
    for (int k = 0; k < 2; ++k) {
        ServerConfig config = bots(200);
        config.policy = interest::PolicyKind::occlusion;
        config.portal_depth = k == 0 ? 0 : 2;
        runs[k] = sets_of(config, world);
    }
    expect_subsets(runs[1], runs[0]);
    EXPECT_LT(runs[1].total, runs[0].total) << "portal tests hide more on oa_dm4";
}

TEST_F(InterestPolicyOnOaDm4, BakedStageOnlyAddsProofsAndAloneCullsLess) {
    const GameWorld& world = *world_;
    const auto dir = std::filesystem::temp_directory_path() / "dsoc-interest-policy-bakes";
    std::filesystem::remove_all(dir);
    // 0: PVS + shaft; 1: baked table + PVS + shaft; 2: the baked table alone.
    ViewerSets runs[3];
    for (int k = 0; k < 3; ++k) {
        ServerConfig config = bots(200);
        config.policy = interest::PolicyKind::occlusion; // each set is this tick's culler verdict
        config.baked_stage = k > 0;
        config.exact_stages = k < 2 ? interest::ExactStages::always : interest::ExactStages::never;
        config.bake_cell_size = 96.0f; // a coarse table bakes in seconds
        config.bake_dir = dir.string();
        // Behind the table alone the manager groups no entities (docs/dsoc.md, "When TBVs
        // pay"); a group's box seen sends all of it, so the runs compare each box alone.
        config.dsoc.push_back({"entity_cluster_size", "0", "test"});
        config.insecure = true; // validate() wants a key otherwise
        const auto problems = validate(config);
        ASSERT_TRUE(problems.empty()) << problems.front();
        runs[k] = sets_of(config, world);
    }
    expect_subsets(runs[1], runs[0]);
    expect_subsets(runs[1], runs[2]);
    const std::size_t totals[3] = {runs[0].total, runs[1].total, runs[2].total};
    EXPECT_LE(totals[1], totals[0]);
    EXPECT_GE(totals[2], totals[1]);
    // The table alone culls too (about a third at these coarse 96-unit cells).
    EXPECT_LT(totals[2], 16u * world.entities().size() * 8 / 10);
    std::printf("16 viewers on oa_dm4: PVS + shaft %zu, table + PVS + shaft %zu, table alone %zu "
                "of %zu pairs\n",
                totals[0], totals[1], totals[2], 16u * world.entities().size());
    std::filesystem::remove_all(dir);
}

TEST(InterestPolicy, ExactStagesAutoFollowATableOnlyWhenTheBakeHadToCoarsenItsCells) {
    const auto table_of = [](float cell_size) {
        const visibility::CellGrid grid = visibility::CellGrid::covering(
            visibility::Aabb{glm::vec3(0.0f), glm::vec3(256.0f)}, cell_size);
        return visibility::CellVisibilityTable(grid, {0});
    };
    ServerConfig config;
    config.bake_cell_size = 32.0f;
    EXPECT_FALSE(
        use_exact_stages(policy_settings(config), table_of(32.0f))); // as fine as asked: alone
    EXPECT_TRUE(
        use_exact_stages(policy_settings(config), table_of(40.0f))); // grown to fit: exact too
    config.exact_stages = interest::ExactStages::never;
    EXPECT_FALSE(use_exact_stages(policy_settings(config), table_of(40.0f)));
    config.exact_stages = interest::ExactStages::always;
    EXPECT_TRUE(use_exact_stages(policy_settings(config), table_of(32.0f)));
}

TEST(GameWorld, EntitiesNeverExceedMaxSpeedHorizontally) {
    GameWorld world(world_settings(bots(50)), testing::rooms_map());
    const auto player = world.spawn_player();
    world.set_player_input(player, {10.0f, 10.0f, 0.0f}, true, 720.0f, 200.0f);
    const float dt = 1.0f / 30.0f;
    for (int t = 0; t < 300; ++t) {
        std::vector<glm::vec3> before;
        for (const auto& e : world.entities()) {
            before.push_back(e.move.position);
        }
        world.step(dt);
        for (std::size_t i = 0; i < before.size(); ++i) {
            const auto& e = world.entities()[i];
            if (e.teleported) {
                continue;
            }
            const glm::vec3 d = e.move.position - before[i];
            ASSERT_LE(std::sqrt(d.x * d.x + d.y * d.y), world.max_speed() * dt * 1.001f);
        }
    }
    const Entity* p = world.find(player);
    ASSERT_NE(p, nullptr);
    EXPECT_GE(p->yaw_deg, -180.0f);
    EXPECT_LT(p->yaw_deg, 180.0f);
    EXPECT_EQ(p->pitch_deg, 90.0f);
}

} // namespace
} // namespace dsoc::server

namespace dsoc::server {
namespace {

std::vector<std::uint32_t> ids_of(const std::vector<Interest>& set) {
    std::vector<std::uint32_t> ids;
    for (const Interest& i : set) {
        ids.push_back(i.id);
    }
    return ids;
}

std::vector<std::uint32_t> union_of(const std::vector<std::uint32_t>& a,
                                    const std::vector<std::uint32_t>& b) {
    std::vector<std::uint32_t> out;
    std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
    return out;
}

/// oa_dm4 with a pit under the first player's spawn point: the player dies on its
/// first step, bound for the next spawn point (the world's respawn delay is the
/// latency allowance: world_settings()).
struct DyingViewer {
    std::shared_ptr<const maps::Map> map;
    std::unique_ptr<GameWorld> world;
    std::uint32_t player = 0;
};

std::optional<DyingViewer> dying_viewer_on_oa_dm4() {
    auto loaded = maps::load_map("oa_dm4", maps::MapSearch::from_environment());
    if (!loaded) {
        return std::nullopt;
    }
    auto map = std::make_shared<maps::Map>(std::move(loaded).value());
    const interest::WorldSettings settings = world_settings(bots(200));
    DyingViewer d;
    d.map = map;
    d.world = std::make_unique<GameWorld>(settings, map);
    // After the world chose its spawn points (it leaves out any in a hazard), so that
    // the player is put into the pit.
    testing::add_pit_at_spawn(*map, settings.seed % map->spawn_points.size());
    d.player = d.world->spawn_player();
    return d;
}

TEST(InterestPolicyWhileRespawning, EveryPolicyAnswersForTheEyeNowAndTheArrivalEye) {
    for (const auto kind :
         {interest::PolicyKind::distance, interest::PolicyKind::pvs, interest::PolicyKind::dsoc}) {
        SCOPED_TRACE(std::string(interest::name_of(kind)));
        auto dying = dying_viewer_on_oa_dm4();
        if (!dying) {
            GTEST_SKIP() << "oa_dm4 not available (scripts/setup installs openarena-081-maps)";
        }
        GameWorld& world = *dying->world;
        ServerConfig config = bots_under(kind, 600.0f);
        auto policy = make_policy(config, world);
        constexpr std::uint32_t kClient = 3;
        policy->add_viewer(kClient, dying->player);
        const int delay = lookahead_ticks(config);
        ASSERT_GE(delay, 1);
        for (int tick = 1; tick <= delay + 1; ++tick) {
            world.step(1.0f / 30.0f);
            policy->begin_tick(world, static_cast<std::uint64_t>(tick));
            const Entity& self = *world.find(dying->player);
            const Viewer viewer = interest::viewer_of(world, kClient, self);
            std::vector<Interest> both;
            policy->select(world, viewer, both);
            ASSERT_TRUE(std::is_sorted(both.begin(), both.end(),
                                       [](const auto& a, const auto& b) { return a.id < b.id; }));
            if (tick > delay) { // put at its spawn point: one eye again
                EXPECT_TRUE(self.teleported);
                EXPECT_FALSE(viewer.arrival_eye.has_value());
                if (kind == interest::PolicyKind::dsoc) {
                    const auto& manager =
                        dynamic_cast<const interest::CullingPolicy&>(*policy).manager();
                    EXPECT_EQ(
                        manager.decisions(kClient | interest::CullingPolicy::kArrivalClientBit),
                        nullptr);
                }
                continue;
            }
            ASSERT_TRUE(viewer.arrival_eye.has_value()) << "tick " << tick;
            // What the viewer is sent for each eye alone.
            std::vector<std::uint32_t> now;
            std::vector<std::uint32_t> arrival;
            if (kind == interest::PolicyKind::dsoc) {
                const auto& manager =
                    dynamic_cast<const interest::CullingPolicy&>(*policy).manager();
                const auto* spectator =
                    manager.decisions(kClient | interest::CullingPolicy::kArrivalClientBit);
                ASSERT_NE(spectator, nullptr);
                EXPECT_TRUE(manager.eye_region(kClient | interest::CullingPolicy::kArrivalClientBit)
                                .contains(*viewer.arrival_eye));
                for (const auto& r : manager.decisions(kClient)->replicated) {
                    now.push_back(r.id);
                }
                for (const auto& r : spectator->replicated) {
                    arrival.push_back(r.id);
                }
            } else {
                std::vector<Interest> one;
                Viewer eye_only = viewer;
                eye_only.arrival_eye.reset();
                policy->select(world, eye_only, one);
                now = ids_of(one);
                Viewer arrival_only = viewer;
                arrival_only.eye = *viewer.arrival_eye;
                arrival_only.arrival_eye.reset();
                policy->select(world, arrival_only, one);
                arrival = ids_of(one);
            }
            EXPECT_EQ(ids_of(both), union_of(now, arrival)) << "tick " << tick;
            // The arrival matters here: the two spawn points see different entities.
            EXPECT_GT(ids_of(both).size(), now.size()) << "tick " << tick;
        }
    }
}

} // namespace
} // namespace dsoc::server

namespace dsoc::server {
namespace {

/// Two worlds alike but for one setting (`plain` and `varied`, both on oa_dm4), each with
/// the policy they ask for and the same kViewers viewers (entity v * 25 for client v):
/// what a rule beyond sight adds is the difference between the two.
struct TwinWorlds {
    static constexpr std::uint32_t kViewers = 8;
    GameWorld plain_world;
    GameWorld varied_world;
    std::unique_ptr<interest::InterestPolicy> plain;
    std::unique_ptr<interest::InterestPolicy> varied;

    TwinWorlds(const ServerConfig& plain_config, const ServerConfig& varied_config,
               const std::shared_ptr<const maps::Map>& map)
        : plain_world(world_settings(plain_config), map),
          varied_world(world_settings(varied_config), map),
          plain(make_policy(plain_config, plain_world)),
          varied(make_policy(varied_config, varied_world)) {
        for (std::uint32_t v = 0; v < kViewers; ++v) {
            plain->add_viewer(v, plain_world.entities()[v * 25].id);
            varied->add_viewer(v, varied_world.entities()[v * 25].id);
        }
    }
    /// Both worlds one 30 Hz step on, and both policies' begin_tick(`tick`).
    void step(int tick) {
        plain_world.step(1.0f / 30.0f);
        varied_world.step(1.0f / 30.0f);
        plain->begin_tick(plain_world, static_cast<std::uint64_t>(tick));
        varied->begin_tick(varied_world, static_cast<std::uint64_t>(tick));
    }
    /// Viewer `v`'s entity in the varied world.
    [[nodiscard]] const Entity& self(std::uint32_t v) const {
        return varied_world.entities()[v * 25];
    }
    /// What the plain world's policy sends viewer `v` this tick.
    [[nodiscard]] std::vector<Interest> plain_set(std::uint32_t v) {
        std::vector<Interest> out;
        plain->select(plain_world,
                      interest::viewer_of(plain_world, v, plain_world.entities()[v * 25]), out);
        return out;
    }
};

TEST(InterestPolicyWithTeams, EveryPolicySendsTheViewersTeammatesOverWhatItSees) {
    // Two worlds alike but for teams; each viewer's set with teams must be its set
    // without them plus every teammate (relevance.hpp's team rule), and some teammates
    // must be ones sight alone would not send.
    const auto map = oa_dm4();
    if (!map) {
        GTEST_SKIP() << kNoOaDm4;
    }
    for (const auto kind : kHidingPolicies) {
        SCOPED_TRACE(std::string(interest::name_of(kind)));
        ServerConfig config = bots_under(kind, 800.0f);
        ServerConfig teamed = config;
        teamed.teams = 2;
        TwinWorlds twins(config, teamed, map);
        std::size_t teammates_unseen = 0;
        for (int tick = 1; tick <= 30; ++tick) {
            twins.step(tick);
            for (std::uint32_t v = 0; v < TwinWorlds::kViewers; ++v) {
                const Entity& self = twins.self(v);
                ASSERT_NE(self.team, visibility::kNoTeam);
                std::vector<Interest> sent;
                twins.varied->select(twins.varied_world,
                                     interest::viewer_of(twins.varied_world, v, self), sent);
                const std::vector<std::uint32_t> expected = ids_of(twins.plain_set(v));
                std::vector<std::uint32_t> teammates;
                for (const Entity& e : twins.varied_world.entities()) {
                    if (e.team == self.team) {
                        teammates.push_back(e.id);
                        teammates_unseen +=
                            std::binary_search(expected.begin(), expected.end(), e.id) ? 0 : 1;
                    }
                }
                ASSERT_EQ(ids_of(sent), union_of(expected, teammates))
                    << "tick " << tick << " viewer " << v;
            }
        }
        EXPECT_GT(teammates_unseen, 0u) << "no teammate was sent that sight would not send";
    }
}

TEST(InterestPolicyWithSounds, EveryPolicySendsWhatTheViewerHearsCoarseAndWhatItSeesPrecise) {
    // Two worlds alike but for sounds (sounds never move anything): each viewer's set
    // with sounds must be its set without them plus every sounding entity within its
    // sound's range of the eye, those on the heard tier; what sight sends keeps its tier,
    // so an entity heard, then seen, turns precise the tick it is seen.
    const auto map = oa_dm4();
    if (!map) {
        GTEST_SKIP() << kNoOaDm4;
    }
    for (const auto kind : kHidingPolicies) {
        SCOPED_TRACE(std::string(interest::name_of(kind)));
        ServerConfig config = bots_under(kind, 600.0f);
        config.sounds = false;
        config.shot_damage = 0; // the loud world's shots must not move anyone: twins
        ServerConfig loud = config;
        loud.sounds = true;
        loud.bot_shots_per_second = 1.0f;
        TwinWorlds twins(config, loud, map);
        interest::Hearing hearing;
        std::size_t heard_only = 0;
        std::size_t turned_precise = 0;
        std::vector<std::vector<std::uint32_t>> heard_before(TwinWorlds::kViewers);
        for (int tick = 1; tick <= 45; ++tick) {
            twins.step(tick);
            hearing.begin_tick(twins.varied_world);
            for (std::uint32_t v = 0; v < TwinWorlds::kViewers; ++v) {
                const Viewer viewer = interest::viewer_of(twins.varied_world, v, twins.self(v));
                const std::vector<Interest> seen = twins.plain_set(v);
                std::vector<Interest> sent;
                twins.varied->select(twins.varied_world, viewer, sent);
                hearing.add_heard(viewer, *twins.varied, sent);
                std::vector<std::uint32_t> heard;
                for (std::size_t i = 0; i < twins.varied_world.entity_count(); ++i) {
                    const interest::EntityView e = twins.varied_world.entity(i);
                    if (e.sound_range > 0.0f && e.id != viewer.entity_id && !contains(seen, e.id) &&
                        interest::within_radius(e.box, viewer.eye, e.sound_range)) {
                        heard.push_back(e.id);
                    }
                }
                ASSERT_EQ(ids_of(sent), union_of(ids_of(seen), heard))
                    << "tick " << tick << " viewer " << v;
                for (const Interest& i : sent) {
                    const bool only_heard = std::binary_search(heard.begin(), heard.end(), i.id);
                    EXPECT_EQ(i.tier == interest::kHeardTier, only_heard) << "entity " << i.id;
                    turned_precise +=
                        !only_heard &&
                        std::binary_search(heard_before[v].begin(), heard_before[v].end(), i.id);
                }
                heard_only += heard.size();
                heard_before[v] = heard;
            }
        }
        EXPECT_GT(heard_only, 0u) << "nothing was heard that sight would not send";
        EXPECT_GT(turned_precise, 0u) << "no heard entity was seen the next tick";
    }
}

} // namespace
} // namespace dsoc::server
