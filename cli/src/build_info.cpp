#include "dsoc/cli/build_info.hpp"

#include "dsoc/visibility/version.hpp"

namespace dsoc::cli {

namespace detail {
extern const char* const kBuildCommit; // build_commit.cpp, generated at build time
} // namespace detail

const BuildInfo& build_info() {
    static const BuildInfo info{dsoc::version(), detail::kBuildCommit};
    return info;
}

std::string version_line(std::string_view program, const BuildInfo& info) {
    std::string line = std::string(program) + " " + info.version;
    if (!info.commit.empty()) {
        line += " (commit " + info.commit + ")";
    }
    return line;
}

std::string version_line(std::string_view program) {
    return version_line(program, build_info());
}

} // namespace dsoc::cli
