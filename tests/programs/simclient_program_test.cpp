// dsoc-simclient as a load tester runs it, against a real dsoc-server started on port 0:
// a reason for every failure, an unexpected server shutdown failing the run, thresholds,
// a scenario file with stages and groups, the time series, and the exit statuses.

#include "program_paths.hpp"
#include "support/child_process.hpp"
#include "support/temp_dir.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ip/udp.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>

namespace dsoc::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// A small dsoc-server that starts in moments, on a free port, stopped at the end.
class LightServer {
public:
    explicit LightServer(const std::vector<std::string>& more = {}) {
        child_ = std::make_unique<ChildProcess>(light_server(more));
        if (!child_->wait_for_output("listening on port")) {
            ADD_FAILURE() << "the server did not start: " << child_->err();
            return;
        }
        const std::string out = child_->out();
        std::smatch match;
        if (std::regex_search(out, match, std::regex(R"(listening on port (\d+))"))) {
            address_ = "127.0.0.1:" + match[1].str();
        }
    }
    ~LightServer() {
        child_->signal(SIGTERM);
        child_->wait(std::chrono::seconds(10));
    }
    LightServer(const LightServer&) = delete;
    LightServer& operator=(const LightServer&) = delete;

    [[nodiscard]] const std::string& address() const { return address_; }
    ChildProcess& process() { return *child_; }

private:
    std::unique_ptr<ChildProcess> child_;
    std::string address_;
};

json read_json(const std::string& path) {
    std::ifstream in(path);
    return json::parse(in, nullptr, /*allow_exceptions=*/false);
}

std::vector<json> read_json_lines(const std::string& path) {
    std::ifstream in(path);
    std::vector<json> lines;
    for (std::string line; std::getline(in, line);) {
        lines.push_back(json::parse(line, nullptr, /*allow_exceptions=*/false));
    }
    return lines;
}

/// Runs dsoc-simclient with `args` (quiet, a JSON report in `files`); the report in `report`.
ProgramRun simclient(const TempDir& files, std::vector<std::string> args, json& report) {
    std::vector<std::string> argv = {program("dsoc-simclient"), "--quiet", "--report",
                                     files.path("report.json")};
    argv.insert(argv.end(), args.begin(), args.end());
    ProgramRun run = run_program(argv);
    report = read_json(files.path("report.json"));
    return run;
}

/// A port nothing listens on (bound, then closed).
std::string closed_port() {
    boost::asio::io_context io;
    boost::asio::ip::tcp::acceptor a(io, {boost::asio::ip::make_address("127.0.0.1"), 0});
    return std::to_string(a.local_endpoint().port());
}

double seconds_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

TEST(SimclientFailures, RefusedUnresolvableAndTimeoutAreNamedAndEndTheRunEarly) {
    const TempDir files("dsoc-simclient-connect");
    json report;
    const auto count = [](const std::string& text, const std::string& what) {
        std::size_t n = 0;
        for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
            ++n;
        }
        return n;
    };
    auto t0 = std::chrono::steady_clock::now();
    // On two threads, one client each, with progress lines: the run gives up as one,
    // and says so once. Over UDP the host's ICMP answer says the same as TCP's reset.
    for (const char* transport : {"tcp", "udp"}) {
        t0 = std::chrono::steady_clock::now();
        const ProgramRun refused =
            run_program({program("dsoc-simclient"), "--report", files.path("report.json"),
                         "--server", "127.0.0.1:" + closed_port(), "--transport", transport,
                         "--clients", "2", "--duration", "20", "--threads", "2"});
        report = read_json(files.path("report.json"));
        EXPECT_LT(seconds_since(t0), 10.0) << transport; // not the whole --duration
        EXPECT_EQ(refused.status, 1) << refused.out << refused.err;
        EXPECT_NE(refused.out.find("failures               2 (refused=2)"), std::string::npos)
            << refused.out;
        EXPECT_NE(refused.out.find("Connection refused"), std::string::npos) << refused.out;
        EXPECT_EQ(count(refused.err, "failed: refused"), 1u) << refused.err;
        EXPECT_EQ(count(refused.err, "stopping early"), 1u) << refused.err;
        EXPECT_EQ(report["failures_by_reason"], json({{"refused", 2}})) << report.dump(2);
        EXPECT_EQ(report["protocol_errors"], 0);
        EXPECT_NE(report["stopped_early"].get<std::string>().find("no client could connect"),
                  std::string::npos);
    }

    // .invalid never resolves (RFC 2606); the timeout leaves the resolver time to say so.
    const ProgramRun unresolvable = simclient(files,
                                              {"--server", "nonexistent.invalid:27960", "--clients",
                                               "2", "--duration", "20", "--connect-timeout", "15"},
                                              report);
    EXPECT_EQ(unresolvable.status, 1);
    EXPECT_EQ(report["failures_by_reason"], json({{"unresolvable", 2}})) << report.dump(2);
    EXPECT_EQ(report["protocol_errors"], 0) << "an unresolvable host is no protocol error";

    // A port that accepts (the kernel completes the handshake) and never answers; over
    // UDP, a socket that reads and never answers.
    boost::asio::io_context io;
    boost::asio::ip::tcp::acceptor silent(io, {boost::asio::ip::make_address("127.0.0.1"), 0});
    boost::asio::ip::udp::socket silent_udp(
        io, {boost::asio::ip::make_address("127.0.0.1"), silent.local_endpoint().port()});
    for (const char* transport : {"tcp", "udp"}) {
        t0 = std::chrono::steady_clock::now();
        const ProgramRun timeout =
            simclient(files,
                      {"--server", "127.0.0.1:" + std::to_string(silent.local_endpoint().port()),
                       "--transport", transport, "--clients", "2", "--ramp-up", "0", "--duration",
                       "20", "--connect-timeout", "0.5"},
                      report);
        EXPECT_LT(seconds_since(t0), 10.0) << transport;
        EXPECT_EQ(timeout.status, 1) << transport;
        EXPECT_EQ(report["failures_by_reason"], json({{"timeout", 2}}))
            << transport << report.dump(2);
        EXPECT_EQ(report["failure_examples"]["timeout"], "sim-0: no server hello within 0.5 s")
            << transport;
    }
}

TEST(SimclientFailures, UnauthorizedVersionMismatchAndDroppedByServer) {
    const TempDir files("dsoc-simclient-refusals");
    const std::string key = files.path("server.key");
    const std::string other_key = files.path("other.key");
    ASSERT_EQ(run_program({program("dsoc-token"), "keygen", "--out", key}).status, 0);
    ASSERT_EQ(run_program({program("dsoc-token"), "keygen", "--out", other_key}).status, 0);
    const ProgramRun minted =
        run_program({program("dsoc-token"), "mint", "--key-file", other_key, "--client-id", "1"});
    ASSERT_EQ(minted.status, 0) << minted.err;
    std::string wrong_token = minted.out;
    wrong_token.erase(wrong_token.find_last_not_of(" \n") + 1);
    json report;
    {
        LightServer server({"--token-key-file", key});
        const ProgramRun unauthorized = simclient(files,
                                                  {"--server", server.address(), "--clients", "2",
                                                   "--duration", "5", "--token", wrong_token},
                                                  report);
        EXPECT_EQ(unauthorized.status, 1);
        EXPECT_EQ(report["failures_by_reason"], json({{"unauthorized", 2}})) << report.dump(2);
        EXPECT_EQ(report["disconnect_reasons"], json({{"unauthorized", 2}}));
    }
    {
        LightServer server({"--max-clients", "1"});
        const ProgramRun version = simclient(files,
                                             {"--server", server.address(), "--clients", "2",
                                              "--duration", "5", "--protocol-version", "1"},
                                             report);
        EXPECT_EQ(version.status, 1);
        EXPECT_EQ(report["failures_by_reason"], json({{"version_mismatch", 2}})) << report.dump(2);
        EXPECT_NE(version.out.find("client speaks protocol 1, server speaks "), std::string::npos)
            << version.out;

        // One place on the server, two clients: the server drops the second with its reason.
        const ProgramRun dropped = simclient(
            files,
            {"--server", server.address(), "--clients", "2", "--ramp-up", "0", "--duration", "1"},
            report);
        EXPECT_EQ(dropped.status, 1);
        EXPECT_EQ(report["connected"], 1);
        EXPECT_EQ(report["failures_by_reason"], json({{"dropped_by_server", 1}})) << report.dump(2);
        EXPECT_EQ(report["disconnect_reasons"], json({{"server_full", 1}}));
        EXPECT_NE(dropped.out.find("dropped_by_server    first: sim-1: server_full: server holds "
                                   "1 clients at most"),
                  std::string::npos)
            << dropped.out;
    }
}

TEST(SimclientShutdown, AServerStoppingBeforeTheEndFailsTheRun) {
    for (const char* transport : {"tcp", "udp"}) {
        const TempDir files("dsoc-simclient-shutdown");
        LightServer server({"--duration", "1"});
        json report;
        const auto t0 = std::chrono::steady_clock::now();
        const ProgramRun run = simclient(files,
                                         {"--server", server.address(), "--transport", transport,
                                          "--clients", "2", "--duration", "8"},
                                         report);
        EXPECT_LT(seconds_since(t0), 6.0) << transport; // stopped early, not at 8 s
        EXPECT_EQ(run.status, 1) << run.out;
        EXPECT_EQ(report["passed"], false);
        // Over TCP both notices are read; over UDP the first to arrive stops the run, and
        // the other client may be stopped before its datagram is read.
        const int shutdowns = report["failures_by_reason"].value("server_shutdown", 0);
        EXPECT_EQ(report["failures_by_reason"].size(), 1u) << report.dump(2);
        if (std::string(transport) == "tcp") {
            EXPECT_EQ(shutdowns, 2) << report.dump(2);
        } else {
            EXPECT_GE(shutdowns, 1) << report.dump(2);
        }
        EXPECT_NE(report["stopped_early"].get<std::string>().find("the server shut down at"),
                  std::string::npos)
            << report.dump(2);
        EXPECT_NE(run.out.find("FAIL: stopped early: the server shut down"), std::string::npos)
            << run.out;
    }
}

TEST(SimclientThresholds, AFailedThresholdFailsTheRunAndNamesLimitAndValue) {
    const TempDir files("dsoc-simclient-thresholds");
    LightServer server;
    json report;
    // At 30 Hz snapshots come every 33 ms: below 1 ms fails, below 5 s holds.
    const ProgramRun failed =
        simclient(files,
                  {"--server", server.address(), "--clients", "2", "--duration", "1.5",
                   "--threshold", "interarrival_p99<1ms", "--threshold", "interarrival_p99 < 5s",
                   "--threshold", "failures<=0"},
                  report);
    EXPECT_EQ(failed.status, 1) << failed.out;
    EXPECT_TRUE(std::regex_search(
        failed.out, std::regex(R"(\n    FAIL interarrival_p99 < 1ms: observed \d+(\.\d+)? ms\n)")))
        << failed.out;
    EXPECT_TRUE(std::regex_search(
        failed.out, std::regex(R"(\n    pass interarrival_p99 < 5s: observed 0\.0\d+ s\n)")))
        << failed.out;
    EXPECT_NE(failed.out.find("thresholds             2 passed, 1 failed"), std::string::npos);
    EXPECT_NE(failed.out.find("FAIL: threshold failed: interarrival_p99 < 1ms"), std::string::npos)
        << failed.out;
    ASSERT_EQ(report["thresholds"].size(), 3u) << report.dump(2);
    const json& t = report["thresholds"][0];
    EXPECT_EQ(t["threshold"], "interarrival_p99<1ms");
    EXPECT_EQ(t["limit"], 1.0);
    EXPECT_EQ(t["unit"], "ms");
    EXPECT_GT(t["observed"].get<double>(), 20.0);
    EXPECT_EQ(t["passed"], false);
    EXPECT_EQ(report["thresholds"][1]["passed"], true);
    EXPECT_EQ(report["failures"], 0);

    const ProgramRun passed = simclient(files,
                                        {"--server", server.address(), "--clients", "2",
                                         "--duration", "1.2", "--threshold", "interarrival_p99<5s",
                                         "--threshold", "bytes_down_per_client>10B/s"},
                                        report);
    EXPECT_EQ(passed.status, 0) << passed.out;
    EXPECT_EQ(report["passed"], true);
}

TEST(SimclientScenario, ThreeStagesAndTwoGroupsAreFollowedSecondBySecond) {
    const TempDir files("dsoc-simclient-scenario");
    const std::string scenario = files.write("scenario.toml", R"(
stages = [
  { duration = "1s", target = 6 },    # ramp up to 6
  { duration = "1.5s", target = 6 },  # hold
  { duration = "1s", target = 2 },    # ramp down to 2
]
thresholds = ["failure_rate < 1%"]

[[groups]]
name = "wanderers"
weight = 2

[[groups]]
name = "campers"
behaviour = "camper"
latency = "20ms"
)");
    LightServer server;
    json report;
    // On two threads: the stages, the groups' shares and the seconds are the run's.
    const ProgramRun run = simclient(files,
                                     {"--server", server.address(), "--scenario", scenario,
                                      "--timeseries", files.path("series.jsonl"), "--threads", "2"},
                                     report);
    EXPECT_EQ(run.status, 0) << run.out << run.err;
    EXPECT_EQ(report["clients"], 6) << report.dump(2);
    EXPECT_EQ(report["peak_connected"], 6);
    EXPECT_EQ(report["failures"], 0);
    EXPECT_EQ(report["cancelled_before_hello"], 0);
    EXPECT_EQ(report["groups"]["wanderers"]["sessions"], 4);
    EXPECT_EQ(report["groups"]["campers"]["sessions"], 2);
    EXPECT_DOUBLE_EQ(report["scenario_seconds"].get<double>(), 3.5);

    // One line per second, and a last one at the end: the count follows the stages.
    const auto lines = read_json_lines(files.path("series.jsonl"));
    ASSERT_GE(lines.size(), 4u);
    for (const json& line : lines) {
        ASSERT_TRUE(line.is_object());
        EXPECT_LE(line["connected"].get<int>(), line["target"].get<int>() + 1) << line.dump();
    }
    EXPECT_NEAR(lines[0]["t_s"].get<double>(), 1.0, 0.2);
    EXPECT_EQ(lines[0]["target"], 6);
    EXPECT_NEAR(lines[1]["t_s"].get<double>(), 2.0, 0.2);
    EXPECT_EQ(lines[1]["target"], 6); // the hold
    EXPECT_EQ(lines[1]["connected"], 6) << lines[1].dump();
    EXPECT_GT(lines[1]["snapshots_per_s"].get<double>(), 100.0); // 6 clients at 30 Hz
    EXPECT_GT(lines[1]["interarrival_p99_ms"].get<double>(), 20.0);
    const json& last = lines.back();
    EXPECT_NEAR(last["t_s"].get<double>(), 3.5, 0.2);
    EXPECT_LE(last["target"].get<int>(), 3); // ramped down
    EXPECT_GE(last["connected"].get<int>(), 2);
}

TEST(SimclientScenario, RespawnersComeBackAsThemselvesAndChurnBringsNewClients) {
    const TempDir files("dsoc-simclient-churn");
    const std::string key = files.path("server.key");
    ASSERT_EQ(run_program({program("dsoc-token"), "keygen", "--out", key}).status, 0);
    const std::string scenario = files.write("scenario.toml", R"(
stages = [{ duration = 0, target = 4 }, { duration = "2.5s", target = 4 }]

[[groups]]
name = "respawners"
behaviour = "respawner"
respawn_every = "0.6s"

[[groups]]
name = "churn"
churn_per_s = 2
)");
    // With tokens: a respawner reconnects with its own client id, which the server
    // refuses while the old connection is open.
    LightServer server({"--token-key-file", key});
    json report;
    const ProgramRun run = simclient(
        files, {"--server", server.address(), "--scenario", scenario, "--token-key-file", key},
        report);
    EXPECT_EQ(run.status, 0) << run.out << run.err;
    EXPECT_EQ(report["failures"], 0) << report.dump(2);
    // Respawners: the same two clients (names, client ids), session after session.
    EXPECT_EQ(report["groups"]["respawners"]["clients"], 2) << report.dump(2);
    EXPECT_GE(report["groups"]["respawners"]["sessions"].get<int>(), 5) << report.dump(2);
    // Churn: two places, new clients taking them (about 2 a second for 2.5 s).
    EXPECT_GE(report["groups"]["churn"]["clients"].get<int>(), 4) << report.dump(2);
    EXPECT_EQ(report["groups"]["churn"]["clients"], report["groups"]["churn"]["sessions"]);
    EXPECT_EQ(report["disconnect_reasons"].size(), 0u) << report.dump(2);
}

TEST(SimclientUsage, BadThresholdsAndScenarioFilesAreUsageErrors) {
    const TempDir files("dsoc-simclient-usage");
    const ProgramRun unknown =
        run_program({program("dsoc-simclient"), "--threshold", "latency_p99<50ms"});
    EXPECT_EQ(unknown.status, 2);
    EXPECT_NE(unknown.err.find("unknown figure 'latency_p99'; known: interarrival_mean, "
                               "interarrival_p50"),
              std::string::npos)
        << unknown.err;
    const ProgramRun unit =
        run_program({program("dsoc-simclient"), "--threshold", "interarrival_p99<5KiB/s"});
    EXPECT_EQ(unit.status, 2);
    EXPECT_NE(unit.err.find("does not fit; expected a time"), std::string::npos) << unit.err;

    const std::string bad = files.write("bad.toml", "stages = [{ duration = \"1s\", target = 2 }]\n"
                                                    "users = 3\n");
    const ProgramRun file = run_program({program("dsoc-simclient"), "--scenario", bad});
    EXPECT_EQ(file.status, 2);
    EXPECT_EQ(file.err, "dsoc-simclient: --scenario: " + bad +
                            ":2:9: users: unknown key; known: stages, groups, thresholds, "
                            "connect_timeout\n");
    const ProgramRun missing =
        run_program({program("dsoc-simclient"), "--scenario", files.path("none.toml")});
    EXPECT_EQ(missing.status, 2);
    EXPECT_NE(missing.err.find("cannot read scenario file"), std::string::npos) << missing.err;
    const ProgramRun both =
        run_program({program("dsoc-simclient"), "--scenario", bad, "--clients", "3"});
    EXPECT_EQ(both.status, 2) << both.err;

    const ProgramRun figures = run_program({program("dsoc-simclient"), "--list-figures"});
    EXPECT_EQ(figures.status, 0);
    EXPECT_NE(figures.out.find("interarrival_p99  p99 of the time between a client's snapshots"),
              std::string::npos)
        << figures.out;
}

} // namespace
} // namespace dsoc::testing
