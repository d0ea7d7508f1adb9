#pragma once
// Numbers with units as a user writes them on the command line and in scenario files:
// "50ms", "1.5s", "1m30s", "12KiB/s", "1%", "300". Used by thresholds (whose figure
// fixes the kind of quantity) and by the scenario file's durations.

#include <string>
#include <string_view>

namespace dsoc::simclient {

/// What a figure measures, which fixes the units it may be written in and its base unit.
enum class Dimension {
    time,      ///< base: milliseconds; units us, ms, s, m (minutes), h
    byte_rate, ///< base: bytes per second; units B/s, KiB/s, MiB/s, GiB/s, kB/s, MB/s, GB/s
    ratio,     ///< base: a fraction (0.01); units % (1% = 0.01), or a bare fraction
    plain,     ///< a count or a rate per second: a bare number, no unit
};

/// "a time (ms, s, ...)": how a dimension is named in messages, with its units.
[[nodiscard]] std::string describe(Dimension dimension);

/// A number as written, converted to its dimension's base unit.
struct Quantity {
    double base = 0.0;   ///< in the dimension's base unit
    std::string unit;    ///< the unit as written ("" for a bare number)
    double per_unit = 1; ///< base units in one `unit` (to show other values in it)
};

/// Parses `text` (surrounding spaces allowed) as a quantity of `dimension`. A bare
/// number is in the base unit. Times may be compound ("1m30s"). Returns false and says
/// why in `error` on a malformed number, an unknown unit, or a unit of another
/// dimension.
[[nodiscard]] bool parse_quantity(std::string_view text, Dimension dimension, Quantity& out,
                                  std::string& error);

/// A duration in seconds ("5s", "500ms", "1m30s"; a bare number is seconds); false with
/// `error` when malformed or negative.
[[nodiscard]] bool parse_duration_s(std::string_view text, double& seconds, std::string& error);

} // namespace dsoc::simclient
