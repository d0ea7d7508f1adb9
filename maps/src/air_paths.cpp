#include "dsoc/maps/air_paths.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace dsoc::maps {

glm::ivec3 AirGrid::voxel_of(glm::vec3 p) const {
    const glm::vec3 v = glm::floor((p - origin) / voxel);
    return {static_cast<int>(v.x), static_cast<int>(v.y), static_cast<int>(v.z)};
}

glm::vec3 AirGrid::centre_of(glm::ivec3 v) const {
    return origin + (glm::vec3(v) + 0.5f) * voxel;
}

namespace {

/// Whether the closed box [lo, hi] may meet the brush: every plane has a corner of the
/// box on its inner side. Never false when they meet; true for some boxes that only
/// come near an edge the brush's bevels do not cut (so a voxel may be solid for
/// nothing, never open with a wall in it).
bool box_meets_brush(glm::vec3 lo, glm::vec3 hi, const CollisionBrush& brush) {
    for (const visibility::Plane& p : brush.planes) {
        const glm::vec3 nearest{p.normal.x >= 0.0f ? lo.x : hi.x, p.normal.y >= 0.0f ? lo.y : hi.y,
                                p.normal.z >= 0.0f ? lo.z : hi.z};
        if (p.signed_distance(nearest) > 0.0f) {
            return false;
        }
    }
    return true;
}

bool stops_sound(const CollisionBrush& brush) {
    return (brush.contents & contents_solid) != 0 && (brush.contents & contents_translucent) == 0;
}

/// One of the 26 steps: its offset, its length in voxels, and the voxels it grazes (the
/// face and edge neighbours between its ends), which must be open too.
struct Step {
    glm::ivec3 offset;
    float length;
    std::vector<glm::ivec3> grazed;
};

std::vector<Step> make_steps() {
    std::vector<Step> steps;
    for (int z = -1; z <= 1; ++z) {
        for (int y = -1; y <= 1; ++y) {
            for (int x = -1; x <= 1; ++x) {
                const glm::ivec3 o{x, y, z};
                if (o == glm::ivec3(0)) {
                    continue;
                }
                Step s{o, std::sqrt(static_cast<float>(x * x + y * y + z * z)), {}};
                // Every non-empty proper subset of the step's components.
                for (int mask = 1; mask < 7; ++mask) {
                    const glm::ivec3 sub{(mask & 1) != 0 ? x : 0, (mask & 2) != 0 ? y : 0,
                                         (mask & 4) != 0 ? z : 0};
                    if (sub != glm::ivec3(0) && sub != o &&
                        std::find(s.grazed.begin(), s.grazed.end(), sub) == s.grazed.end()) {
                        s.grazed.push_back(sub);
                    }
                }
                steps.push_back(std::move(s));
            }
        }
    }
    return steps;
}

/// Whether the segment p-q meets one of the walls (clipped by each brush's planes).
bool segment_meets_wall(const std::vector<CollisionBrush>& walls, glm::vec3 p, glm::vec3 q) {
    const glm::vec3 lo = glm::min(p, q);
    const glm::vec3 hi = glm::max(p, q);
    for (const CollisionBrush& wall : walls) {
        if (glm::any(glm::lessThan(hi, wall.bounds.min)) ||
            glm::any(glm::greaterThan(lo, wall.bounds.max))) {
            continue;
        }
        float enter = 0.0f;
        float leave = 1.0f;
        for (const visibility::Plane& plane : wall.planes) {
            const float dp = plane.signed_distance(p);
            const float dq = plane.signed_distance(q);
            if (dp > 0.0f && dq > 0.0f) {
                leave = -1.0f; // wholly outside this plane
                break;
            }
            if (dp > 0.0f) {
                enter = std::max(enter, dp / (dp - dq));
            } else if (dq > 0.0f) {
                leave = std::min(leave, dp / (dp - dq));
            }
        }
        if (enter <= leave) {
            return true;
        }
    }
    return false;
}

/// The open voxel where a path from `p` starts (or ends), with the distance from `p` to
/// its centre: `p`'s own voxel when open, or else the nearest open voxel within two of
/// it whose centre a straight line from `p` reaches without meeting a wall; none:
/// {-1, 0}.
std::pair<std::ptrdiff_t, float> open_voxel_near(const AirGrid& grid, glm::vec3 p) {
    const glm::ivec3 home = grid.voxel_of(p);
    if (grid.inside(home) && grid.solid[grid.index(home)] == 0) {
        return {static_cast<std::ptrdiff_t>(grid.index(home)),
                glm::length(grid.centre_of(home) - p)};
    }
    std::vector<std::pair<float, glm::ivec3>> candidates;
    for (int z = -2; z <= 2; ++z) {
        for (int y = -2; y <= 2; ++y) {
            for (int x = -2; x <= 2; ++x) {
                const glm::ivec3 v = home + glm::ivec3(x, y, z);
                if (grid.inside(v) && grid.solid[grid.index(v)] == 0) {
                    candidates.emplace_back(glm::length(grid.centre_of(v) - p), v);
                }
            }
        }
    }
    std::sort(candidates.begin(), candidates.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [distance, v] : candidates) {
        if (!segment_meets_wall(grid.walls, p, grid.centre_of(v))) {
            return {static_cast<std::ptrdiff_t>(grid.index(v)), distance};
        }
    }
    return {-1, 0.0f};
}

} // namespace

AirGrid air_grid(const Map& map, float voxel) {
    if (!(voxel > 0.0f) || !std::isfinite(voxel)) {
        throw std::invalid_argument("air grid of " + map.name +
                                    ": the voxel must be positive, not " + std::to_string(voxel));
    }
    AirGrid grid;
    grid.voxel = voxel;
    // A voxel of air all round, so that a path may pass outside the outermost brushes,
    // and round that a layer of solid voxels, so that no step leaves the grid.
    grid.origin = map.bounds.min - 2.0f * voxel;
    const glm::vec3 extent = map.bounds.max + 2.0f * voxel - grid.origin;
    const glm::vec3 counts = glm::ceil(glm::max(extent, glm::vec3(0.0f)) / voxel);
    const double total = static_cast<double>(counts.x) * counts.y * counts.z;
    if (!(total <= static_cast<double>(kMaxAirVoxels))) {
        throw std::invalid_argument("air grid of " + map.name + ": " + std::to_string(total) +
                                    " voxels of " + std::to_string(voxel) + " units, more than " +
                                    std::to_string(kMaxAirVoxels));
    }
    grid.size = {static_cast<int>(counts.x), static_cast<int>(counts.y),
                 static_cast<int>(counts.z)};
    grid.solid.assign(static_cast<std::size_t>(total), 0);
    for (int z = 0; z < grid.size.z; ++z) {
        for (int y = 0; y < grid.size.y; ++y) {
            for (int x = 0; x < grid.size.x; ++x) {
                const bool outermost = x == 0 || y == 0 || z == 0 || x == grid.size.x - 1 ||
                                       y == grid.size.y - 1 || z == grid.size.z - 1;
                grid.solid[grid.index({x, y, z})] = outermost ? 1 : 0;
            }
        }
    }
    for (const CollisionBrush& brush : map.collision_brushes) {
        if (!stops_sound(brush)) {
            continue;
        }
        grid.walls.push_back(brush);
        const glm::ivec3 lo = glm::max(grid.voxel_of(brush.bounds.min), glm::ivec3(0));
        const glm::ivec3 hi = glm::min(grid.voxel_of(brush.bounds.max), grid.size - 1);
        for (int z = lo.z; z <= hi.z; ++z) {
            for (int y = lo.y; y <= hi.y; ++y) {
                for (int x = lo.x; x <= hi.x; ++x) {
                    const glm::ivec3 v{x, y, z};
                    const std::size_t i = grid.index(v);
                    if (grid.solid[i] == 0) {
                        const glm::vec3 corner = grid.origin + glm::vec3(v) * voxel;
                        grid.solid[i] = box_meets_brush(corner, corner + voxel, brush) ? 1 : 0;
                    }
                }
            }
        }
    }
    return grid;
}

AirPathSearch::AirPathSearch(const AirGrid& grid) : grid_(&grid) {
    for (int z = 0; z < grid.size.z; ++z) {
        for (int y = 0; y < grid.size.y; ++y) {
            for (int x = 0; x < grid.size.x; ++x) {
                const bool outermost = x == 0 || y == 0 || z == 0 || x == grid.size.x - 1 ||
                                       y == grid.size.y - 1 || z == grid.size.z - 1;
                if (outermost && grid.solid[grid.index({x, y, z})] == 0) {
                    throw std::invalid_argument("air path search: the grid's outermost layer "
                                                "must be solid");
                }
            }
        }
    }
    const auto nx = static_cast<std::ptrdiff_t>(grid.size.x);
    const auto nxy = nx * static_cast<std::ptrdiff_t>(grid.size.y);
    const auto linear = [&](glm::ivec3 o) { return o.x + o.y * nx + o.z * nxy; };
    for (const Step& s : make_steps()) {
        LinearStep step;
        step.offset = linear(s.offset);
        step.length = s.length;
        for (const glm::ivec3 g : s.grazed) {
            step.grazed[step.grazed_count++] = linear(g);
        }
        steps_.push_back(step);
    }
}

std::vector<float> AirPathSearch::lengths(glm::vec3 from, std::span<const glm::vec3> to,
                                          float max_length) {
    const AirGrid& grid = *grid_;
    std::vector<float> lengths(to.size(), kNoAirPath);
    const auto [start, start_detour] = open_voxel_near(grid, from);
    if (start < 0) {
        return lengths;
    }
    if (distance_.size() != grid.solid.size()) {
        distance_.assign(grid.solid.size(), kNoAirPath);
        settled_.assign(grid.solid.size(), 0);
    }
    for (const std::size_t i : touched_) { // what the last search reached, and no more
        distance_[i] = kNoAirPath;
        settled_[i] = 0;
    }
    touched_.clear();
    // Dijkstra over voxel centres, in voxels, up to the bound, with buckets one voxel
    // wide (Dial's): every step is at least a voxel long, so a voxel taken from the
    // lowest bucket can no longer be reached shorter, and a step lands one or two
    // buckets on (at most sqrt(3) long): three buckets in turn. The grid's outermost
    // layer is solid (air_grid()), so no step leaves it.
    const float bound = max_length / grid.voxel;
    const auto first = static_cast<std::size_t>(start);
    distance_[first] = start_detour / grid.voxel;
    touched_.push_back(first);
    std::array<std::vector<std::size_t>, 3>& buckets = buckets_;
    for (auto& b : buckets) {
        b.clear();
    }
    auto bucket_of = [](float d) { return static_cast<std::size_t>(d); };
    buckets[bucket_of(distance_[first]) % 3].push_back(first);
    std::size_t pending = 1;
    const std::uint8_t* solid = grid.solid.data();
    for (std::size_t k = bucket_of(distance_[first]); pending > 0; ++k) {
        std::vector<std::size_t>& now = buckets[k % 3];
        while (!now.empty()) {
            const std::size_t i = now.back();
            now.pop_back();
            --pending;
            const float d = distance_[i];
            if (bucket_of(d) != k || settled_[i] != 0) {
                continue; // reached shorter since, or taken already
            }
            settled_[i] = 1;
            const auto here = static_cast<std::ptrdiff_t>(i);
            for (const LinearStep& step : steps_) {
                const std::ptrdiff_t w = here + step.offset;
                if (solid[w] != 0) {
                    continue;
                }
                bool grazes_solid = false;
                for (int g = 0; g < step.grazed_count; ++g) {
                    grazes_solid = grazes_solid || solid[here + step.grazed[g]] != 0;
                }
                const float dw = d + step.length;
                const auto j = static_cast<std::size_t>(w);
                if (!grazes_solid && dw < distance_[j] && dw <= bound) {
                    if (distance_[j] == kNoAirPath) {
                        touched_.push_back(j);
                    }
                    distance_[j] = dw;
                    buckets[bucket_of(dw) % 3].push_back(j);
                    ++pending;
                }
            }
        }
    }
    for (std::size_t k = 0; k < to.size(); ++k) {
        const auto [end, end_detour] = open_voxel_near(grid, to[k]);
        if (end < 0 || distance_[static_cast<std::size_t>(end)] == kNoAirPath) {
            continue;
        }
        const float length = distance_[static_cast<std::size_t>(end)] * grid.voxel + end_detour;
        if (length <= max_length) {
            lengths[k] = length;
        }
    }
    return lengths;
}

} // namespace dsoc::maps
