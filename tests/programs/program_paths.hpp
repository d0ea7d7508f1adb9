#pragma once
// Where the tests find the built programs (tests/programs/CMakeLists.txt), and the
// command line of a server that starts in moments.

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

namespace dsoc::testing {

/// The path of the built program `name` (build/bin/<name>).
inline std::string program(const std::string& name) {
    return std::string(DSOC_BIN_DIR) + "/" + name;
}

/// Every program that follows dsoc::cli's conventions.
inline std::vector<std::string> cli_programs() {
    std::vector<std::string> names;
    std::istringstream list(DSOC_PROGRAMS);
    for (std::string name; std::getline(list, name, ',');) {
        names.push_back(name);
    }
    return names;
}

/// dsoc-server on port 0 with a generated map, no bake, 4 bots and 1 thread (it starts
/// in moments), then `more`; --insecure unless `more` names a --token-key-file.
inline std::vector<std::string> light_server(const std::vector<std::string>& more = {}) {
    std::vector<std::string> argv = {program("dsoc-server"),
                                     "--port",
                                     "0",
                                     "--map",
                                     "gen:rooms:1",
                                     "--baked-stage",
                                     "false",
                                     "--bots",
                                     "4",
                                     "--threads",
                                     "1"};
    argv.insert(argv.end(), more.begin(), more.end());
    if (std::find(more.begin(), more.end(), "--token-key-file") == more.end()) {
        argv.emplace_back("--insecure");
    }
    return argv;
}

} // namespace dsoc::testing
