// What every dsoc program shares (dsoc/cli/program.hpp, docs/operations.md "Exit
// statuses"): --version, --help, and the meaning of each exit status.

#include "dsoc/cli/build_info.hpp"
#include "program_paths.hpp"
#include "support/child_process.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <regex>

namespace dsoc::testing {
namespace {

TEST(Programs, VersionIsOneLineWithTheProgramVersionAndCommit) {
    ASSERT_GE(cli_programs().size(), 7u);
    const std::regex shape(
        R"(dsoc-[a-z-]+ [0-9]+\.[0-9]+\.[0-9]+( \(commit [0-9a-f]{12}(-dirty)?\))?\n)");
    for (const auto& name : cli_programs()) {
        const ProgramRun run = run_program({program(name), "--version"});
        EXPECT_EQ(run.status, 0) << name << ": " << run.err;
        EXPECT_EQ(run.out, cli::version_line(name) + "\n") << name;
        EXPECT_TRUE(std::regex_match(run.out, shape)) << run.out;
        EXPECT_TRUE(run.err.empty()) << name << ": " << run.err;
    }
}

TEST(Programs, TheCommitIsTheCheckedOutOne) {
    if (std::string(DSOC_GIT).empty() ||
        !std::filesystem::exists(std::filesystem::path(DSOC_SOURCE_DIR) / ".git")) {
        GTEST_SKIP() << "not built from a git checkout";
    }
    const ProgramRun head =
        run_program({DSOC_GIT, "-C", DSOC_SOURCE_DIR, "rev-parse", "--short=12", "HEAD"});
    ASSERT_EQ(head.status, 0) << head.err;
    ASSERT_GE(head.out.size(), 12u);
    // A build older than the last commit says the commit it was built from: build again.
    EXPECT_EQ(cli::build_info().commit.substr(0, 12), head.out.substr(0, 12));
    EXPECT_EQ(cli::version_line("dsoc-x", {"1.2.3", ""}), "dsoc-x 1.2.3");
}

TEST(Programs, HelpExitsZeroAndListsVersion) {
    for (const auto& name : cli_programs()) {
        const ProgramRun run = run_program({program(name), "--help"});
        EXPECT_EQ(run.status, 0) << name << ": " << run.err;
        EXPECT_NE(run.out.find("--version"), std::string::npos) << name << ":\n" << run.out;
    }
}

/// What `name` needs on its command line besides flags with defaults (CLI11 names a
/// missing required argument before an unknown one).
std::vector<std::string> required_arguments(const std::string& name) {
    if (name == "dsoc-bake") {
        return {"gen:rooms"};
    }
    if (name == "dsoc-inspect") {
        return {"--out", "/tmp/dsoc-unused"};
    }
    if (name == "dsoc-token") {
        return {"keygen"};
    }
    return {};
}

TEST(ExitStatus, AnUnknownFlagIsAUsageErrorNamingIt) {
    for (const auto& name : cli_programs()) {
        std::vector<std::string> command = {program(name)};
        for (auto& argument : required_arguments(name)) {
            command.push_back(std::move(argument));
        }
        command.push_back("--no-such-flag");
        const ProgramRun run = run_program(command);
        EXPECT_EQ(run.status, 2) << name;
        EXPECT_EQ(run.err.rfind(name + ": ", 0), 0u) << run.err;
        EXPECT_NE(run.err.find("--no-such-flag"), std::string::npos) << run.err;
        EXPECT_NE(run.err.find(name + " --help"), std::string::npos) << run.err;
    }
}

TEST(ExitStatus, ABadValueIsAUsageError) {
    const std::vector<std::vector<std::string>> commands = {
        {program("dsoc-server"), "--port", "seventy"},
        {program("dsoc-simclient"), "--clients", "0"},
        {program("dsoc-tick-bench"), "--players", "0"},
        {program("dsoc-inspect"), "--out", "/tmp/x", "--pyramid", "sideways"},
        {program("dsoc-token"), "mint", "--key-file", "k", "--client-id", "0"},
        {program("dsoc-bake"), "--cell-size", "1", "gen:rooms"},
        {program("dsoc-mapinfo")}, // MAP is required
    };
    for (const auto& command : commands) {
        const ProgramRun run = run_program(command);
        EXPECT_EQ(run.status, 2) << command[0] << ": " << run.err;
        EXPECT_FALSE(run.err.empty()) << command[0];
    }
}

TEST(ExitStatus, AFailedCheckIsAFailure) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "dsoc-exit-status";
    std::filesystem::create_directories(dir);
    const std::string key = (dir / "a.key").string();
    const std::string other_key = (dir / "b.key").string();
    ASSERT_EQ(run_program({program("dsoc-token"), "keygen", "--out", key}).status, 0);
    ASSERT_EQ(run_program({program("dsoc-token"), "keygen", "--out", other_key}).status, 0);
    const ProgramRun minted =
        run_program({program("dsoc-token"), "mint", "--key-file", other_key, "--client-id", "5"});
    ASSERT_EQ(minted.status, 0) << minted.err;
    const std::string token = minted.out.substr(0, minted.out.find('\n'));

    // A token of another key: the check ran and says no.
    const ProgramRun check =
        run_program({program("dsoc-token"), "check", "--key-file", key, token});
    EXPECT_EQ(check.status, 1) << check.out << check.err;
    EXPECT_EQ(check.out.rfind("invalid: ", 0), 0u) << check.out;
    const ProgramRun good =
        run_program({program("dsoc-token"), "check", "--key-file", other_key, token});
    EXPECT_EQ(good.status, 0) << good.out << good.err;
    // An unreadable key is an input that is wrong: a usage error.
    const ProgramRun no_key = run_program({program("dsoc-token"), "mint", "--key-file",
                                           (dir / "none.key").string(), "--client-id", "5"});
    EXPECT_EQ(no_key.status, 2) << no_key.err;
    EXPECT_NE(no_key.err.find("none.key"), std::string::npos) << no_key.err;

    // dsoc-mapinfo's check of a map that does not load.
    const ProgramRun mapinfo = run_program({program("dsoc-mapinfo"), "no_such_map_dsoc"});
    EXPECT_EQ(mapinfo.status, 1) << mapinfo.err;
    EXPECT_NE(mapinfo.err.find("dsoc-mapinfo --list"), std::string::npos) << mapinfo.err;
    std::filesystem::remove_all(dir);
}

TEST(ExitStatus, AMapToRunOnThatDoesNotLoadIsAUsageErrorWithTheHint) {
    const std::string out =
        (std::filesystem::temp_directory_path() / "dsoc-inspect-unused").string();
    const std::vector<std::vector<std::string>> commands = {
        {program("dsoc-tick-bench"), "--map", "no_such_map_dsoc", "--players", "1"},
        {program("dsoc-inspect"), "--map", "no_such_map_dsoc", "--out", out},
        {program("dsoc-eval"), "--map", "no_such_map_dsoc", "--duration", "1", "--quiet"},
    };
    for (const auto& command : commands) {
        const ProgramRun run = run_program(command);
        EXPECT_EQ(run.status, 2) << command[0] << ": " << run.err;
        EXPECT_NE(run.err.find("cannot load map 'no_such_map_dsoc'"), std::string::npos) << run.err;
        EXPECT_NE(run.err.find("`dsoc-mapinfo --list` lists the map names found; --map also takes"),
                  std::string::npos)
            << run.err;
    }
    std::filesystem::remove_all(out);
}

TEST(ExitStatus, AScenarioMapThatDoesNotLoadIsAUsageErrorNamingTheScenario) {
    const auto scenarios =
        std::filesystem::temp_directory_path() / "dsoc-programs-bad-scenario.json";
    {
        std::ofstream out(scenarios);
        out << R"({"version": 1, "scenarios": [{"name": "nowhere", "map": "no_such_map_dsoc",
                   "viewers": 2, "bots": 2, "duration_s": 1, "tick_rate": 30}]})";
    }
    const ProgramRun run = run_program({program("dsoc-snapshot-bytes"), "--scenarios",
                                        scenarios.string(), "--scenario", "nowhere"});
    EXPECT_EQ(run.status, 2) << run.err;
    EXPECT_NE(run.err.find("scenario nowhere: cannot load map 'no_such_map_dsoc'"),
              std::string::npos)
        << run.err;
    std::filesystem::remove(scenarios);
}

} // namespace
} // namespace dsoc::testing

namespace dsoc::testing {
namespace {

TEST(BakeProgram, JsonGivesTheSpecTheCpuAndThePeakMemoryAndACachedSecondRun) {
    // What scripts/bake-all keeps per map: the map as given (to resume by), the bake's
    // CPU over all cores and the process's peak memory, and the block unions a culler
    // holds beside the table; a second run loads the table.
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "dsoc-bake-json";
    std::filesystem::remove_all(dir);
    const auto bake = [&] {
        return run_program({program("dsoc-bake"), "--json", "--cell-size", "256", "--cache-dir",
                            dir.string(), "gen:rooms:1"});
    };
    for (const bool cached : {false, true}) {
        const ProgramRun run = bake();
        ASSERT_EQ(run.status, 0) << run.err;
        const auto out = nlohmann::json::parse(run.out, nullptr, false);
        ASSERT_TRUE(out.is_object()) << run.out;
        EXPECT_EQ(out["spec"], "gen:rooms:1");
        EXPECT_EQ(out["from_cache"], cached);
        EXPECT_GT(out["peak_rss_bytes"].get<double>(), 1e6);
        EXPECT_GT(out["block_union_bytes"].get<double>(), 0.0); // held beside the table
        if (!cached) {
            EXPECT_GT(out["cpu_seconds"].get<double>(), 0.0);
            EXPECT_GT(out["exact_tests"].get<double>(), 0.0);
        }
    }
    std::filesystem::remove_all(dir);
}

} // namespace
} // namespace dsoc::testing
