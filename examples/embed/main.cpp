// dsoc-embed-example: the smallest game server loop that embeds dsoc's interest
// management. docs/integration.md walks through this file section by section.
//
//   dsoc-embed-example [MAP] [TICKS]
//
// MAP: a text map (default: two_halls.map beside this file), a .bsp, or an
// OpenArena map name such as oa_dm4. TICKS: how many ticks to run (default 300, at
// 30 Hz: 10 s of game time, run as fast as the machine goes). Prints every client's
// enter/leave events, then one summary line per client. Exit status 0 on success,
// 1 on bad arguments or a map that cannot be loaded.

#include <dsoc/maps/map_source.hpp>
#include <dsoc/maps/pvs_region_visibility.hpp>
#include <dsoc/visibility/interest_manager.hpp>
#include <dsoc/visibility/occluder_region_visibility.hpp>
#include <dsoc/visibility/version.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace vis = dsoc::visibility;

namespace {

constexpr int kTickRate = 30;        // [Hz]
constexpr float kRoundTripMs = 100;  // the worst round trip we serve [ms]
constexpr float kInterpDelayMs = 50; // the clients' interpolation delay [ms]

// Our game's player box around its origin (Quake 3 sizes). [world units]
constexpr glm::vec3 kPlayerMins{-15.0f, -15.0f, -24.0f};
constexpr glm::vec3 kPlayerMaxs{15.0f, 15.0f, 32.0f};
constexpr float kViewHeight = 26.0f; // eye above the origin [world units]

/// One entity of our game. dsoc does not own it: the game tells dsoc where it is.
struct Walker {
    vis::EntityId id = 0;
    glm::vec3 origin{0.0f};
    glm::vec3 velocity{0.0f}; // [world units / s]
    float speed = 0.0f;       // [world units / s]; below the declared limit
    std::size_t next_waypoint = 0;
};

vis::Aabb box_of(const Walker& w) {
    return {w.origin + kPlayerMins, w.origin + kPlayerMaxs};
}

/// Our game's "AI": walk the spawn points in order, at constant speed.
void walk(Walker& w, const std::vector<dsoc::maps::SpawnPoint>& path, float seconds) {
    const glm::vec3 start = w.origin;
    float budget = w.speed * seconds;
    for (std::size_t step = 0; step < path.size() && budget > 0.0f; ++step) {
        const glm::vec3 to_target = path[w.next_waypoint].origin - w.origin;
        const float distance = glm::length(to_target);
        if (distance > budget) {
            w.origin += to_target * (budget / distance);
            break;
        }
        w.origin = path[w.next_waypoint].origin;
        budget -= distance;
        w.next_waypoint = (w.next_waypoint + 1) % path.size();
    }
    w.velocity = (w.origin - start) / seconds;
}

struct Tally {
    std::uint64_t enters = 0;
    std::uint64_t leaves = 0;
    std::uint64_t updates = 0; // entity updates due (each at its update_interval)
};

void print_ids(const char* label, const std::vector<vis::EntityId>& ids) {
    if (ids.empty()) {
        return;
    }
    std::printf(" %s", label);
    for (const vis::EntityId id : ids) {
        std::printf(" %u", id);
    }
}

} // namespace

int main(int argc, char** argv) {
    const std::string map_name = argc > 1 ? argv[1] : EMBED_DEFAULT_MAP;
    const long ticks = argc > 2 ? std::strtol(argv[2], nullptr, 10) : 300;
    if (argc > 3 || ticks < 1 || ticks > 1000000) {
        std::fprintf(stderr, "usage: dsoc-embed-example [MAP] [TICKS: 1..1000000]\n");
        return 1;
    }
    std::printf("dsoc %s\n", dsoc::version());

    // 1. Load the map: the static world whose solid brushes hide entities.
    auto loaded = dsoc::maps::load_map(map_name, dsoc::maps::MapSearch::from_environment());
    if (!loaded) {
        std::fprintf(stderr, "dsoc-embed-example: %s\n", loaded.error().message().c_str());
        return 1;
    }
    const dsoc::maps::Map& map = loaded.value();
    if (map.spawn_points.size() < 2) {
        std::fprintf(stderr, "dsoc-embed-example: %s: needs at least 2 spawn points\n",
                     map_name.c_str());
        return 1;
    }
    std::printf("map %s: %zu occluders, %zu spawn points\n", map.name.c_str(), map.occluders.size(),
                map.spawn_points.size());

    // 2. Settings, checked before use: a bad field is named, not silently clamped.
    vis::DSOCConfig config;
    config.tick_rate = kTickRate;
    config.strategy = vis::TbvStrategy::adaptive;
    if (const auto problems = vis::validate(config); !problems.empty()) {
        for (const auto& problem : problems) {
            std::fprintf(stderr, "dsoc-embed-example: config: %s\n", problem.c_str());
        }
        return 1;
    }

    // 3. The culler, built once from the map and shared read-only by every client's
    //    culler; the map's PVS (Quake 3 maps) goes first when there is one.
    auto scene = vis::OccluderScene::build(map.occluders);
    auto make_culler = dsoc::maps::with_pvs_stage(map.pvs, vis::occluder_region_visibility(scene));
    vis::InterestManager interest(config, map.bounds.expanded(64.0f), make_culler);

    // 4. What every entity promises about its motion. dsoc's guarantee holds only
    //    for entities that keep this promise (our walkers never exceed 300 u/s).
    vis::EntityDesc walker_desc;
    walker_desc.half_extents = (kPlayerMaxs - kPlayerMins) * 0.5f;
    walker_desc.motion.horizontal_speed = 320.0f;
    walker_desc.motion.up_speed = 320.0f;
    walker_desc.motion.down_speed = 800.0f;
    walker_desc.motion.gravity = 800.0f;

    std::vector<Walker> walkers;
    const std::size_t walker_count = std::min<std::size_t>(8, map.spawn_points.size());
    for (std::size_t i = 0; i < walker_count; ++i) {
        Walker w;
        w.id = static_cast<vis::EntityId>(100 + i); // our game's ids; dsoc keeps them
        w.origin = map.spawn_points[i].origin;
        w.speed = 160.0f + 20.0f * static_cast<float>(i);
        w.next_waypoint = (i + 1) % map.spawn_points.size();
        interest.add_entity(w.id, walker_desc, box_of(w));
        walkers.push_back(w);
    }

    // 5. Clients: each views from the entity it controls, and must be covered for
    //    every position it can reach before our updates reach its screen.
    vis::ClientDesc player;
    // The eye relative to the centre of the viewer's box.
    player.eye_offset = glm::vec3(0.0f, 0.0f, kViewHeight) - (kPlayerMins + kPlayerMaxs) * 0.5f;
    player.lookahead_ticks =
        static_cast<int>(std::ceil((kRoundTripMs + kInterpDelayMs) * kTickRate / 1000.0f));
    player.eye_motion = walker_desc.motion;
    const auto connect = [&](vis::ClientId client, std::size_t walker) {
        vis::ClientDesc desc = player;
        desc.viewer = walkers[walker % walkers.size()].id;
        interest.add_client(client, desc);
        std::printf("client %u connects, views from entity %u\n", client, desc.viewer);
    };
    connect(1, 0);
    connect(2, 4);
    std::map<vis::ClientId, Tally> tallies;

    // 6. The game's tick loop.
    for (long tick = 1; tick <= ticks; ++tick) {
        // Our simulation moves the world ...
        for (Walker& w : walkers) {
            walk(w, map.spawn_points, 1.0f / kTickRate);
        }
        // ... players come and go, entities die ...
        if (tick == 90) {
            connect(3, 2);
        }
        if (tick == 240 && interest.remove_client(3)) {
            std::printf("tick %ld client 3 disconnects\n", tick);
        }
        if (tick == 180 && walkers.size() > 7 && interest.remove_entity(walkers[7].id)) {
            std::printf("tick %ld entity %u removed\n", tick, walkers[7].id);
            walkers.pop_back();
        }
        // ... then dsoc is told where every entity is now, and decides.
        for (const Walker& w : walkers) {
            interest.set_entity_box(w.id, box_of(w), w.velocity);
        }
        interest.update(static_cast<std::uint64_t>(tick));

        // 7. Read the decisions: send "enter" with full state, updates for the
        //    replicated set (each at its update_interval), "leave" to forget.
        for (std::size_t i = 0; i < interest.client_count(); ++i) {
            const vis::ClientId client = interest.client_at(i);
            const vis::ClientDecisions& d = *interest.decisions(client);
            tallies[client].enters += d.enter.size();
            tallies[client].leaves += d.leave.size();
            for (const vis::Replicated& r : d.replicated) {
                // Far entities may be sent less often (and, at your choice, coarser).
                if (tick % r.update_interval == 0) {
                    ++tallies[client].updates;
                }
            }
            if (d.enter.empty() && d.leave.empty()) {
                continue;
            }
            std::printf("tick %ld client %u:", tick, client);
            print_ids("enter", d.enter);
            print_ids("leave", d.leave);
            std::printf("\n");
        }
    }

    for (std::size_t i = 0; i < interest.client_count(); ++i) {
        const vis::ClientId client = interest.client_at(i);
        const vis::ClientStats& stats = *interest.stats(client);
        std::printf("summary client %u: %llu enter, %llu leave, %zu of %zu replicated at the "
                    "end, %llu teleports, %llu TBVs created, %llu updates\n",
                    client, static_cast<unsigned long long>(tallies[client].enters),
                    static_cast<unsigned long long>(tallies[client].leaves),
                    interest.decisions(client)->replicated.size(), walkers.size(),
                    static_cast<unsigned long long>(stats.teleports),
                    static_cast<unsigned long long>(stats.tbvs_created),
                    static_cast<unsigned long long>(tallies[client].updates));
    }
    return 0;
}
