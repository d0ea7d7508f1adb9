#pragma once

namespace dsoc {

/// The library version as "MAJOR.MINOR.PATCH". Static storage; never null.
const char* version() noexcept;

} // namespace dsoc
