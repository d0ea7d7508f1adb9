#include "dsoc/maps/map_checks.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string_view>

namespace dsoc::maps {
namespace {

constexpr std::size_t kExamples = 3; ///< spawn points quoted per finding

bool finite(glm::vec3 v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

bool finite(const visibility::Aabb& box) {
    return box.is_empty() || (finite(box.min) && finite(box.max));
}

std::string format_point(glm::vec3 p) {
    char text[96];
    std::snprintf(text, sizeof text, "(%g %g %g)", static_cast<double>(p.x),
                  static_cast<double>(p.y), static_cast<double>(p.z));
    return text;
}

/// How deep `p` lies inside `brush` (the smallest distance to one of its planes,
/// positive inside, negative outside).
float depth_inside(const CollisionBrush& brush, glm::vec3 p) {
    float depth = std::numeric_limits<float>::max();
    for (const visibility::Plane& plane : brush.planes) {
        const float length = glm::length(plane.normal);
        depth = std::min(depth, -plane.signed_distance(p) / length);
    }
    return depth;
}

bool in_solid(const Map& map, glm::vec3 p) {
    return std::any_of(
        map.collision_brushes.begin(), map.collision_brushes.end(), [&](const CollisionBrush& b) {
            return b.bounds.expanded(1.0f).contains(p) && depth_inside(b, p) > kSpawnInSolidDepth;
        });
}

bool in_hazard(const Map& map, glm::vec3 p) {
    return std::any_of(map.hazards.begin(), map.hazards.end(),
                       [&](const Hazard& h) { return h.bounds.contains(p); });
}

/// The first element where `part` is non-finite, described; empty when all are finite.
std::string first_non_finite(const Map& map) {
    for (std::size_t i = 0; i < map.spawn_points.size(); ++i) {
        const SpawnPoint& s = map.spawn_points[i];
        if (!finite(s.origin) || !std::isfinite(s.yaw_degrees)) {
            return "spawn point " + std::to_string(i);
        }
    }
    for (std::size_t i = 0; i < map.occluders.size(); ++i) {
        const auto& o = map.occluders[i];
        if (!finite(o.bounds()) || !std::all_of(o.vertices().begin(), o.vertices().end(),
                                                [](glm::vec3 v) { return finite(v); })) {
            return "occluder " + std::to_string(i);
        }
    }
    for (std::size_t i = 0; i < map.collision_brushes.size(); ++i) {
        const CollisionBrush& b = map.collision_brushes[i];
        if (!finite(b.bounds) ||
            !std::all_of(b.planes.begin(), b.planes.end(), [](const visibility::Plane& p) {
                return finite(p.normal) && std::isfinite(p.distance);
            })) {
            return "collision brush " + std::to_string(i);
        }
    }
    for (std::size_t i = 0; i < map.hazards.size(); ++i) {
        if (!finite(map.hazards[i].bounds)) {
            return "hazard " + std::to_string(i);
        }
    }
    if (!finite(map.bounds)) {
        return "the world bounds";
    }
    return {};
}

/// Spawn points for which `bad` holds, as one finding (nothing when there are none).
template <class Predicate>
void spawn_finding(const Map& map, Predicate bad, const char* code, std::string_view what,
                   std::vector<MapFinding>& out) {
    std::size_t count = 0;
    std::string examples;
    for (std::size_t i = 0; i < map.spawn_points.size(); ++i) {
        const glm::vec3 p = map.spawn_points[i].origin;
        if (!bad(p)) {
            continue;
        }
        if (++count <= kExamples) {
            examples += (examples.empty() ? "" : ", ") + std::string("#") + std::to_string(i) +
                        " at " + format_point(p);
        }
    }
    if (count > 0) {
        out.push_back({FindingSeverity::warning, code,
                       std::to_string(count) + " of " + std::to_string(map.spawn_points.size()) +
                           " spawn points " + std::string(what) + " (" + examples +
                           (count > kExamples ? ", ..." : "") + ")"});
    }
}

float largest_coordinate(glm::vec3 p) {
    const glm::vec3 m = glm::abs(p);
    return std::max({m.x, m.y, m.z});
}

float largest_coordinate(const visibility::Aabb& box) {
    return box.is_empty() ? 0.0f
                          : std::max(largest_coordinate(box.min), largest_coordinate(box.max));
}

/// Largest coordinate of anything in the map (brushes that were left out aside).
float largest_coordinate(const Map& map) {
    float largest = largest_coordinate(map.bounds);
    for (const SpawnPoint& s : map.spawn_points) {
        largest = std::max(largest, largest_coordinate(s.origin));
    }
    for (const Hazard& h : map.hazards) {
        largest = std::max(largest, largest_coordinate(h.bounds));
    }
    return largest;
}

} // namespace

const char* to_string(FindingSeverity severity) noexcept {
    return severity == FindingSeverity::unusable ? "unusable" : "warning";
}

std::vector<MapFinding> check_map(const Map& map) {
    std::vector<MapFinding> out;
    if (const std::string where = first_non_finite(map); !where.empty()) {
        // Nothing below is meaningful on NaN or infinite coordinates.
        out.push_back({FindingSeverity::unusable, "non_finite_geometry",
                       "non-finite coordinates (NaN or infinite) in " + where +
                           ": culling and movement on it are undefined"});
        return out;
    }
    const visibility::Aabb world{map.bounds.min - glm::vec3(1.0f),
                                 map.bounds.max + glm::vec3(1.0f, 1.0f, kSpawnHeadroom)};
    const auto outside = [&](glm::vec3 p) { return !world.contains(p); };
    const auto solid = [&](glm::vec3 p) { return in_solid(map, p); };
    const auto hazard = [&](glm::vec3 p) { return in_hazard(map, p); };
    if (map.spawn_points.empty()) {
        out.push_back({FindingSeverity::unusable, "no_spawn_points",
                       "no spawn points: there is nowhere to put a player"});
    } else if (std::all_of(map.spawn_points.begin(), map.spawn_points.end(),
                           [&](const SpawnPoint& s) {
                               return outside(s.origin) || solid(s.origin) || hazard(s.origin);
                           })) {
        out.push_back({FindingSeverity::unusable, "no_usable_spawn_point",
                       "every spawn point is outside the world, inside solid or inside a "
                       "hazard: no player can spawn"});
    }
    spawn_finding(
        map, outside, "spawn_outside_world",
        "are outside the world (the bounds of its collision brushes, with headroom above)", out);
    spawn_finding(map, solid, "spawn_in_solid",
                  "are inside solid brushes (more than " +
                      std::to_string(static_cast<int>(kSpawnInSolidDepth)) + " unit deep)",
                  out);
    spawn_finding(map, hazard, "spawn_in_hazard", "are inside a hazard (players die at once)", out);
    const MapStats& s = map.stats;
    if (map.occluders.empty()) {
        out.push_back({FindingSeverity::warning, "no_occluders",
                       "no occluders (" + std::to_string(s.opaque_candidates) +
                           " opaque solid brushes, none with usable geometry): nothing blocks "
                           "sight, so occlusion culling hides nothing"});
    }
    if (map.collision_brushes.empty()) {
        out.push_back({FindingSeverity::warning, "no_collision_brushes",
                       "no collision brushes: nothing to stand on, players fall forever"});
    }
    if (const float largest = largest_coordinate(map); largest > kMaxWorldCoordinate) {
        out.push_back({FindingSeverity::warning, "beyond_world_limit",
                       "the map reaches " + std::to_string(static_cast<long long>(largest)) +
                           " units from the origin, beyond Quake 3's world limit of " +
                           std::to_string(static_cast<long long>(kMaxWorldCoordinate)) +
                           ": is the map scaled absurdly?"});
    }
    if (s.degenerate.total() > 0) {
        out.push_back({FindingSeverity::warning, "degenerate_brushes",
                       std::to_string(s.degenerate.total()) + " of " +
                           std::to_string(s.collision_candidates) +
                           " solid or clip brushes left out for unusable geometry (too many "
                           "planes " +
                           std::to_string(s.degenerate.too_many_planes) + ", too few planes " +
                           std::to_string(s.degenerate.too_few_planes) + ", non-finite " +
                           std::to_string(s.degenerate.non_finite_plane) + ", unbounded " +
                           std::to_string(s.degenerate.unbounded) + ", empty " +
                           std::to_string(s.degenerate.empty) + ")"});
    }
    if (!map.shader_script_problems.empty()) {
        out.push_back({FindingSeverity::warning, "shader_scripts_unread",
                       std::to_string(map.shader_script_problems.size()) +
                           " of the game's shader scripts or archives could not be read (first: " +
                           map.shader_script_problems.front().message() +
                           "): see-through shaders are told by their names instead, which "
                           "culls less"});
    }
    return out;
}

bool any_unusable(const std::vector<MapFinding>& findings) {
    return std::any_of(findings.begin(), findings.end(),
                       [](const MapFinding& f) { return f.severity == FindingSeverity::unusable; });
}

} // namespace dsoc::maps
