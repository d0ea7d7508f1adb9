#include "dsoc/simclient/quantity.hpp"

#include <fmt/format.h>

#include <array>
#include <cctype>
#include <charconv>
#include <utility>

namespace dsoc::simclient {

namespace {

struct Unit {
    std::string_view name;
    Dimension dimension;
    double per_unit; // base units in one of this unit
};

constexpr std::array kUnits{
    Unit{"us", Dimension::time, 0.001},
    Unit{"ms", Dimension::time, 1.0},
    Unit{"s", Dimension::time, 1000.0},
    Unit{"m", Dimension::time, 60'000.0},
    Unit{"min", Dimension::time, 60'000.0},
    Unit{"h", Dimension::time, 3'600'000.0},
    Unit{"B/s", Dimension::byte_rate, 1.0},
    Unit{"KiB/s", Dimension::byte_rate, 1024.0},
    Unit{"MiB/s", Dimension::byte_rate, 1024.0 * 1024.0},
    Unit{"GiB/s", Dimension::byte_rate, 1024.0 * 1024.0 * 1024.0},
    Unit{"kB/s", Dimension::byte_rate, 1e3},
    Unit{"MB/s", Dimension::byte_rate, 1e6},
    Unit{"GB/s", Dimension::byte_rate, 1e9},
    Unit{"%", Dimension::ratio, 0.01},
};

std::string_view trim(std::string_view s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front())) != 0) {
        s.remove_prefix(1);
    }
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back())) != 0) {
        s.remove_suffix(1);
    }
    return s;
}

const Unit* find_unit(std::string_view name) {
    for (const Unit& u : kUnits) {
        if (u.name == name) {
            return &u;
        }
    }
    return nullptr;
}

/// Reads a number at the front of `s` and removes it; false when there is none.
bool take_number(std::string_view& s, double& value) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    if (ec != std::errc() || end == s.data()) {
        return false;
    }
    s.remove_prefix(static_cast<std::size_t>(end - s.data()));
    return true;
}

/// Removes and returns the unit at the front of `s`: everything up to the next digit,
/// sign or dot, spaces dropped.
std::string take_unit(std::string_view& s) {
    std::string unit;
    while (!s.empty() && std::isdigit(static_cast<unsigned char>(s.front())) == 0 &&
           s.front() != '.' && s.front() != '-' && s.front() != '+') {
        if (std::isspace(static_cast<unsigned char>(s.front())) == 0) {
            unit += s.front();
        }
        s.remove_prefix(1);
    }
    return unit;
}

} // namespace

std::string describe(Dimension dimension) {
    switch (dimension) {
    case Dimension::time:
        return "a time (us, ms, s, m, h; a bare number is ms)";
    case Dimension::byte_rate:
        return "a byte rate (B/s, KiB/s, MiB/s, GiB/s, kB/s, MB/s, GB/s; a bare number is B/s)";
    case Dimension::ratio:
        return "a ratio (1% or 0.01)";
    case Dimension::plain:
        return "a bare number";
    }
    return "?";
}

bool parse_quantity(std::string_view text, Dimension dimension, Quantity& out, std::string& error) {
    std::string_view rest = trim(text);
    const std::string written(rest);
    Quantity q;
    q.unit.clear();
    q.per_unit = 1.0;
    bool first = true;
    while (first || !rest.empty()) {
        double value = 0.0;
        if (!take_number(rest, value)) {
            error =
                fmt::format("'{}' is not a number{}", written, first ? "" : " followed by units");
            return false;
        }
        const std::string unit = take_unit(rest);
        const Unit* u = unit.empty() ? nullptr : find_unit(unit);
        if (!unit.empty() && u == nullptr) {
            error = fmt::format("'{}': unknown unit '{}'; expected {}", written, unit,
                                describe(dimension));
            return false;
        }
        if (u != nullptr && u->dimension != dimension) {
            error = fmt::format("'{}': '{}' does not fit; expected {}", written, unit,
                                describe(dimension));
            return false;
        }
        if (u == nullptr && !(first && rest.empty())) {
            error = fmt::format("'{}': a number without a unit in a compound quantity", written);
            return false;
        }
        if (!first && dimension != Dimension::time) {
            error = fmt::format("'{}': only times may be compound (1m30s)", written);
            return false;
        }
        const double per_unit = u != nullptr ? u->per_unit : 1.0;
        q.base += value * per_unit;
        if (first) {
            q.unit = unit;
            q.per_unit = per_unit;
        }
        first = false;
    }
    out = std::move(q);
    return true;
}

bool parse_duration_s(std::string_view text, double& seconds, std::string& error) {
    // A bare number of a duration is seconds, not the time dimension's milliseconds.
    std::string_view t = trim(text);
    double bare = 0.0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), bare);
    Quantity q;
    if (ec == std::errc() && end == t.data() + t.size()) {
        q.base = bare * 1000.0;
    } else if (!parse_quantity(t, Dimension::time, q, error)) {
        return false;
    }
    if (q.base < 0.0) {
        error = fmt::format("'{}' is negative", t);
        return false;
    }
    seconds = q.base / 1000.0;
    return true;
}

} // namespace dsoc::simclient
