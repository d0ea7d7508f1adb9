#include "dsoc/cli/program.hpp"

#include "dsoc/cli/build_info.hpp"

#include <filesystem>
#include <iostream>

namespace dsoc::cli {

void set_up(CLI::App& app, std::string_view program) {
    const std::string name(program);
    app.name(name);
    app.set_version_flag("--version", version_line(program),
                         "Print the program, its version and git commit, and exit");
    app.failure_message([name](const CLI::App*, const CLI::Error& e) {
        return name + ": " + e.what() + " (see " + name + " --help)\n";
    });
}

std::optional<int> parse(CLI::App& app, int argc, const char* const* argv) {
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // Help and version print and give CLI11's 0; its errors have codes of their own
        // (100..127), which are all usage errors here.
        const int status = app.exit(e, std::cout, std::cerr);
        return status == 0 ? exit_ok : exit_usage;
    }
    return std::nullopt;
}

bool is_map_name(std::string_view spec) {
    // As maps::load_map() decides: an existing file, a path or a generator is not a name.
    std::error_code ec;
    return !spec.empty() && !spec.starts_with("gen:") &&
           spec.find_first_of("/\\") == std::string_view::npos &&
           !std::filesystem::is_regular_file(std::filesystem::path(std::string(spec)), ec);
}

std::string map_load_failure(std::string_view flag, std::string_view spec, std::string_view error) {
    std::string text = "cannot load map '" + std::string(spec) + "': " + std::string(error);
    if (is_map_name(spec)) {
        text += ". `dsoc-mapinfo --list` lists the map names found; " + std::string(flag) +
                " also takes a path to a .bsp or dsoc text map, or gen:city / gen:rooms; "
                "DSOC_MAP_PATH adds .pk3 archives or directories to search";
    }
    return text;
}

} // namespace dsoc::cli
