// dsoc-tick-bench: the server's tick for N connected players, in one process and
// without sockets, split into its phases, so that a capacity question ("what does
// a tick cost with 500 players?") has an answer that does not depend on a load
// generator sharing the machine. Each player steers like dsoc-simclient (a heading
// held 1-3 s); every tick runs what a server tick runs (Server::start_tick and the
// parallel phase) - movement, the policy's begin_tick, per client select() plus the
// viewer's own entity, the compact snapshot and its frame - and, apart, the client's
// decoding of that frame.
//
// Phases are timed on one thread with the monotonic clock (a vDSO read of tens of
// nanoseconds: the phases per client-tick are a few microseconds, and the thread's CPU
// clock, a system call here, cost more than a microsecond per read). The thread's CPU
// clock is read once per tick beside it: the report says what share of the phases'
// time the thread was on a CPU, below 100% when other processes preempted it and the
// phases carry that. `perf stat -e instructions:u` around the program gives a count
// that does not depend on load.
// The output is deterministic for a seed except the times (entity updates and
// bytes are a checksum of the run).

#include "dsoc/cli/program.hpp"
#include "dsoc/common/percentiles.hpp"
#include "dsoc/interest/game_world.hpp"
#include "dsoc/interest/interest_policy.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/compact_snapshot.hpp"
#include "dsoc/protocol/datagram.hpp"
#include "dsoc/server/client_tick.hpp"
#include "dsoc/server/interest_setup.hpp"
#include "dsoc/server/replication_state.hpp"
#include "dsoc/server/server_config.hpp"
#include "dsoc/server/udp_connection.hpp"

#include "program_options.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <memory>
#include <random>
#include <span>
#include <vector>

namespace {

using namespace dsoc;

double clock_ms(clockid_t clock) {
    timespec ts{};
    clock_gettime(clock, &ts);
    return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}
double phase_clock_ms() {
    return clock_ms(CLOCK_MONOTONIC);
}
double thread_cpu_ms() {
    return clock_ms(CLOCK_THREAD_CPUTIME_ID);
}

/// What one read of the phase clock costs [Units: ms], the least mean of a few runs of
/// back-to-back reads: each phase's figure per client-tick carries one read (the bench
/// reads the clock between phases), so ratios of two phases subtract it.
double clock_read_ms() {
    double least = 1e9;
    for (int run = 0; run < 5; ++run) {
        constexpr int reads = 2000;
        const double start = phase_clock_ms();
        double last = start;
        for (int i = 0; i < reads; ++i) {
            last = phase_clock_ms();
        }
        least = std::min(least, (last - start) / reads);
    }
    return least;
}

struct Player {
    std::uint32_t client_id = 0;
    std::uint32_t entity_id = 0;
    server::ReplicationState replication;
    std::vector<interest::Interest> interest;
    protocol::pb::Envelope envelope;
    std::vector<std::uint8_t> frame;
    protocol::UpdateColumns columns;   // the update entries in wire form, as the server keeps them
    protocol::SnapshotDecoder decoder; // the client's side
    protocol::AckedSnapshotDecoder acked_decoder; // the client's side over UDP
    float heading_deg = 0.0f;
    int ticks_until_turn = 0;
};

struct Phases {
    double movement = 0.0;   // world step and inputs
    double begin_tick = 0.0; // the policy's serial part
    double select = 0.0;     // per-client interest (InterestPolicy::select)
    double hearing = 0.0;    // Hearing::begin_tick and per client add_heard
    double snapshot = 0.0;   // SharedPoses::compute, ReplicationState::build_snapshot
    double encode = 0.0;     // the frame
    double decode = 0.0;     // client side: parse + SnapshotDecoder::apply

    /// The server's phases (all but the client's decode). [ms]
    [[nodiscard]] double server() const {
        return movement + begin_tick + select + hearing + snapshot + encode;
    }

    Phases& operator+=(const Phases& p) {
        movement += p.movement;
        begin_tick += p.begin_tick;
        select += p.select;
        hearing += p.hearing;
        snapshot += p.snapshot;
        encode += p.encode;
        decode += p.decode;
        return *this;
    }
};

} // namespace

int main(int argc, char** argv) {
    server::ServerConfig config;
    int players = 500;
    int ticks = 90;
    int warm_up = 30;
    bool udp = false;
    int ack_delay = 0;
    CLI::App app{"dsoc-tick-bench: CPU per server tick for N players, by phase, no sockets"};
    cli::set_up(app, "dsoc-tick-bench");
    server::add_world_options(app, config);
    server::add_policy_options(app, config);
    app.add_option("--players", players, "Connected players (viewers)")
        ->capture_default_str()
        ->check(CLI::Range(1, 100000));
    app.add_option("--ticks", ticks, "Measured ticks")
        ->capture_default_str()
        ->check(CLI::Range(1, 1000000));
    app.add_option("--warm-up", warm_up, "Ticks run before measuring (players join over them)")
        ->capture_default_str()
        ->check(CLI::Range(1, 1000000));
    app.add_option("--udp", udp,
                   "Snapshots as over UDP: acknowledged deltas, each client acknowledging every "
                   "snapshot before the next tick (a LAN), split into datagrams (true/false)")
        ->capture_default_str();
    app.add_option("--ack-delay", ack_delay,
                   "With --udp: each client's acknowledgement is of the snapshot this many ticks "
                   "older than the newest it decoded, as a round trip makes it (snapshots are "
                   "then coded against older baselines)")
        ->capture_default_str()
        ->check(CLI::Range(0, 16));
    if (const auto stop = cli::parse(app, argc, argv)) {
        return *stop;
    }
    config.insecure = true; // no connections here: the token settings do not matter
    if (const auto problems = server::validate(config); !problems.empty()) {
        for (const auto& p : problems) {
            fmt::print(stderr, "invalid setting: {}\n", p);
        }
        return cli::exit_usage;
    }
    auto loaded = maps::load_map(config.map, maps::MapSearch::from_environment());
    if (!loaded) {
        fmt::print(stderr, "dsoc-tick-bench: {}\n",
                   cli::map_load_failure("--map", config.map, loaded.error().message()));
        return cli::exit_usage;
    }
    const auto map = std::make_shared<const maps::Map>(std::move(loaded).value());
    interest::GameWorld world(server::world_settings(config), map);
    auto policy = server::make_policy(config, world);
    std::vector<std::unique_ptr<Player>> clients;
    server::SharedPoses poses;
    interest::Hearing hearing;
    std::uint64_t heard = 0;
    std::uint64_t sent_entities = 0; // every entity a client is sent, seen or heard
    std::mt19937_64 rng(config.seed);
    const float dt = 1.0f / static_cast<float>(config.tick_rate);
    Phases total;
    std::vector<double> server_ms_of_tick; // each measured tick's server phases [ms]
    double on_cpu = 0.0;                   // the thread's CPU time over the measured ticks [ms]
    std::uint64_t updates = 0;
    std::uint64_t bytes = 0;
    std::uint64_t decode_problems = 0;
    std::uint64_t fragments = 0; // datagrams (--udp)
    std::uint64_t oversized =
        0;                      // snapshots over kMaxSnapshotBytes: not sent, as the server (--udp)
    std::uint64_t deferred = 0; // entities left to enter in a later snapshot (--udp)
    std::uint64_t updates_deferred = 0;  // update entries left for a later snapshot (--udp)
    std::vector<std::uint8_t> datagrams; // one snapshot's (--udp)
    protocol::EnvelopeArena incoming(256 * 1024); // as the simulated clients decode
    for (int t = 1; t <= warm_up + ticks; ++t) {
        const auto tick = static_cast<std::uint64_t>(t);
        const bool measured = t > warm_up;
        Phases p;
        const double cpu_at_start = thread_cpu_ms();
        double at = phase_clock_ms();
        const auto lap = [&](double& phase) {
            const double now = phase_clock_ms();
            phase += now - at;
            at = now;
        };
        // Players join evenly over the warm-up.
        while (static_cast<int>(clients.size()) < players &&
               static_cast<long>(clients.size()) * warm_up < static_cast<long>(players) * t) {
            auto c = std::make_unique<Player>();
            c->client_id = static_cast<std::uint32_t>(clients.size() + 1);
            c->entity_id = world.spawn_player();
            c->replication = server::ReplicationState(server::quantization(config), udp);
            c->decoder.set_settings(server::quantization(config));
            c->acked_decoder = protocol::AckedSnapshotDecoder(server::quantization(config));
            policy->add_viewer(c->client_id, c->entity_id);
            clients.push_back(std::move(c));
        }
        for (auto& c : clients) {
            if (--c->ticks_until_turn <= 0) {
                c->heading_deg = std::uniform_real_distribution<float>(-180.0f, 180.0f)(rng);
                c->ticks_until_turn =
                    std::uniform_int_distribution<int>(config.tick_rate, 3 * config.tick_rate)(rng);
            }
            const float rad = c->heading_deg * 3.14159265f / 180.0f;
            world.set_player_input(c->entity_id, glm::vec3(std::cos(rad), std::sin(rad), 0.0f),
                                   false, c->heading_deg, 0.0f);
        }
        world.step(dt);
        lap(p.movement);
        policy->begin_tick(world, tick);
        lap(p.begin_tick);
        hearing.begin_tick(world);
        lap(p.hearing);
        poses.compute(world, server::quantization(config));
        lap(p.snapshot);
        for (auto& c : clients) {
            const interest::Entity* self = world.find(c->entity_id);
            const interest::Viewer viewer = interest::viewer_of(world, c->client_id, *self);
            // As run_client_ticks: the policy's set, what the viewer hears, its own entity.
            policy->select(world, viewer, c->interest);
            lap(p.select);
            const std::size_t heard_now = hearing.add_heard(viewer, *policy, c->interest);
            heard += measured ? heard_now : 0;
            lap(p.hearing);
            server::add_own_entity(c->interest, c->entity_id);
            sent_entities += measured ? c->interest.size() : 0;
            if (udp) {
                // Nothing acknowledged until the delay has passed (acknowledgements never go
                // back: an undelayed one first would be newer than the delayed ones after).
                const std::optional<std::uint64_t> newest = c->acked_decoder.newest_tick();
                const auto delay = static_cast<std::uint64_t>(ack_delay);
                const std::optional<std::uint64_t> acked =
                    newest && *newest > delay ? std::optional(*newest - delay) : std::nullopt;
                c->replication.build_acked_snapshot(world, c->interest, viewer.eye, tick, acked,
                                                    false, *c->envelope.mutable_snapshot(), &poses,
                                                    &c->columns);
                lap(p.snapshot);
                // As the server: the frame on the pool, its datagrams in write_now().
                server::snapshot_frame(tick, c->envelope, &c->columns, c->frame);
                datagrams.clear();
                const std::size_t count = protocol::write_snapshot_datagrams(
                    1, 1, tick, std::span(c->frame).subspan(8), datagrams);
                lap(p.encode);
                const protocol::pb::Envelope* received = nullptr;
                if (count == 0) {
                    oversized += measured ? 1 : 0; // the client never sees nor acknowledges it
                } else if (incoming.decode(std::span(c->frame).subspan(8), received) !=
                           protocol::DecodeError::none) {
                    ++decode_problems;
                } else {
                    decode_problems += c->acked_decoder.apply(received->snapshot()).size();
                }
                lap(p.decode);
                if (measured) {
                    updates += c->replication.last_updates();
                    bytes += datagrams.size() - 2 * count; // without the length prefixes
                    fragments += count;
                    deferred += c->replication.last_deferred();
                    updates_deferred += c->replication.last_updates_deferred();
                }
                continue;
            }
            c->replication.build_snapshot(world, c->interest, tick, false,
                                          *c->envelope.mutable_snapshot(), &poses, &c->columns);
            lap(p.snapshot);
            c->frame.clear();
            protocol::encode_snapshot_frame(c->envelope, c->columns, c->frame);
            lap(p.encode);
            const std::span<const std::uint8_t> payload(c->frame.data() + 4, c->frame.size() - 4);
            const protocol::pb::Envelope* received = nullptr;
            if (incoming.decode(payload, received) != protocol::DecodeError::none) {
                ++decode_problems;
            } else {
                decode_problems += c->decoder.apply(received->snapshot()).size();
            }
            lap(p.decode);
            if (measured) {
                const auto& s = c->envelope.snapshot();
                updates += static_cast<std::uint64_t>(s.enter_size()) + c->columns.count();
                bytes += c->frame.size();
            }
        }
        if (measured) {
            total += p;
            server_ms_of_tick.push_back(p.server());
            on_cpu += thread_cpu_ms() - cpu_at_start;
        }
    }
    const double n = ticks;
    const double server_ms = total.server() / n;
    const double client_tick = static_cast<double>(clients.size()) * n;
    fmt::print("dsoc-tick-bench: map {} policy {} bots {} players {} tick rate {} Hz, {} ticks "
               "measured after {}, snapshots {}\n",
               map->name, dsoc::interest::name_of(config.policy), config.bots, clients.size(),
               config.tick_rate, ticks, warm_up,
               udp ? "acknowledged deltas in datagrams (--udp)" : "compact, TCP frames");
    fmt::print("  server CPU per tick  {:8.2f} ms (one thread; budget {:.1f} ms per core)\n",
               server_ms, 1000.0 / config.tick_rate);
    // How the ticks spread: the wall time of one thread's phases, tick to tick, with no
    // socket and nothing else of the server's beside it (the host's own hiccups are in
    // it, so it bounds the work's own spread from above).
    std::sort(server_ms_of_tick.begin(), server_ms_of_tick.end());
    const auto at_quantile = [&](double q) {
        return common::percentile_sorted(server_ms_of_tick, q);
    };
    fmt::print("  a tick's spread      p50 {:.2f} / p90 {:.2f} / p99 {:.2f} / max {:.2f} ms\n",
               at_quantile(0.5), at_quantile(0.9), at_quantile(0.99), server_ms_of_tick.back());
    const double all_phases_ms = server_ms * n + total.decode;
    fmt::print("  on a CPU             {:.1f}% of the phases' time (below 100: preempted)\n",
               100.0 * on_cpu / all_phases_ms);
    const auto row = [&](const char* name, double ms) {
        fmt::print("    {:<18} {:8.2f} ms  {:5.1f}%  {:6.2f} us per client-tick\n", name, ms / n,
                   100.0 * ms / n / server_ms, 1000.0 * ms / client_tick);
    };
    row("movement", total.movement);
    row("begin_tick", total.begin_tick);
    row("select (interest)", total.select);
    row("hearing", total.hearing);
    row("build_snapshot", total.snapshot);
    row("encode frame", total.encode);
    fmt::print("  client decode        {:8.2f} ms per tick for all clients, {:.2f} us per "
               "snapshot\n",
               total.decode / n, 1000.0 * total.decode / client_tick);
    // Per client-tick, select and hearing each carry one read of the clock.
    const double clock_us = 1000.0 * clock_read_ms();
    const double select_us = 1000.0 * total.select / client_tick - clock_us;
    const double hearing_us = 1000.0 * total.hearing / client_tick - clock_us;
    fmt::print("  entities             {:.2f} sent per client-tick, seen or heard (what a "
               "snapshot's frame holds)\n",
               static_cast<double>(sent_entities) / client_tick);
    fmt::print("  hearing              {:.2f} heard-only entities per client-tick; beyond the "
               "{:.2f} us clock read each carries: {:.2f} us, {:.1f}% of select's {:.2f} us\n",
               static_cast<double>(heard) / client_tick, clock_us, hearing_us,
               100.0 * hearing_us / select_us, select_us);
    fmt::print("  checksum             {} entity updates, {} bytes, {} decode problems\n", updates,
               bytes, decode_problems);
    if (udp) {
        fmt::print("  datagrams            {:.3f} per snapshot\n",
                   static_cast<double>(fragments) / client_tick);
        fmt::print("  oversized            {} snapshots over {} bytes, not sent (the server drops "
                   "them too; docs/protocol.md)\n",
                   oversized, protocol::kMaxSnapshotBytes);
        fmt::print("  deferred enters      {:.2f} per client-tick (over {} entering one snapshot, "
                   "or over the datagrams' bytes: the rest enter later, nearest first)\n",
                   static_cast<double>(deferred) / client_tick, protocol::kMaxEntersPerSnapshot);
        fmt::print("  deferred updates     {:.2f} per client-tick (entries over the datagrams' "
                   "bytes: repaired by a later snapshot, nearest first)\n",
                   static_cast<double>(updates_deferred) / client_tick);
    }
    return decode_problems == 0 ? cli::exit_ok : cli::exit_failure;
}
