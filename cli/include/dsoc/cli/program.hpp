#pragma once
// The command-line conventions every dsoc program follows (docs/operations.md, "Exit
// statuses"): --version, one meaning for each exit status, command-line errors named
// the same way. Every main() calls set_up() and parse(), not a copy of its own.

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <string_view>

namespace dsoc::cli {

/// What the exit status of every dsoc program means.
enum ExitStatus : int {
    /// Did what was asked; also --help and --version.
    exit_ok = 0,
    /// Ran, and failed: a check or verdict that failed (dsoc-simclient's FAIL,
    /// dsoc-token check of an invalid token, dsoc-mapinfo on a map that does not
    /// load), or an error while running (a port in use, a file that cannot be written).
    exit_failure = 1,
    /// Did not start: the command line (unknown flag, bad value, missing argument), a
    /// config file or setting, or an input they name (a map to run on, a key file) is
    /// wrong. The message on stderr names which, where and why.
    exit_usage = 2,
};

/// Makes `app` the command line of the dsoc program `program`: its name, --version
/// (prints version_line(program) on stdout and exits with exit_ok), and errors written
/// as "<program>: <what>" with a pointer to --help. Call before adding subcommands.
void set_up(CLI::App& app, std::string_view program);

/// Parses the command line; use it instead of CLI11_PARSE. Returns the exit status when
/// the program must stop now: exit_ok after printing --help or --version, exit_usage
/// after naming a command-line error on stderr. Returns nothing when it should go on.
[[nodiscard]] std::optional<int> parse(CLI::App& app, int argc, const char* const* argv);

/// True when maps::load_map() looks `spec` up as a map name (oa_dm4): not gen:..., not
/// a path, not an existing file.
[[nodiscard]] bool is_map_name(std::string_view spec);

/// What to say when the map `spec`, given with `flag` (e.g. "--map"), did not load:
/// "cannot load map '<spec>': <error>", and when `spec` is a map name, where the names
/// are listed (dsoc-mapinfo --list), what else `flag` takes and how to search more
/// places (DSOC_MAP_PATH).
[[nodiscard]] std::string map_load_failure(std::string_view flag, std::string_view spec,
                                           std::string_view error);

} // namespace dsoc::cli
