#pragma once
// Counts the fields of an aggregate at compile time, so that a test can check that a
// hand-written list of a config's fields (a visitor) misses none.

#include <cstddef>

namespace dsoc::testing {

namespace detail {
struct AnyValue {
    template <class T>
    operator T() const; // NOLINT: never defined, only for overload resolution
};
} // namespace detail

/// The largest N for which T{a1, ..., aN} compiles: T's field count.
template <class T, class... Args>
constexpr std::size_t aggregate_field_count(Args... args) {
    if constexpr (requires { T{args..., detail::AnyValue{}}; }) {
        return aggregate_field_count<T>(args..., detail::AnyValue{});
    } else {
        return sizeof...(Args);
    }
}

} // namespace dsoc::testing
