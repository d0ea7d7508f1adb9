#include "dsoc/maps/generators.hpp"

#include "split_mix.hpp"

#include <glm/vec2.hpp>

#include <algorithm>
#include <array>
#include <numeric>

namespace dsoc::maps {
namespace {

using visibility::Aabb;
constexpr float kSpawnHeight = 25.0f;

void add_box(MapSpec& spec, BrushKind kind, glm::vec3 min, glm::vec3 max) {
    spec.brushes.push_back(BrushSpec::box(kind, {min, max}));
}

/// Walls around [min, max] in xy, from z0 to z1, `thickness` thick, outside the region.
void add_enclosure(MapSpec& spec, glm::vec2 min, glm::vec2 max, float z0, float z1,
                   float thickness) {
    const float t = thickness;
    add_box(spec, BrushKind::solid, {min.x - t, min.y - t, z0}, {max.x + t, min.y, z1});
    add_box(spec, BrushKind::solid, {min.x - t, max.y, z0}, {max.x + t, max.y + t, z1});
    add_box(spec, BrushKind::solid, {min.x - t, min.y, z0}, {min.x, max.y, z1});
    add_box(spec, BrushKind::solid, {max.x, min.y, z0}, {max.x + t, max.y, z1});
}

} // namespace

std::vector<std::string> validate(const CityParams& p) {
    std::vector<std::string> problems;
    if (p.blocks_x < 1 || p.blocks_x > 256 || p.blocks_y < 1 || p.blocks_y > 256) {
        problems.emplace_back("blocks_x and blocks_y must be in 1..256");
    }
    if (!(p.block_size >= 32.0f)) {
        problems.emplace_back("block_size must be >= 32");
    }
    if (!(p.street_width >= 64.0f)) {
        problems.emplace_back("street_width must be >= 64");
    }
    if (!(p.min_height > 0.0f) || !(p.max_height >= p.min_height)) {
        problems.emplace_back("need 0 < min_height <= max_height");
    }
    if (!(p.glass_fraction >= 0.0f && p.glass_fraction <= 1.0f)) {
        problems.emplace_back("glass_fraction must be in 0..1");
    }
    return problems;
}

std::vector<std::string> validate(const RoomsParams& p) {
    std::vector<std::string> problems;
    if (p.rooms_x < 1 || p.rooms_x > 128 || p.rooms_y < 1 || p.rooms_y > 128) {
        problems.emplace_back("rooms_x and rooms_y must be in 1..128");
    }
    if (!(p.room_size >= 160.0f)) {
        problems.emplace_back("room_size must be >= 160");
    }
    if (!(p.corridor_length >= 32.0f)) {
        problems.emplace_back("corridor_length must be >= 32");
    }
    if (!(p.corridor_width >= 48.0f && p.corridor_width <= p.room_size - 32.0f)) {
        problems.emplace_back("corridor_width must be in 48..room_size - 32");
    }
    if (!(p.height >= 96.0f)) {
        problems.emplace_back("height must be >= 96");
    }
    if (!(p.wall_thickness >= 1.0f)) {
        problems.emplace_back("wall_thickness must be >= 1");
    }
    if (!(p.extra_door_fraction >= 0.0f && p.extra_door_fraction <= 1.0f)) {
        problems.emplace_back("extra_door_fraction must be in 0..1");
    }
    return problems;
}

MapSpec generate_city(const CityParams& p) {
    detail::SplitMix random(p.seed);
    MapSpec spec;
    spec.name = "city_" + std::to_string(p.blocks_x) + "x" + std::to_string(p.blocks_y) + "_s" +
                std::to_string(p.seed);
    const float pitch = p.block_size + p.street_width;
    // Streets run around every block: the world is [0, extent] with a street first.
    const glm::vec2 extent(static_cast<float>(p.blocks_x) * pitch + p.street_width,
                           static_cast<float>(p.blocks_y) * pitch + p.street_width);
    const float wall_height = p.max_height + 256.0f;
    add_box(spec, BrushKind::solid, {-32.0f, -32.0f, -32.0f},
            {extent.x + 32.0f, extent.y + 32.0f, 0.0f});
    add_enclosure(spec, {0.0f, 0.0f}, extent, -32.0f, wall_height, 32.0f);
    for (int bx = 0; bx < p.blocks_x; ++bx) {
        for (int by = 0; by < p.blocks_y; ++by) {
            const glm::vec2 min(p.street_width + static_cast<float>(bx) * pitch,
                                p.street_width + static_cast<float>(by) * pitch);
            const float height = random.range(p.min_height, p.max_height);
            const BrushKind kind =
                random.unit() < p.glass_fraction ? BrushKind::glass : BrushKind::solid;
            add_box(spec, kind, {min.x, min.y, 0.0f},
                    {min.x + p.block_size, min.y + p.block_size, height});
            // A kerb (16 high: within the step-up height) on the street beside the block.
            const float kerb_x = min.x + random.range(0.0f, p.block_size - 64.0f);
            add_box(spec, BrushKind::solid, {kerb_x, min.y - 48.0f, 0.0f},
                    {kerb_x + 64.0f, min.y - 16.0f, 16.0f});
        }
    }
    for (int sx = 0; sx <= p.blocks_x; ++sx) {
        for (int sy = 0; sy <= p.blocks_y; ++sy) {
            SpawnPoint spawn;
            spawn.origin = {static_cast<float>(sx) * pitch + p.street_width * 0.5f,
                            static_cast<float>(sy) * pitch + p.street_width * 0.5f, kSpawnHeight};
            spawn.yaw_degrees = random.range(0.0f, 360.0f);
            spawn.classname = "info_player_deathmatch";
            spec.spawn_points.push_back(spawn);
        }
    }
    return spec;
}

MapSpec generate_rooms(const RoomsParams& p) {
    detail::SplitMix random(p.seed);
    MapSpec spec;
    spec.name = "rooms_" + std::to_string(p.rooms_x) + "x" + std::to_string(p.rooms_y) + "_s" +
                std::to_string(p.seed);
    const float pitch = p.room_size + p.corridor_length;
    const float t = p.wall_thickness;
    const float h = p.height;
    const int count = p.rooms_x * p.rooms_y;
    auto room_min = [&](int index) {
        return glm::vec2(static_cast<float>(index % p.rooms_x) * pitch,
                         static_cast<float>(index / p.rooms_x) * pitch);
    };

    // Doors: edges of the room grid. A random spanning tree (randomized Kruskal) keeps
    // every room reachable; extra doors add loops.
    struct Edge {
        int a, b;
    };
    std::vector<Edge> edges;
    for (int i = 0; i < count; ++i) {
        if (i % p.rooms_x + 1 < p.rooms_x) {
            edges.push_back({i, i + 1});
        }
        if (i / p.rooms_x + 1 < p.rooms_y) {
            edges.push_back({i, i + p.rooms_x});
        }
    }
    for (std::size_t i = edges.size(); i > 1; --i) {
        std::swap(edges[i - 1], edges[random.below(static_cast<std::uint32_t>(i))]);
    }
    std::vector<int> parent(static_cast<std::size_t>(count));
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](int x) {
        while (parent[static_cast<std::size_t>(x)] != x) {
            x = parent[static_cast<std::size_t>(x)] =
                parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
        }
        return x;
    };
    // door[room][side]: side 0 = -x, 1 = +x, 2 = -y, 3 = +y.
    std::vector<std::array<bool, 4>> door(static_cast<std::size_t>(count),
                                          {false, false, false, false});
    for (const Edge& edge : edges) {
        const int ra = find(edge.a);
        const int rb = find(edge.b);
        const bool joins_trees = ra != rb;
        if (!joins_trees && random.unit() >= p.extra_door_fraction) {
            continue;
        }
        parent[static_cast<std::size_t>(ra)] = rb;
        const bool along_x = edge.b == edge.a + 1;
        door[static_cast<std::size_t>(edge.a)][along_x ? 1 : 3] = true;
        door[static_cast<std::size_t>(edge.b)][along_x ? 0 : 2] = true;
        // Corridor walls (outside both rooms' walls) and nothing else: floor and
        // ceiling slabs cover everything.
        const glm::vec2 a = room_min(edge.a);
        const float half = p.corridor_width * 0.5f;
        if (along_x) {
            const float cy = a.y + p.room_size * 0.5f;
            const float x0 = a.x + p.room_size + t;
            const float x1 = a.x + pitch - t;
            add_box(spec, BrushKind::solid, {x0, cy - half - t, 0.0f}, {x1, cy - half, h});
            add_box(spec, BrushKind::solid, {x0, cy + half, 0.0f}, {x1, cy + half + t, h});
        } else {
            const float cx = a.x + p.room_size * 0.5f;
            const float y0 = a.y + p.room_size + t;
            const float y1 = a.y + pitch - t;
            add_box(spec, BrushKind::solid, {cx - half - t, y0, 0.0f}, {cx - half, y1, h});
            add_box(spec, BrushKind::solid, {cx + half, y0, 0.0f}, {cx + half + t, y1, h});
        }
    }

    const glm::vec2 extent(static_cast<float>(p.rooms_x) * pitch,
                           static_cast<float>(p.rooms_y) * pitch);
    add_box(spec, BrushKind::solid, {-t - 64.0f, -t - 64.0f, -t},
            {extent.x + 64.0f, extent.y + 64.0f, 0.0f});
    add_box(spec, BrushKind::caulk, {-t - 64.0f, -t - 64.0f, h},
            {extent.x + 64.0f, extent.y + 64.0f, h + t});
    add_enclosure(spec, {-64.0f, -64.0f}, {extent.x + 64.0f - t, extent.y + 64.0f - t}, 0.0f, h, t);

    const float half_door = p.corridor_width * 0.5f;
    for (int i = 0; i < count; ++i) {
        const glm::vec2 m = room_min(i);
        const float s = p.room_size;
        const auto& doors = door[static_cast<std::size_t>(i)];
        // Wall along y at x = wx (thickness outward by `dir`), with an optional gap.
        auto wall_y = [&](float x0, float x1, bool gap) {
            const float c = m.y + s * 0.5f;
            if (gap) {
                add_box(spec, BrushKind::solid, {x0, m.y - t, 0.0f}, {x1, c - half_door, h});
                add_box(spec, BrushKind::solid, {x0, c + half_door, 0.0f}, {x1, m.y + s + t, h});
            } else {
                add_box(spec, BrushKind::solid, {x0, m.y - t, 0.0f}, {x1, m.y + s + t, h});
            }
        };
        auto wall_x = [&](float y0, float y1, bool gap) {
            const float c = m.x + s * 0.5f;
            if (gap) {
                add_box(spec, BrushKind::solid, {m.x, y0, 0.0f}, {c - half_door, y1, h});
                add_box(spec, BrushKind::solid, {c + half_door, y0, 0.0f}, {m.x + s, y1, h});
            } else {
                add_box(spec, BrushKind::solid, {m.x, y0, 0.0f}, {m.x + s, y1, h});
            }
        };
        wall_y(m.x - t, m.x, doors[0]);
        wall_y(m.x + s, m.x + s + t, doors[1]);
        wall_x(m.y - t, m.y, doors[2]);
        wall_x(m.y + s, m.y + s + t, doors[3]);
        // A step (within step-up height) and a crate (must be jumped or walked around),
        // kept away from the centre where the spawn point is.
        const float step_x = m.x + random.range(16.0f, s * 0.25f);
        add_box(spec, BrushKind::solid, {step_x, m.y + 16.0f, 0.0f},
                {step_x + 64.0f, m.y + 80.0f, 16.0f});
        const float crate_y = m.y + random.range(s * 0.6f, s - 80.0f);
        add_box(spec, BrushKind::solid, {m.x + s - 80.0f, crate_y, 0.0f},
                {m.x + s - 16.0f, crate_y + 64.0f, 64.0f});

        SpawnPoint spawn;
        spawn.origin = {m.x + s * 0.5f, m.y + s * 0.5f, kSpawnHeight};
        spawn.yaw_degrees = random.range(0.0f, 360.0f);
        spawn.classname = "info_player_deathmatch";
        spec.spawn_points.push_back(spawn);
    }
    return spec;
}

} // namespace dsoc::maps
