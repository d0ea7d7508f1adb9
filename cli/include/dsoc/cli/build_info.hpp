#pragma once
// What a dsoc program was built from: the project version and the git commit. The
// one place the version line of every program's --version and the build info of
// /metrics come from.

#include <string>
#include <string_view>

namespace dsoc::cli {

struct BuildInfo {
    /// "MAJOR.MINOR.PATCH": dsoc::version(), the CMake project() version.
    std::string version;
    /// The git commit the build was made from, 12 hex digits, "-dirty" appended when
    /// tracked files differed from it; empty when the build did not know it (not a
    /// git checkout, no git).
    std::string commit;
};

/// This build's. Static storage; thread-safe.
[[nodiscard]] const BuildInfo& build_info();

/// "<program> <version> (commit <commit>)", or "<program> <version>" when the commit
/// is not known: what --version prints, one line without the newline.
[[nodiscard]] std::string version_line(std::string_view program, const BuildInfo& info);
[[nodiscard]] std::string version_line(std::string_view program);

} // namespace dsoc::cli
