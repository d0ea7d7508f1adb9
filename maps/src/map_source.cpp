#include "dsoc/maps/map_source.hpp"

#include "dsoc/maps/generators.hpp"
#include "dsoc/maps/map_spec.hpp"
#include "dsoc/maps/pk3.hpp"
#include "dsoc/maps/q3_map.hpp"
#include "dsoc/maps/q3_shaders.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <system_error>

namespace dsoc::maps {
namespace {

namespace fs = std::filesystem;

/// Archives to search, in priority order.
std::vector<fs::path> archives(const MapSearch& search) {
    std::vector<fs::path> out;
    for (const fs::path& location : search.locations) {
        std::error_code ec;
        if (fs::is_directory(location, ec)) {
            std::vector<fs::path> in_dir;
            for (const auto& entry : fs::directory_iterator(location, ec)) {
                if (entry.path().extension() == ".pk3") {
                    in_dir.push_back(entry.path());
                }
            }
            std::sort(in_dir.rbegin(), in_dir.rend());
            out.insert(out.end(), in_dir.begin(), in_dir.end());
        } else if (fs::is_regular_file(location, ec)) {
            out.push_back(location);
        }
    }
    return out;
}

Result<Map> load_generated(std::string_view spec) {
    const std::string_view rest = spec.substr(4);
    const std::size_t colon = rest.find(':');
    const std::string_view kind = rest.substr(0, colon);
    std::uint64_t seed = 1;
    if (colon != std::string_view::npos) {
        const std::string_view digits = rest.substr(colon + 1);
        const auto [end, code] =
            std::from_chars(digits.data(), digits.data() + digits.size(), seed);
        if (code != std::errc() || end != digits.data() + digits.size()) {
            return LoadError{std::string(spec), "", "seed is not a decimal number"};
        }
    }
    if (kind == "city") {
        CityParams params;
        params.seed = seed;
        return build_map(generate_city(params), std::string(spec));
    }
    if (kind == "rooms") {
        RoomsParams params;
        params.seed = seed;
        return build_map(generate_rooms(params), std::string(spec));
    }
    return LoadError{std::string(spec), "", "unknown generator (expected gen:city or gen:rooms)"};
}

/// read_shader_scripts(archives), read once per process while the archives are the same
/// files (path, size and modification time): a test or a tool loads maps many times, and
/// the game's archives hold hundreds of megabytes.
std::shared_ptr<const ShaderScriptsRead> shader_scripts_of(const std::vector<fs::path>& archives) {
    std::string key;
    for (const fs::path& archive : archives) {
        std::error_code ec;
        const auto size = fs::file_size(archive, ec);
        const auto time = fs::last_write_time(archive, ec).time_since_epoch().count();
        key += archive.string() + '\n' + std::to_string(size) + '\n' + std::to_string(time) + '\n';
    }
    static std::mutex mutex;
    static std::map<std::string, std::shared_ptr<const ShaderScriptsRead>> read;
    const std::lock_guard lock(mutex);
    auto& scripts = read[key];
    if (scripts == nullptr) {
        scripts = std::make_shared<const ShaderScriptsRead>(read_shader_scripts(archives));
    }
    return scripts;
}

/// A Quake 3 map given by `spec`: the .bsp or single-map .pk3 at `path`, else the map of
/// that name on the search path.
Result<Map> load_q3(std::string_view spec, const fs::path& path, bool is_pk3, bool is_bsp,
                    const MapSearch& search, const ShaderScripts& scripts) {
    if (is_bsp) {
        return load_q3_map_from_bsp(path, &scripts);
    }
    if (is_pk3) {
        auto names = list_pk3_maps(path);
        if (!names) {
            return names.error();
        }
        if (names.value().size() != 1) {
            return LoadError{path.string(), "",
                             "archive holds " + std::to_string(names.value().size()) +
                                 " maps: give one map's name, with the archive on the map "
                                 "search path (DSOC_MAP_PATH)"};
        }
        return load_q3_map_from_pk3(path, names.value().front(), &scripts);
    }
    if (spec.empty() || spec.find_first_of("/\\") != std::string_view::npos) {
        return LoadError{std::string(spec), "", "no such file"};
    }
    auto bsp = find_q3_bsp(spec, search);
    if (!bsp) {
        return bsp.error();
    }
    return map_from_q3_bsp(bsp.value(), std::string(spec), &scripts);
}

} // namespace

MapSearch MapSearch::from_environment() {
    MapSearch search;
    if (const char* env = std::getenv("DSOC_MAP_PATH"); env != nullptr) {
        std::string_view paths(env);
        while (!paths.empty()) {
            const std::size_t colon = paths.find(':');
            const std::string_view one = paths.substr(0, colon);
            if (!one.empty()) {
                search.locations.emplace_back(std::string(one));
            }
            paths = colon == std::string_view::npos ? std::string_view() : paths.substr(colon + 1);
        }
    }
    search.locations.emplace_back(kOpenArenaBaseDir);
    return search;
}

Result<Map> load_map(std::string_view spec, const MapSearch& search) {
    if (spec.starts_with("gen:")) {
        return load_generated(spec);
    }
    const fs::path path{std::string(spec)};
    std::error_code ec;
    const bool is_file = fs::is_regular_file(path, ec);
    const bool is_pk3 = is_file && (path.extension() == ".pk3" || path.extension() == ".PK3");
    const bool is_bsp = is_file && (path.extension() == ".bsp" || path.extension() == ".BSP");
    if (!is_file || is_pk3 || is_bsp) {
        // A Quake 3 map: the shader scripts of the archives the game would load with it
        // (an archive given by path, then the search path's) tell its see-through shaders.
        std::vector<fs::path> with_scripts = archives(search);
        if (is_pk3) {
            with_scripts.insert(with_scripts.begin(), path);
        }
        const std::shared_ptr<const ShaderScriptsRead> read = shader_scripts_of(with_scripts);
        auto map = load_q3(spec, path, is_pk3, is_bsp, search, read->scripts);
        if (map) {
            map.value().shader_script_problems = read->problems;
        }
        return map;
    }
    auto text = read_text_map_file(path);
    if (!text) {
        return text.error();
    }
    return build_map(text.value(), path.string());
}

Result<q3::Q3Bsp> find_q3_bsp(std::string_view name, const MapSearch& search) {
    const std::string entry = "maps/" + std::string(name) + ".bsp";
    std::error_code ec;
    for (const fs::path& location : search.locations) {
        const fs::path loose = location / entry;
        if (fs::is_regular_file(loose, ec)) {
            return q3::read_q3_bsp_file(loose);
        }
    }
    std::string looked;
    std::string unreadable;
    for (const fs::path& archive : archives(search)) {
        auto names = list_pk3_maps(archive);
        looked += (looked.empty() ? "" : ", ") + archive.string();
        if (!names) {
            // A corrupt archive must not hide a good one; say so if nothing is found.
            unreadable += "; unreadable: " + names.error().message();
            continue;
        }
        for (const std::string& candidate : names.value()) {
            if (candidate.size() == name.size() &&
                std::equal(candidate.begin(), candidate.end(), name.begin(), [](char a, char b) {
                    return std::tolower(static_cast<unsigned char>(a)) ==
                           std::tolower(static_cast<unsigned char>(b));
                })) {
                auto bytes = read_pk3_entry(archive, entry);
                if (!bytes) {
                    return bytes.error();
                }
                return q3::parse_q3_bsp(bytes.value(), archive.string() + ":" + entry);
            }
        }
    }
    return LoadError{std::string(name), "",
                     "no map of that name (looked for " + entry + " in " +
                         (looked.empty() ? std::string("no archives") : looked) + ")" + unreadable};
}

std::vector<std::string> list_maps(const MapSearch& search) {
    std::set<std::string> names;
    for (const fs::path& archive : archives(search)) {
        if (auto listed = list_pk3_maps(archive)) {
            names.insert(listed.value().begin(), listed.value().end());
        }
    }
    return {names.begin(), names.end()};
}

} // namespace dsoc::maps
