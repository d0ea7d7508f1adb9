// dsoc-mapinfo: loads a map the way a server would and prints what it holds:
// brushes, occluders, degenerate brushes skipped, spawn points, bounds, load time,
// and the sanity checks' findings (dsoc/maps/map_checks.hpp), which dsoc-server logs
// at start (and refuses to run a map with an "unusable" one).
// Exit status (dsoc/cli/program.hpp): 0 loaded (findings or not), 1 the map failed to
// load (message on stderr), 2 bad usage.

#include "dsoc/cli/program.hpp"
#include "dsoc/maps/map_checks.hpp"
#include "dsoc/maps/map_source.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <iostream>

namespace {

nlohmann::json vec_json(glm::vec3 v) {
    return nlohmann::json::array({v.x, v.y, v.z});
}

void print_text(const dsoc::maps::Map& map, const std::vector<dsoc::maps::MapFinding>& findings,
                double load_ms) {
    const auto& s = map.stats;
    std::printf("map                 %s\n", map.name.c_str());
    std::printf("source              %s\n", map.source.c_str());
    std::printf("brushes             %zu (world %zu)\n", s.brushes_total, s.world_brushes);
    std::printf("opaque occluders    %zu (of %zu opaque solid brushes)\n", s.opaque_occluders,
                s.opaque_candidates);
    std::printf("collision brushes   %zu (of %zu solid or player clip)\n", s.collision_brushes,
                s.collision_candidates);
    std::printf("not occluding       %zu translucent, %zu all-nodraw, %zu see-through shader\n",
                s.translucent_skipped, s.nodraw_skipped, s.see_through_skipped);
    std::printf("shader scripts      %zu%s\n", s.shader_scripts,
                s.shader_scripts == 0 ? " (none read whole: see-through told by shader names)"
                                      : "");
    if (map.pvs != nullptr && map.pvs->has_visibility()) {
        std::printf("pvs                 %d clusters, %llu one-way pairs made two-way, %llu pairs "
                    "opened through see-through brushes\n",
                    map.pvs->cluster_count(),
                    static_cast<unsigned long long>(map.pvs->one_way_pairs()),
                    static_cast<unsigned long long>(map.pvs->opened_pairs()));
    }
    std::printf("degenerate skipped  %zu (too many planes %zu, too few planes %zu, non-finite "
                "%zu, unbounded %zu, empty %zu)\n",
                s.degenerate.total(), s.degenerate.too_many_planes, s.degenerate.too_few_planes,
                s.degenerate.non_finite_plane, s.degenerate.unbounded, s.degenerate.empty);
    std::printf("patches left out    %zu (%zu of the world's drawn opaque: they block the oracle's "
                "rays)\n",
                s.patches_left_out, s.opaque_patches);
    std::printf("spawn points        %zu\n", map.spawn_points.size());
    std::printf("hazards             %zu\n", map.hazards.size());
    if (map.bounds.is_empty()) {
        std::printf("bounds              empty\n");
    } else {
        std::printf("bounds              (%.0f %.0f %.0f) .. (%.0f %.0f %.0f)\n", map.bounds.min.x,
                    map.bounds.min.y, map.bounds.min.z, map.bounds.max.x, map.bounds.max.y,
                    map.bounds.max.z);
    }
    std::printf("load ms             %.1f\n", load_ms);
    std::printf("findings            %zu%s\n", findings.size(),
                dsoc::maps::any_unusable(findings) ? " (unusable: a server refuses this map)" : "");
    for (const auto& f : findings) {
        std::printf("  %-8s %s: %s\n", dsoc::maps::to_string(f.severity), f.code.c_str(),
                    f.text.c_str());
    }
}

void print_json(const dsoc::maps::Map& map, const std::vector<dsoc::maps::MapFinding>& findings,
                double load_ms) {
    const auto& s = map.stats;
    nlohmann::json out;
    out["map"] = map.name;
    out["source"] = map.source;
    out["brushes"] = s.brushes_total;
    out["world_brushes"] = s.world_brushes;
    out["opaque_candidates"] = s.opaque_candidates;
    out["opaque_occluders"] = s.opaque_occluders;
    out["collision_candidates"] = s.collision_candidates;
    out["collision_brushes"] = s.collision_brushes;
    out["translucent_skipped"] = s.translucent_skipped;
    out["nodraw_skipped"] = s.nodraw_skipped;
    out["see_through_skipped"] = s.see_through_skipped;
    out["shader_scripts"] = s.shader_scripts;
    if (map.pvs != nullptr && map.pvs->has_visibility()) {
        out["pvs_clusters"] = map.pvs->cluster_count();
        out["pvs_one_way_pairs"] = map.pvs->one_way_pairs();
        out["pvs_opened_pairs"] = map.pvs->opened_pairs();
    }
    out["patches_left_out"] = s.patches_left_out;
    out["opaque_patches"] = s.opaque_patches;
    out["degenerate_skipped"] = s.degenerate.total();
    out["degenerate_by_reason"] = {{"too_many_planes", s.degenerate.too_many_planes},
                                   {"too_few_planes", s.degenerate.too_few_planes},
                                   {"non_finite_plane", s.degenerate.non_finite_plane},
                                   {"unbounded", s.degenerate.unbounded},
                                   {"empty", s.degenerate.empty}};
    out["spawn_points"] = map.spawn_points.size();
    out["hazards"] = map.hazards.size();
    if (map.bounds.is_empty()) {
        out["bounds"] = nullptr;
    } else {
        out["bounds"] = {{"min", vec_json(map.bounds.min)}, {"max", vec_json(map.bounds.max)}};
    }
    out["load_ms"] = load_ms;
    out["usable"] = !dsoc::maps::any_unusable(findings);
    out["findings"] = nlohmann::json::array();
    for (const auto& f : findings) {
        out["findings"].push_back(
            {{"severity", dsoc::maps::to_string(f.severity)}, {"code", f.code}, {"text", f.text}});
    }
    std::cout << out.dump() << '\n';
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"Loads a map and prints its brushes, occluders, spawn points and bounds.\n"
                 "MAP is a map name (looked up as maps/MAP.bsp in .pk3 archives: --pak, then\n"
                 "$DSOC_MAP_PATH, then /usr/share/games/openarena/baseoa), a path to a .bsp\n"
                 "or dsoc text map, or gen:city[:seed] / gen:rooms[:seed]."};
    dsoc::cli::set_up(app, "dsoc-mapinfo");
    std::string map_spec;
    bool json = false;
    std::vector<std::string> paks;
    bool list = false;
    app.add_option("MAP", map_spec, "map name, file path or generator");
    app.add_flag("--json", json,
                 "print one JSON object (keys brushes, opaque_occluders, "
                 "degenerate_skipped, spawn_points, bounds, load_ms, usable, findings, ...)");
    app.add_option("--pak", paks, "a .pk3 archive or a directory of them, searched first")
        ->allow_extra_args(false);
    app.add_flag("--list", list, "list the map names found and exit");
    if (const auto stop = dsoc::cli::parse(app, argc, argv)) {
        return *stop;
    }

    dsoc::maps::MapSearch search = dsoc::maps::MapSearch::from_environment();
    search.locations.insert(search.locations.begin(), paks.begin(), paks.end());
    if (list) {
        for (const std::string& name : dsoc::maps::list_maps(search)) {
            std::cout << name << '\n';
        }
        return dsoc::cli::exit_ok;
    }
    if (map_spec.empty()) {
        std::cerr << "dsoc-mapinfo: MAP is required (see --help)\n";
        return dsoc::cli::exit_usage;
    }
    const auto start = std::chrono::steady_clock::now();
    auto map = dsoc::maps::load_map(map_spec, search);
    const double load_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (!map) {
        std::cerr << "dsoc-mapinfo: "
                  << dsoc::cli::map_load_failure("MAP", map_spec, map.error().message()) << '\n';
        return dsoc::cli::exit_failure;
    }
    const auto findings = dsoc::maps::check_map(map.value());
    if (json) {
        print_json(map.value(), findings, load_ms);
    } else {
        print_text(map.value(), findings, load_ms);
    }
    return dsoc::cli::exit_ok;
}
