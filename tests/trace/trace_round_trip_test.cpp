#include "dsoc/trace/trace_reader.hpp"
#include "dsoc/trace/trace_writer.hpp"

#include "support/temp_dir.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace dsoc::trace {
namespace {

TEST(Trace, WritesExactlyTheSpecFieldsAndReadsThemBack) {
    const std::string path = testing::run_temp_path("dsoc-trace", ".jsonl");
    TraceHeader header;
    header.map = "oa_dm4";
    header.tick_rate = 30;
    header.policy = "dsoc";
    header.lookahead_ticks = 3;
    header.occluders.push_back({0,
                                {{{1, 0, 0}, 8},
                                 {{-1, 0, 0}, 8},
                                 {{0, 1, 0}, 100},
                                 {{0, -1, 0}, 100},
                                 {{0, 0, 1}, 50},
                                 {{0, 0, -1}, 0.1f}}});
    std::string error;
    {
        TraceWriter w;
        ASSERT_TRUE(w.open(path, header, error)) << error;
        for (std::uint64_t t = 10; t <= 30; t += 10) {
            TraceTick tick;
            tick.t = t;
            tick.entities.push_back({42, {{-15, -15, -24}, {15.5f, 15, 32}}});
            tick.entities.push_back({43, {{100, 0, 0}, {130, 30, 56}}});
            tick.clients.push_back({7, 42u, {0.1f, 0.2f, 26}, {43}, std::nullopt, {43}, {44}});
            tick.clients.push_back(
                {8, std::nullopt, {5, 5, 5}, {42}, glm::vec3(900, -4, 26.5f), {}, {}, {42}});
            ASSERT_TRUE(w.write_tick(tick));
        }
        TraceTick backwards;
        backwards.t = 15;
        EXPECT_FALSE(w.write_tick(backwards)); // must increase
        EXPECT_TRUE(w.close());
    }

    // Line by line, the spec's keys and nothing we invented.
    std::ifstream in(path);
    std::string first;
    std::getline(in, first);
    for (const char* key : {R"("type":"header")", R"("version":1)", R"("map":"oa_dm4")",
                            R"("tick_rate":30)", R"("policy":"dsoc")", R"("lookahead_ticks":3)",
                            R"("occluders":[{"id":0,"planes":[[1,0,0,8])"}) {
        EXPECT_NE(first.find(key), std::string::npos) << key << " in " << first;
    }
    EXPECT_EQ(first.find("patches"), std::string::npos) << "no patches, no key: " << first;
    std::string tick_line;
    std::getline(in, tick_line);
    EXPECT_EQ(
        tick_line.rfind(R"({"type":"tick","t":10,"entities":[[42,-15,-15,-24,15.5,15,32])", 0), 0u)
        << tick_line;
    EXPECT_NE(
        tick_line.find(
            R"({"id":7,"entity":42,"eye":[0.1,0.2,26],"replicated":[43],"always":[43],"never":[44]})"),
        std::string::npos);
    EXPECT_NE(
        tick_line.find(
            R"({"id":8,"entity":null,"eye":[5,5,5],"arrival":[900,-4,26.5],"replicated":[42],"heard":[42]})"),
        std::string::npos)
        << tick_line;

    TraceReader r;
    ASSERT_TRUE(r.open(path)) << r.error();
    EXPECT_EQ(r.header().map, "oa_dm4");
    EXPECT_EQ(r.header().lookahead_ticks, 3);
    ASSERT_EQ(r.header().occluders.size(), 1u);
    EXPECT_EQ(r.header().occluders[0].planes.size(), 6u);
    EXPECT_EQ(r.header().occluders[0].planes[5].distance, 0.1f);
    TraceTick tick;
    int ticks = 0;
    while (r.next(tick)) {
        ++ticks;
        ASSERT_EQ(tick.entities.size(), 2u);
        EXPECT_EQ(tick.entities[0].box.max.x, 15.5f);
        ASSERT_EQ(tick.clients.size(), 2u);
        EXPECT_EQ(tick.clients[0].entity, 42u);
        EXPECT_EQ(tick.clients[0].eye.x, 0.1f);
        EXPECT_EQ(tick.clients[0].replicated, std::vector<std::uint32_t>{43});
        EXPECT_FALSE(tick.clients[1].entity.has_value());
        EXPECT_FALSE(tick.clients[0].arrival.has_value());
        EXPECT_EQ(tick.clients[0].always, std::vector<std::uint32_t>{43});
        EXPECT_EQ(tick.clients[0].never, std::vector<std::uint32_t>{44});
        EXPECT_TRUE(tick.clients[1].always.empty());
        EXPECT_TRUE(tick.clients[0].heard.empty());
        EXPECT_EQ(tick.clients[1].heard, std::vector<std::uint32_t>{42});
        EXPECT_EQ(tick.clients[1].arrival, std::optional<glm::vec3>(glm::vec3(900, -4, 26.5f)));
    }
    EXPECT_TRUE(r.error().empty()) << r.error();
    EXPECT_TRUE(r.finished());
    EXPECT_EQ(ticks, 3);
    std::filesystem::remove(path);
}

TEST(Trace, CarriesTheMapsOpaquePatches) {
    const std::string path = testing::run_temp_path("dsoc-trace-patches", ".jsonl");
    TraceHeader header;
    header.map = "pul1ctf";
    header.policy = std::string("p\x01v\"s"); // a control character and a quote read back
    TracePatch patch{3, 5, {}};
    for (int i = 0; i < 15; ++i) {
        patch.points.emplace_back(static_cast<float>(i), 0.5f, -2.0f);
    }
    header.patches.push_back(patch);
    std::string error;
    {
        TraceWriter w;
        ASSERT_TRUE(w.open(path, header, error)) << error;
        EXPECT_TRUE(w.close());
    }
    std::ifstream in(path);
    std::string first;
    std::getline(in, first);
    EXPECT_NE(first.find(R"("patches":[{"width":3,"height":5,"points":[[0,0.5,-2],[1,0.5,-2])"),
              std::string::npos)
        << first;
    TraceReader r;
    ASSERT_TRUE(r.open(path)) << r.error();
    EXPECT_EQ(r.header().policy, header.policy);
    ASSERT_EQ(r.header().patches.size(), 1u);
    EXPECT_EQ(r.header().patches[0].height, 5);
    EXPECT_EQ(r.header().patches[0].points, patch.points);

    // A header without patches has no key; malformed patches are named.
    const auto header_with = [&](const std::string& patches) {
        std::ofstream out(path);
        out << R"({"type":"header","version":1,"map":"m","tick_rate":30,"policy":"p",)"
            << R"("lookahead_ticks":0,"occluders":[],"patches":)" << patches << "}\n";
    };
    const std::pair<std::string, std::string> bad[] = {
        {R"({})", "patches must be an array"},
        {R"([{"width":4,"height":3,"points":[]}])",
         "patch 0 needs width and height (odd, 3 to 31)"},
        {R"([{"width":3,"height":3,"points":[[0,0,0]]}])", "patch 0: 1 points for 3 x 3"},
        {R"([{"width":3,"height":3,"points":[[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0]]}])",
         "patch 0: a point must be [x,y,z]"},
    };
    for (const auto& [text, fragment] : bad) {
        header_with(text);
        TraceReader reader;
        EXPECT_FALSE(reader.open(path)) << text;
        EXPECT_NE(reader.error().find(fragment), std::string::npos) << reader.error();
    }
    std::filesystem::remove(path);
}

TEST(Trace, ReaderNamesTheLineAndTheProblem) {
    const std::string path = testing::run_temp_path("dsoc-bad-trace", ".jsonl");
    {
        std::ofstream out(path);
        out << R"({"type":"header","version":1,"map":"m","tick_rate":30,"policy":"p","lookahead_ticks":0,"occluders":[]})"
            << "\n"
            << R"({"type":"tick","t":5,"entities":[[1,0,0,0,1,1]],"clients":[]})"
            << "\n";
    }
    TraceReader r;
    ASSERT_TRUE(r.open(path)) << r.error();
    TraceTick tick;
    EXPECT_FALSE(r.next(tick));
    EXPECT_NE(r.error().find(":2: tick: an entity must be"), std::string::npos) << r.error();

    {
        std::ofstream out(path);
        out << R"({"type":"header","version":1,"map":"m","tick_rate":30,"policy":"p","lookahead_ticks":0,"occluders":[]})"
            << "\n"
            << R"({"type":"tick","t":5,"entities":[],"clients":[{"id":3,"eye":[0,0,0],"arrival":[1,2],"replicated":[]}]})"
            << "\n";
    }
    TraceReader bad_arrival;
    ASSERT_TRUE(bad_arrival.open(path)) << bad_arrival.error();
    EXPECT_FALSE(bad_arrival.next(tick));
    EXPECT_NE(bad_arrival.error().find(":2: tick: client 3: arrival must be [x,y,z]"),
              std::string::npos)
        << bad_arrival.error();

    {
        std::ofstream out(path);
        out << R"({"type":30,"version":1})"
            << "\n"; // once threw out of the reader (fuzz_trace)
    }
    TraceReader not_a_string;
    EXPECT_FALSE(not_a_string.open(path));
    EXPECT_NE(not_a_string.error().find("must have \"type\":\"header\""), std::string::npos)
        << not_a_string.error();

    {
        std::ofstream out(path);
        out << R"({"type":"header","version":2})"
            << "\n";
    }
    TraceReader r2;
    EXPECT_FALSE(r2.open(path));
    EXPECT_NE(r2.error().find("version must be 1"), std::string::npos) << r2.error();
    std::filesystem::remove(path);
}

} // namespace
} // namespace dsoc::trace
