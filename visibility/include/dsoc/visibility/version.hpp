#pragma once

namespace dsoc {

/// The version of the dsoc library linked in, as "MAJOR.MINOR.PATCH": the version of
/// the CMake project it was built from (project(dsoc VERSION ...), also what
/// find_package(dsoc) reports as dsoc_VERSION). While MAJOR is 0, a change of MINOR
/// may break the API; the installed package accepts only the same MAJOR.MINOR. The
/// wire protocol has its own version (dsoc::protocol::kProtocolVersion), checked at
/// hello. Static storage; never null; thread-safe.
const char* version() noexcept;

} // namespace dsoc
