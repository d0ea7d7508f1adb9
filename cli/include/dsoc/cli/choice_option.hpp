#pragma once
// A command-line option whose value is one of an enum's names (dsoc::interest's
// PolicyKind, CullerKind, ExactStages): parsed into the enum as the command line is
// read, so that a wrong name stops the program there, with the flag and every allowed
// name ("--policy: must be one of dsoc, occlusion, pvs, distance, broadcast; got 'x'").
// The enum's parse_choice(), not_a_choice() and name_of() are found by argument-
// dependent lookup (dsoc/interest/policy_choices.hpp), so dsoc::cli needs no interest
// header.

#include <CLI/CLI.hpp>

#include <string>

namespace dsoc::cli {

/// Adds `flag`, setting `field` to the choice it names; help shows `help` and the
/// current value's name as the default.
template <class Choice>
CLI::Option* add_choice_option(CLI::App& app, const std::string& flag, Choice& field,
                               const std::string& help) {
    return app
        .add_option_function<std::string>(
            flag, [&field](const std::string& text) { (void)parse_choice(text, field); }, help)
        ->check([](const std::string& text) {
            Choice choice{};
            return parse_choice(text, choice) ? std::string() : not_a_choice(text, choice);
        })
        ->default_str(std::string(name_of(field)));
}

} // namespace dsoc::cli
