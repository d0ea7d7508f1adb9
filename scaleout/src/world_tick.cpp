#include "dsoc/scaleout/world_tick.hpp"

#include "dsoc/maps/bake_file.hpp"

#include "little_endian.hpp"

#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

namespace dsoc::scaleout {

namespace {

constexpr std::size_t kHeaderBytes = 56;
constexpr std::size_t kEntityBytes = 68;
constexpr std::size_t kRespawnBytes = 48;

enum EntityFlags : std::uint8_t {
    kOnGround = 1,
    kTeleported = 2,
    kFiring = 4,
    kRespawnPending = 8,
    kArrivalOnGround = 16,
    kKnownFlags = 31,
};

/// Positions and velocities beyond this are refused (no map is near it). [Units: world units]
constexpr float kMaxCoordinate = 1.0e6f;
/// A respawn countdown longer than this is refused. [Units: ticks]
constexpr std::int32_t kMaxRespawnTicks = 1'000'000;

class Writer {
public:
    explicit Writer(std::vector<std::byte>& out) : out_(out) {}
    template <typename T>
    void put(T value) {
        scaleout::put(out_, value);
    }
    void put(glm::vec3 v) {
        put(v.x);
        put(v.y);
        put(v.z);
    }

private:
    std::vector<std::byte>& out_;
};

/// Reads in order; the caller checks left() before each part.
class Reader {
public:
    explicit Reader(std::span<const std::byte> bytes) : bytes_(bytes) {}
    template <typename T>
    T get() {
        const T value = scaleout::get<T>(bytes_, at_);
        at_ += sizeof(T);
        return value;
    }
    glm::vec3 get_vec3() {
        const float x = get<float>();
        const float y = get<float>();
        const float z = get<float>();
        return {x, y, z};
    }
    [[nodiscard]] std::size_t at() const { return at_; }
    [[nodiscard]] std::size_t left() const { return bytes_.size() - at_; }

private:
    std::span<const std::byte> bytes_;
    std::size_t at_ = 0;
};

void put_move(Writer& w, const sim::MoveState& m) {
    w.put(m.position);
    w.put(m.velocity);
    w.put(m.ground_normal);
    w.put(m.climb_credit);
}

sim::MoveState get_move(Reader& r, bool on_ground) {
    sim::MoveState m;
    m.position = r.get_vec3();
    m.velocity = r.get_vec3();
    m.on_ground = on_ground;
    m.ground_normal = r.get_vec3();
    m.climb_credit = r.get<float>();
    return m;
}

bool finite_within(glm::vec3 v, float limit) {
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(v[a]) || std::fabs(v[a]) > limit) {
            return false;
        }
    }
    return true;
}

/// Why `m` cannot be a walker's state, or "".
std::string move_problem(const sim::MoveState& m) {
    if (!finite_within(m.position, kMaxCoordinate)) {
        return "position not finite or beyond 1e6 units";
    }
    if (!finite_within(m.velocity, kMaxCoordinate)) {
        return "velocity not finite or beyond 1e6 units/s";
    }
    if (!finite_within(m.ground_normal, 1.0001f)) {
        return "ground normal not finite or longer than 1";
    }
    if (!std::isfinite(m.climb_credit) || m.climb_credit < 0.0f || m.climb_credit > 1.0e3f) {
        return "climb credit not finite or outside 0..1000 units";
    }
    return {};
}

std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
    h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    return h;
}

std::uint64_t bits_of(float f) {
    return std::bit_cast<std::uint32_t>(f);
}

} // namespace

std::uint64_t world_key(const maps::Map& map, const interest::WorldSettings& settings) {
    std::uint64_t h = maps::bake_key_of_map(map);
    h = mix(h, map.collision_brushes.size());
    for (const auto& brush : map.collision_brushes) {
        h = mix(h, brush.planes.size());
        h = mix(h, brush.contents);
        for (const visibility::Plane& plane : brush.planes) {
            h = mix(h, bits_of(plane.normal.x) << 32 | bits_of(plane.normal.y));
            h = mix(h, bits_of(plane.normal.z) << 32 | bits_of(plane.distance));
        }
    }
    h = mix(h, map.spawn_points.size());
    for (const auto& spawn : map.spawn_points) {
        h = mix(h, bits_of(spawn.origin.x));
        h = mix(h, bits_of(spawn.origin.y));
        h = mix(h, bits_of(spawn.origin.z));
        h = mix(h, bits_of(spawn.yaw_degrees));
    }
    h = mix(h, map.hazards.size());
    for (const maps::Hazard& hazard : map.hazards) {
        for (int a = 0; a < 3; ++a) {
            h = mix(h, bits_of(hazard.bounds.min[a]) << 32 | bits_of(hazard.bounds.max[a]));
        }
    }
    h = mix(h, bits_of(settings.max_speed));
    h = mix(h, static_cast<std::uint64_t>(settings.teams));
    h = mix(h, static_cast<std::uint64_t>(settings.respawn_delay_ticks));
    const sim::SoundSettings& s = settings.sounds;
    h = mix(h, s.enabled ? 1 : 0);
    for (const float f : {s.footstep_range, s.footstep_seconds, s.run_speed_fraction, s.shot_range,
                          s.shot_seconds, s.bot_shots_per_second, settings.shots.range}) {
        h = mix(h, bits_of(f));
    }
    h = mix(h, static_cast<std::uint64_t>(settings.shots.damage));
    return h;
}

std::uint64_t monotonic_ns() {
    return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                          std::chrono::steady_clock::now().time_since_epoch())
                                          .count());
}

void encode_world_tick(const interest::GameWorld& world, std::uint64_t world_key,
                       std::uint64_t tick, std::vector<std::byte>& out, std::uint64_t published_ns,
                       std::uint64_t instance) {
    out.clear();
    out.reserve(kHeaderBytes + world.entities().size() * kEntityBytes);
    Writer w(out);
    w.put(kWorldTickMagic);
    w.put(kWorldTickVersion);
    w.put(std::uint16_t{0});
    w.put(world_key);
    w.put(instance);
    w.put(tick);
    w.put(world.frags());
    w.put(published_ns);
    w.put(world.next_id());
    w.put(static_cast<std::uint32_t>(world.entities().size()));
    for (const interest::Entity& e : world.entities()) {
        std::uint8_t flags = 0;
        flags |= e.move.on_ground ? kOnGround : 0;
        flags |= e.teleported ? kTeleported : 0;
        flags |= e.firing ? kFiring : 0;
        flags |= e.respawn ? kRespawnPending : 0;
        flags |= e.respawn && e.respawn->arrival.on_ground ? kArrivalOnGround : 0;
        w.put(e.id);
        w.put(static_cast<std::uint8_t>(e.kind));
        w.put(flags);
        w.put(static_cast<std::uint16_t>(e.team));
        w.put(static_cast<std::int32_t>(e.health));
        put_move(w, e.move);
        w.put(e.yaw_deg);
        w.put(e.pitch_deg);
        w.put(e.audible.footstep_left);
        w.put(e.audible.shot_left);
        if (e.respawn) {
            put_move(w, e.respawn->arrival);
            w.put(e.respawn->yaw_degrees);
            w.put(static_cast<std::int32_t>(e.respawn->ticks_left));
        }
    }
}

maps::Result<WorldTick> decode_world_tick(std::span<const std::byte> bytes,
                                          const std::string& source,
                                          std::optional<std::uint64_t> expected_key) {
    const auto fail = [&](const std::string& part, const std::string& what) {
        return maps::LoadError{source, part, what};
    };
    if (bytes.size() < kHeaderBytes) {
        return fail("header", std::to_string(bytes.size()) + " bytes, a world tick has at least " +
                                  std::to_string(kHeaderBytes));
    }
    Reader r(bytes);
    if (r.get<std::uint32_t>() != kWorldTickMagic) {
        return fail("header", "not a world tick (no DSWT magic)");
    }
    if (const auto version = r.get<std::uint16_t>(); version != kWorldTickVersion) {
        return fail("header", "version " + std::to_string(version) + ", this build reads " +
                                  std::to_string(kWorldTickVersion));
    }
    if (r.get<std::uint16_t>() != 0) {
        return fail("header", "reserved field not 0");
    }
    WorldTick tick;
    tick.world_key = r.get<std::uint64_t>();
    if (expected_key && tick.world_key != *expected_key) {
        return fail("header", "a tick of another world (map or settings differ: key " +
                                  std::to_string(tick.world_key) + ", expected " +
                                  std::to_string(*expected_key) + ")");
    }
    tick.instance = r.get<std::uint64_t>();
    if (tick.instance == 0) {
        return fail("header", "world instance 0 (a world process picks one that is not)");
    }
    tick.tick = r.get<std::uint64_t>();
    tick.frags = r.get<std::uint64_t>();
    tick.published_ns = r.get<std::uint64_t>();
    tick.next_id = r.get<std::uint32_t>();
    const auto count = r.get<std::uint32_t>();
    if (tick.next_id == 0) {
        return fail("header", "next id 0 (ids start at 1)");
    }
    if (count > kMaxWorldTickEntities || count >= tick.next_id ||
        static_cast<std::uint64_t>(count) * kEntityBytes > r.left()) {
        return fail("header", std::to_string(count) + " entities do not fit " +
                                  std::to_string(r.left()) + " bytes or next id " +
                                  std::to_string(tick.next_id));
    }
    tick.entities.reserve(count);
    std::uint32_t previous = 0;
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::string part =
            "entity " + std::to_string(i) + " (byte " + std::to_string(r.at()) + ")";
        if (r.left() < kEntityBytes) {
            return fail(part, "truncated: " + std::to_string(r.left()) + " bytes left of " +
                                  std::to_string(kEntityBytes));
        }
        interest::Entity e;
        e.id = r.get<std::uint32_t>();
        const auto kind = r.get<std::uint8_t>();
        const auto flags = r.get<std::uint8_t>();
        e.team = r.get<std::uint16_t>();
        const auto health = r.get<std::int32_t>();
        if (e.id <= previous || e.id >= tick.next_id) {
            return fail(part, "id " + std::to_string(e.id) + " after " + std::to_string(previous) +
                                  " (ids increase and stay below next id " +
                                  std::to_string(tick.next_id) + ")");
        }
        previous = e.id;
        if (kind > static_cast<std::uint8_t>(interest::EntityKind::player)) {
            return fail(part, "unknown kind " + std::to_string(kind));
        }
        e.kind = static_cast<interest::EntityKind>(kind);
        if ((flags & ~kKnownFlags) != 0) {
            return fail(part, "unknown flags " + std::to_string(flags));
        }
        if (health < -sim::kMaxHealth || health > sim::kMaxHealth) {
            return fail(part, "health " + std::to_string(health) + " outside -100..100");
        }
        e.health = health;
        e.move = get_move(r, (flags & kOnGround) != 0);
        e.yaw_deg = r.get<float>();
        e.pitch_deg = r.get<float>();
        e.audible.footstep_left = r.get<float>();
        e.audible.shot_left = r.get<float>();
        e.teleported = (flags & kTeleported) != 0;
        e.firing = (flags & kFiring) != 0;
        if (const std::string problem = move_problem(e.move); !problem.empty()) {
            return fail(part, problem);
        }
        if (!(e.yaw_deg >= -180.0f && e.yaw_deg <= 180.0f && e.pitch_deg >= -90.0f &&
              e.pitch_deg <= 90.0f)) {
            return fail(part, "view angles outside yaw -180..180, pitch -90..90");
        }
        if (!(e.audible.footstep_left >= 0.0f && e.audible.footstep_left <= 1.0e6f &&
              e.audible.shot_left >= 0.0f && e.audible.shot_left <= 1.0e6f)) {
            return fail(part, "sound time left not finite or negative");
        }
        if ((flags & kRespawnPending) != 0) {
            if (r.left() < kRespawnBytes) {
                return fail(part, "truncated respawn: " + std::to_string(r.left()) +
                                      " bytes left of " + std::to_string(kRespawnBytes));
            }
            sim::PendingRespawn respawn;
            respawn.arrival = get_move(r, (flags & kArrivalOnGround) != 0);
            respawn.yaw_degrees = r.get<float>();
            respawn.ticks_left = r.get<std::int32_t>();
            if (const std::string problem = move_problem(respawn.arrival); !problem.empty()) {
                return fail(part, "respawn arrival: " + problem);
            }
            if (!(std::fabs(respawn.yaw_degrees) <= 1.0e6f)) { // a map's spawn yaw, unwrapped
                return fail(part, "respawn yaw not finite or beyond 1e6 degrees");
            }
            if (respawn.ticks_left < 1 || respawn.ticks_left > kMaxRespawnTicks) {
                return fail(part, "respawn ticks left " + std::to_string(respawn.ticks_left) +
                                      " outside 1..1000000");
            }
            e.respawn = respawn;
        } else if ((flags & kArrivalOnGround) != 0) {
            return fail(part, "arrival flag without a pending respawn");
        }
        tick.entities.push_back(e);
    }
    if (r.left() != 0) {
        return fail("end", std::to_string(r.left()) + " bytes after the last entity");
    }
    return tick;
}

void apply_world_tick(WorldTick tick, interest::GameWorld& mirror) {
    mirror.mirror(std::move(tick.entities), tick.frags, tick.next_id);
}

} // namespace dsoc::scaleout
