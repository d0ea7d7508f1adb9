// dsoc-server as an operator runs it: the hint after an unknown map, the config file
// round trip (--print-config, one edit, --config), $DSOC_CONFIG, JSON logs, exit
// statuses, and /healthz, /readyz and /metrics of the running process.

#include "dsoc/cli/build_info.hpp"
#include "program_paths.hpp"
#include "support/child_process.hpp"
#include "support/http_client.hpp"
#include "support/temp_dir.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

namespace dsoc::testing {
namespace {

namespace fs = std::filesystem;

/// The lines of `text` that are not comments.
std::string settings_lines(const std::string& text) {
    std::istringstream in(text);
    std::string kept;
    for (std::string line; std::getline(in, line);) {
        if (line.rfind('#', 0) != 0) {
            kept += line + "\n";
        }
    }
    return kept;
}

TEST(ServerMap, AnUnknownNameNamesRealFlagsAndTheMapList) {
    const ProgramRun run = run_program({program("dsoc-server"), "--insecure", "--map", "oa_dm99"});
    EXPECT_EQ(run.status, 2) << run.err;
    EXPECT_NE(run.err.find("cannot load map 'oa_dm99': oa_dm99: no map of that name"),
              std::string::npos)
        << run.err;
    EXPECT_NE(run.err.find("`dsoc-mapinfo --list` lists the map names found"), std::string::npos)
        << run.err;
    EXPECT_NE(run.err.find("DSOC_MAP_PATH"), std::string::npos) << run.err;
    // Every flag the message names is one dsoc-server (or dsoc-mapinfo, for --list) has.
    const std::string server_help = run_program({program("dsoc-server"), "--help"}).out;
    const std::string mapinfo_help = run_program({program("dsoc-mapinfo"), "--help"}).out;
    const std::regex flag(R"(--[a-z][a-z-]*)");
    std::set<std::string> named;
    for (auto it = std::sregex_iterator(run.err.begin(), run.err.end(), flag);
         it != std::sregex_iterator(); ++it) {
        named.insert(it->str());
    }
    EXPECT_EQ(named, (std::set<std::string>{"--map", "--list"})) << run.err;
    EXPECT_NE(server_help.find("--map "), std::string::npos);
    EXPECT_NE(mapinfo_help.find("--list "), std::string::npos);
    EXPECT_EQ(run.err.find("--pak"), std::string::npos) << run.err;

    // And what it points to works: the list holds the OpenArena maps (when installed).
    const ProgramRun list = run_program({program("dsoc-mapinfo"), "--list"});
    EXPECT_EQ(list.status, 0) << list.err;
    if (fs::exists("/usr/share/games/openarena/baseoa")) {
        EXPECT_NE(list.out.find("oa_dm4\n"), std::string::npos) << list.out;
    }
}

TEST(ServerConfig, PrintConfigRoundTripsWithOneEditTheTokenKey) {
    const TempDir dir("dsoc-print-config");
    // The documented first step: dsoc-server --print-config > server.toml.
    const ProgramRun printed = run_program({program("dsoc-server"), "--print-config"});
    ASSERT_EQ(printed.status, 0) << printed.err;
    EXPECT_NE(printed.err.find("token_key_file: required unless insecure = true"),
              std::string::npos)
        << printed.err;
    const std::string toml = dir.write("server.toml", printed.out);

    // As printed, the server names the one thing to fix.
    const ProgramRun unedited =
        run_program({program("dsoc-server"), "--config", toml, "--check-config"});
    EXPECT_EQ(unedited.status, 2) << unedited.err;
    EXPECT_EQ(unedited.err, "invalid setting: token_key_file: required unless insecure = true "
                            "(mint a key with dsoc-token keygen)\n");

    // The edit docs/operations.md shows: a key, and its path in token_key_file.
    const std::string key = dir.path("token.key");
    ASSERT_EQ(run_program({program("dsoc-token"), "keygen", "--out", key}).status, 0);
    std::string text = printed.out;
    const std::string unset = "\ntoken_key_file = ''\n";
    const auto at = text.find(unset);
    ASSERT_NE(at, std::string::npos) << text;
    text.replace(at, unset.size(), "\ntoken_key_file = '" + key + "'\n");
    dir.write("server.toml", text);

    const ProgramRun checked =
        run_program({program("dsoc-server"), "--config", toml, "--check-config"});
    EXPECT_EQ(checked.status, 0) << checked.err;
    EXPECT_NE(checked.out.find("the settings are good"), std::string::npos) << checked.out;
    // Printed again from the file: the same settings, and nothing left to fix.
    const ProgramRun again =
        run_program({program("dsoc-server"), "--config", toml, "--print-config"});
    EXPECT_EQ(again.status, 0) << again.err;
    EXPECT_TRUE(again.err.empty()) << again.err;
    EXPECT_EQ(settings_lines(again.out), settings_lines(text));
    EXPECT_EQ(again.out.find("refuses to start"), std::string::npos) << again.out;

    // And the server runs with it (the flags only make the test light and short).
    const ProgramRun served = run_program({program("dsoc-server"), "--config", toml, "--port", "0",
                                           "--map", "gen:rooms:1", "--baked-stage", "false",
                                           "--bots", "2", "--threads", "1", "--duration", "0.3"});
    EXPECT_EQ(served.status, 0) << served.err;
    EXPECT_NE(served.out.find("listening on port"), std::string::npos) << served.out;
}

TEST(ServerConfig, DsocConfigNamesTheFileAndConfigOverridesIt) {
    const TempDir dir("dsoc-config-env");
    const std::string from_env = dir.write("env.toml", "insecure = true\ntick_rate = 20\n");
    const std::string from_flag = dir.write("flag.toml", "insecure = true\ntick_rate = 40\n");

    const ProgramRun env =
        run_program({program("dsoc-server"), "--print-config"}, {"DSOC_CONFIG=" + from_env});
    EXPECT_EQ(env.status, 0) << env.err;
    EXPECT_NE(env.out.find("\ntick_rate = 20\n"), std::string::npos) << env.out;
    const ProgramRun flag =
        run_program({program("dsoc-server"), "--config", from_flag, "--print-config"},
                    {"DSOC_CONFIG=" + from_env});
    EXPECT_NE(flag.out.find("\ntick_rate = 40\n"), std::string::npos) << flag.out;
    const ProgramRun none = run_program({program("dsoc-server"), "--insecure", "--print-config"});
    EXPECT_NE(none.out.find("\ntick_rate = 30\n"), std::string::npos) << none.out;

    const ProgramRun missing = run_program({program("dsoc-server"), "--check-config"},
                                           {"DSOC_CONFIG=" + dir.path("missing.toml")});
    EXPECT_EQ(missing.status, 2);
    EXPECT_EQ(missing.err, "invalid config file (from DSOC_CONFIG): " + dir.path("missing.toml") +
                               ": cannot read config file: No such file or directory\n");
}

TEST(ServerExit, SettingsAndInputsAreUsageErrorsServingIsAFailure) {
    const TempDir dir("dsoc-server-exit");
    const ProgramRun bad_setting = run_program(light_server({"--tick-rate", "0"}));
    EXPECT_EQ(bad_setting.status, 2);
    EXPECT_NE(bad_setting.err.find("invalid setting: tick_rate: must be 1..240 Hz, got 0"),
              std::string::npos)
        << bad_setting.err;
    // The key is read before the map, so that a bad key does not wait for a bake.
    const ProgramRun no_key = run_program({program("dsoc-server"), "--token-key-file",
                                           dir.path("none.key"), "--map", "no_such_map_dsoc"});
    EXPECT_EQ(no_key.status, 2);
    EXPECT_EQ(no_key.err, "invalid setting: token_key_file: " + dir.path("none.key") +
                              ": cannot read token key: No such file or directory\n");
    const std::string bad_toml = dir.write("bad.toml", "port = 70000\n");
    const ProgramRun bad_file = run_program({program("dsoc-server"), "--config", bad_toml});
    EXPECT_EQ(bad_file.status, 2);
    EXPECT_EQ(bad_file.err, "invalid config file: " + bad_toml +
                                ":1:8: port: 70000 does not fit: must be 0..65535\n");

    // The game port taken: the settings were good, serving failed.
    boost::asio::io_context io;
    boost::asio::ip::tcp::acceptor taken(io, {boost::asio::ip::make_address("127.0.0.1"), 0});
    const std::string port = std::to_string(taken.local_endpoint().port());
    std::vector<std::string> argv = light_server({"--duration", "5"});
    *(std::find(argv.begin(), argv.end(), "--port") + 1) = port;
    const ProgramRun busy = run_program(argv);
    EXPECT_EQ(busy.status, 1) << busy.err;
    EXPECT_NE(busy.err.find("cannot start on 127.0.0.1:" + port), std::string::npos) << busy.err;
}

TEST(ServerLogs, LogFormatJsonWritesOneObjectALine) {
    const ProgramRun run = run_program(light_server({"--log-format", "json", "--duration", "0.3"}));
    ASSERT_EQ(run.status, 0) << run.err;
    std::istringstream lines(run.err);
    int count = 0;
    bool saw_version = false;
    for (std::string line; std::getline(lines, line); ++count) {
        const auto json = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
        ASSERT_TRUE(json.is_object()) << "not a JSON object: " << line;
        for (const char* key : {"time", "level", "logger", "msg"}) {
            EXPECT_TRUE(json.contains(key)) << key << " missing: " << line;
        }
        saw_version =
            saw_version || json["msg"] == cli::version_line("dsoc-server", cli::build_info());
    }
    EXPECT_GE(count, 3); // version, insecure warning, map, listening, shutdown, ...
    EXPECT_TRUE(saw_version) << run.err;

    const ProgramRun text = run_program(light_server({"--duration", "0.1"}));
    ASSERT_EQ(text.status, 0) << text.err;
    EXPECT_EQ(text.err.rfind('[', 0), 0u) << text.err; // "[12:00:00.000] [server] [info] ..."
    const ProgramRun bad = run_program(light_server({"--log-format", "xml"}));
    EXPECT_EQ(bad.status, 2);
    EXPECT_NE(bad.err.find("invalid setting: log_format: must be text or json; got 'xml'"),
              std::string::npos)
        << bad.err;
}

TEST(ServerProbes, HealthReadinessAndMetricsOfTheRunningProcess) {
    // At 1 Hz the first tick comes a second after the game port opens: /readyz must say
    // 503 until then.
    ChildProcess server(light_server({"--metrics-port", "0", "--tick-rate", "1"}));
    ASSERT_TRUE(server.wait_for_output("listening on port")) << server.out() << server.err();
    const std::smatch::string_type out = server.out();
    std::smatch match;
    ASSERT_TRUE(std::regex_search(out, match, std::regex(R"(metrics on port (\d+))"))) << out;
    const auto port = static_cast<std::uint16_t>(std::stoi(match[1]));

    const std::string waiting = http_get(port, "/readyz");
    const std::string alive = http_get(port, "/healthz");
    std::string ready;
    for (int i = 0; i < 500 && http_status(ready) != 200; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        ready = http_get(port, "/readyz");
    }
    const std::string metrics = http_get(port, "/metrics");
    server.signal(SIGTERM);
    const int status = server.wait();

    EXPECT_EQ(http_status(waiting), 503) << waiting;
    EXPECT_EQ(http_body(waiting), "not ready: waiting for the first tick\n");
    EXPECT_EQ(http_status(alive), 200) << alive;
    EXPECT_EQ(http_body(alive), "ok\n");
    EXPECT_EQ(http_status(ready), 200) << ready;
    EXPECT_EQ(http_body(ready), "ready\n");
    EXPECT_EQ(http_status(metrics), 200);
    const auto& build = cli::build_info();
    EXPECT_NE(metrics.find("\ndsoc_build_info{version=\"" + build.version + "\",commit=\"" +
                           build.commit + "\"} 1\n"),
              std::string::npos)
        << metrics;
    for (const char* name :
         {"process_cpu_seconds_total ", "process_resident_memory_bytes ", "process_open_fds ",
          "process_max_fds ", "process_start_time_seconds ", "process_virtual_memory_bytes ",
          // the server's own, unchanged
          "dsoc_ticks_total ", "dsoc_clients ", "dsoc_tick_duration_seconds_count ",
          "dsoc_bytes_sent_total "}) {
        EXPECT_NE(metrics.find(std::string("\n") + name), std::string::npos) << name;
    }
    // Where its threads' time goes, on a kernel that keeps schedstat: the I/O thread and
    // the pool's threads told apart.
    std::ifstream own_schedstat("/proc/self/schedstat");
    std::uint64_t own_run_ns = 0;
    if (own_schedstat >> own_run_ns && own_run_ns > 0) {
        for (const char* name : {"dsoc_thread_runqueue_wait_seconds_total{role=\"io\"} ",
                                 "dsoc_thread_cpu_seconds_total{role=\"worker\"} "}) {
            EXPECT_NE(metrics.find(std::string("\n") + name), std::string::npos) << name;
        }
    }
    // The allocator it runs on; its figures always on jemalloc, where they are cheap, and
    // on glibc only when asked (they cost every allocating thread a wait there).
    const std::string allocator = DSOC_SERVER_ALLOCATOR;
    EXPECT_NE(metrics.find("\ndsoc_heap_allocator_info{allocator=\"" + allocator + "\"} 1\n"),
              std::string::npos)
        << metrics;
    EXPECT_EQ(metrics.find("\ndsoc_heap_in_use_bytes ") != std::string::npos,
              allocator == "jemalloc")
        << metrics;
    EXPECT_EQ(status, 0) << server.err();
}

} // namespace
} // namespace dsoc::testing
