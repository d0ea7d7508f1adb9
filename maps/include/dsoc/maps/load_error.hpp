#pragma once
// Errors as values for everything that reads outside bytes (map files, archives).
// Bad input never throws out of the public API and never crashes: it comes back
// as a LoadError naming the file, the part of it (lump, line, archive entry) and
// what is wrong.

#include <string>
#include <utility>
#include <variant>

namespace dsoc::maps {

struct LoadError {
    std::string file; ///< path or archive:entry that was being read
    std::string lump; ///< part of the file, e.g. "brushes (lump 8)" or "line 12"; may be empty
    std::string what; ///< what is wrong, in words

    /// "file: lump: what" (parts that are empty are left out).
    [[nodiscard]] std::string message() const;
};

/// Either a value or a LoadError (std::expected is C++23).
template <class T>
class [[nodiscard]] Result {
public:
    Result(T value) : state_(std::move(value)) {}         // NOLINT: implicit by design
    Result(LoadError error) : state_(std::move(error)) {} // NOLINT: implicit by design

    [[nodiscard]] bool ok() const { return state_.index() == 0; }
    explicit operator bool() const { return ok(); }

    /// Precondition: ok().
    [[nodiscard]] T& value() & { return std::get<0>(state_); }
    [[nodiscard]] const T& value() const& { return std::get<0>(state_); }
    [[nodiscard]] T&& value() && { return std::get<0>(std::move(state_)); }
    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }

    /// Precondition: !ok().
    [[nodiscard]] const LoadError& error() const { return std::get<1>(state_); }

private:
    std::variant<T, LoadError> state_;
};

} // namespace dsoc::maps
