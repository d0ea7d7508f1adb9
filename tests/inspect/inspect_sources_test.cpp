// The inspector's inputs: a live run of the server's world and dsoc policy on a small
// generated map, drawn and decoded pixel by pixel; and a hand-written trace whose
// replicated entities are split by what the eye can see.

#include "dsoc/inspect/live_source.hpp"
#include "dsoc/inspect/plan_view.hpp"
#include "dsoc/inspect/png_io.hpp"
#include "dsoc/inspect/trace_source.hpp"
#include "dsoc/trace/trace_writer.hpp"
#include "support/test_maps.hpp"
#include "through_png.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace dsoc::inspect {
namespace {

using visibility::Aabb;

TEST(LiveSource, RoomsMapStatesAreConsistentAndDrawnInTheirColours) {
    const auto map = dsoc::testing::rooms_map();
    LiveOptions options;
    options.bots = 60;
    options.viewer_entity = 3;
    options.tbvs = true; // every state is drawn, TBVs included
    LiveSimulation sim(map, options);
    for (int t = 0; t < 45; ++t) {
        sim.advance();
    }
    const ClientView view = sim.view();
    EXPECT_EQ(view.tick, 45u);
    ASSERT_EQ(view.entities.size(), 59u);
    ASSERT_FALSE(view.eye_region.is_empty());
    EXPECT_TRUE(view.eye_region.contains(view.eye));
    std::size_t replicated = 0;
    std::size_t hidden = 0;
    std::size_t heard = 0;
    std::size_t with_tbv = 0;
    for (const EntityView& e : view.entities) {
        EXPECT_NE(e.id, options.viewer_entity);
        if (e.state == EntityState::hidden_tbv) {
            ++with_tbv;
            EXPECT_TRUE(e.tbv.contains(e.box)) << "entity " << e.id << " outside its TBV";
        } else {
            EXPECT_TRUE(e.tbv.is_empty());
        }
        const bool is_replicated = e.state == EntityState::replicated_visible ||
                                   e.state == EntityState::replicated_lookahead ||
                                   e.state == EntityState::replicated_held;
        (is_replicated ? replicated : hidden) += 1;
        heard += e.state == EntityState::replicated_heard ? 1 : 0;
    }
    // Walls between rooms: some bots are hidden, some (at least in the own room) not,
    // and some hidden ones are heard running (the world's sounds are on by default).
    EXPECT_GT(hidden, 0u);
    EXPECT_GT(with_tbv, 0u);
    EXPECT_GT(replicated, 0u);
    EXPECT_GT(heard, 0u);

    PlanStyle style;
    style.units_per_pixel = 4.0f;
    style.cut_above = view.eye.z + 64.0f; // below the rooms' ceiling
    const Image rendered = render_plan(footprints(map->occluders), map->bounds, view, style);
    const Image image = testing::through_png(rendered, "dsoc_inspect_live_test.png");
    const PlanFrame frame(map->bounds, style);
    EXPECT_EQ(image.width(), frame.width());
    EXPECT_EQ(image.height(), frame.height());

    // Every entity standing clear of the others and of the eye cross shows its colour.
    std::vector<Aabb> all{view.viewer_box.expanded(glm::vec3(24.0f, 24.0f, 0.0f))};
    for (const EntityView& e : view.entities) {
        all.push_back(e.box);
    }
    std::size_t checked = 0;
    for (const EntityView& e : view.entities) {
        const Aabb clearance = e.box.expanded(glm::vec3(8.0f, 8.0f, 1.0e6f));
        const auto overlapping = std::count_if(
            all.begin(), all.end(), [&](const Aabb& b) { return b.overlaps(clearance); });
        if (overlapping > 1) { // itself
            continue;
        }
        const glm::vec3 c = e.box.center();
        EXPECT_EQ(image.at(frame.pixel_x(c.x), frame.pixel_y(c.y)), kPalette.of(e.state))
            << "entity " << e.id << " " << to_string(e.state);
        ++checked;
    }
    EXPECT_GT(checked, 10u);
    EXPECT_EQ(image.at(frame.pixel_x(view.eye.x), frame.pixel_y(view.eye.y)), kPalette.viewer);
}

TEST(LiveSource, RefusesOptionsItCannotRun) {
    LiveOptions bad;
    bad.policy = interest::PolicyKind::distance;
    bad.viewer_entity = 0;
    const auto problems = validate(bad);
    ASSERT_EQ(problems.size(), 2u);
    EXPECT_NE(problems[0].find("policy"), std::string::npos);
    EXPECT_NE(problems[1].find("client 0"), std::string::npos);
    EXPECT_THROW(LiveSimulation(dsoc::testing::rooms_map(), bad), std::invalid_argument);

    // TBVs are dsoc's alone: asked of the occlusion policy, refused, not ignored.
    LiveOptions tbvs_without_dsoc;
    tbvs_without_dsoc.policy = interest::PolicyKind::occlusion;
    tbvs_without_dsoc.tbvs = true;
    const auto tbv_problems = validate(tbvs_without_dsoc);
    ASSERT_EQ(tbv_problems.size(), 1u);
    EXPECT_NE(tbv_problems[0].find("only dsoc has TBVs"), std::string::npos);
    tbvs_without_dsoc.policy = interest::PolicyKind::dsoc;
    EXPECT_TRUE(validate(tbvs_without_dsoc).empty());
}

TEST(TraceSource, SplitsReplicatedByWhatTheEyeSees) {
    // A wall at x in [100, 120]; the eye at the origin. Entity 1 is in the open, 2
    // behind the wall, 3 in the open but not replicated, 4 and 5 behind the wall and
    // sent for hearing and for the team; entity 9 is the client's own.
    trace::TraceHeader header;
    header.map = "test";
    header.policy = "dsoc";
    header.lookahead_ticks = 5;
    const auto wall = visibility::ConvexPolyhedron::from_aabb({{100, -500, -500}, {120, 500, 500}});
    header.occluders.push_back({0, wall.planes()});
    const std::string path =
        (std::filesystem::temp_directory_path() / "dsoc_inspect_trace_test.jsonl").string();
    {
        trace::TraceWriter writer;
        std::string error;
        ASSERT_TRUE(writer.open(path, header, error)) << error;
        for (std::uint64_t t : {3u, 6u}) {
            trace::TraceTick tick;
            tick.t = t;
            tick.entities = {
                {9, Aabb{{-10, -10, -30}, {10, 10, 30}}}, {1, Aabb{{-200, 0, 0}, {-180, 20, 20}}},
                {2, Aabb{{300, 0, 0}, {320, 20, 20}}},    {3, Aabb{{0, 200, 0}, {20, 220, 20}}},
                {4, Aabb{{300, 100, 0}, {320, 120, 20}}}, {5, Aabb{{300, 200, 0}, {320, 220, 20}}}};
            tick.clients = {{7, 9u, glm::vec3(0.0f), {1, 2, 4, 5}, std::nullopt, {5}, {}, {4}}};
            ASSERT_TRUE(writer.write_tick(tick));
        }
        ASSERT_TRUE(writer.close());
    }
    TraceSource source;
    std::string error;
    ASSERT_TRUE(source.open(path, error)) << error;
    ASSERT_EQ(source.occluders().size(), 1u);
    ClientView view;
    ASSERT_TRUE(source.next_view(4, 7u, view, error)) << error;
    EXPECT_EQ(view.tick, 6u);
    EXPECT_EQ(view.client, 7u);
    ASSERT_TRUE(view.viewer_entity.has_value());
    EXPECT_EQ(*view.viewer_entity, 9u);
    EXPECT_TRUE(view.eye_region.is_empty());
    ASSERT_EQ(view.entities.size(), 5u);
    EXPECT_EQ(view.entities[0].state, EntityState::replicated_visible);
    EXPECT_EQ(view.entities[1].state, EntityState::replicated_lookahead);
    EXPECT_EQ(view.entities[2].state, EntityState::not_replicated);
    EXPECT_EQ(view.entities[3].state, EntityState::replicated_heard);
    EXPECT_EQ(view.entities[4].state, EntityState::replicated_rule);
    EXPECT_FALSE(source.next_view(7, 7u, view, error));
    EXPECT_EQ(error, "");
    std::filesystem::remove(path);

    TraceSource missing;
    EXPECT_FALSE(missing.open(path, error));
    EXPECT_FALSE(error.empty());
}

} // namespace
} // namespace dsoc::inspect
