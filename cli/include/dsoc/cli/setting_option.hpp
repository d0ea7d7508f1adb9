#pragma once
// A setting's command-line option: a flag bound to a variable whose value before the
// command line is read is the default, and --help shows that default
// ("--tick-rate INT=60"). The form of every dsoc program's setting flags, written once.

#include <CLI/CLI.hpp>

#include <string>

namespace dsoc::cli {

/// Adds `flag`, read into `field`; help shows `help` and `field`'s current value as the
/// default. Returns the option, for what a flag adds of its own (->check(...)).
template <class T>
CLI::Option* add_setting(CLI::App& app, const std::string& flag, T& field,
                         const std::string& help) {
    return app.add_option(flag, field, help)->capture_default_str();
}

} // namespace dsoc::cli
