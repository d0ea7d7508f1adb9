#pragma once
// Where the tests find the built programs (tests/programs/CMakeLists.txt).

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

} // namespace dsoc::testing
