// dsoc-nats-fanout: world ticks of `--entities` entities (a generated map's world with
// that many bots, stepped once, then encoded at every tick) published at `--tick-rate`
// for `--seconds` to `--subscribers` subscribers, each on a connection of its own, as
// gateways are. Prints, per subscriber, ticks received and skipped, bytes a second, and
// publish -> receive latency percentiles, and the nats-server's CPU over the run when
// `--server-pid` names it. For docs/scale-out.md's capacity figures.

#include "dsoc/cli/program.hpp"
#include "dsoc/common/percentiles.hpp"
#include "dsoc/maps/map_source.hpp"
#include "dsoc/scaleout/nats_link.hpp"
#include "dsoc/scaleout/world_tick.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

/// user + system CPU seconds of process `pid` (0 when unreadable).
double cpu_seconds(int pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string field;
    double ticks = 0.0;
    for (int i = 1; i <= 15 && in >> field; ++i) {
        if (i == 14 || i == 15) {
            ticks += std::stod(field);
        }
    }
    return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

struct Subscriber {
    std::unique_ptr<dsoc::scaleout::NatsLink> link;
    std::unique_ptr<dsoc::scaleout::NatsSubscription> sub;
    std::mutex mutex;
    std::vector<double> latency_us;
    std::uint64_t bytes = 0;
    std::uint64_t bad = 0;
};

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"dsoc-nats-fanout: world ticks fanned out over NATS, measured"};
    dsoc::cli::set_up(app, "dsoc-nats-fanout");
    std::string url = "nats://127.0.0.1:4222";
    int entities = 1000;
    int subscribers = 3;
    int tick_rate = 30;
    double seconds = 10.0;
    int server_pid = 0;
    app.add_option("--url", url, "NATS server");
    app.add_option("--entities", entities, "Entities in each tick")->check(CLI::Range(1, 1 << 20));
    app.add_option("--subscribers", subscribers, "Subscribers (gateways)")
        ->check(CLI::Range(1, 64));
    app.add_option("--tick-rate", tick_rate, "Ticks a second")->check(CLI::Range(1, 240));
    app.add_option("--seconds", seconds, "Length of the run")->check(CLI::Range(0.5, 3600.0));
    app.add_option("--server-pid", server_pid, "The nats-server's pid, for its CPU");
    if (const auto stop = dsoc::cli::parse(app, argc, argv)) {
        return *stop;
    }
    auto map = dsoc::maps::load_map("gen:rooms:3", dsoc::maps::MapSearch{});
    if (!map) {
        return dsoc::cli::exit_failure;
    }
    dsoc::interest::WorldSettings settings;
    settings.bots = entities;
    dsoc::interest::GameWorld world(
        settings, std::make_shared<const dsoc::maps::Map>(std::move(map).value()));
    world.step(1.0f / static_cast<float>(tick_rate));
    const std::uint64_t key = 1;

    try {
        dsoc::scaleout::NatsLinkOptions options;
        options.url = url;
        std::vector<std::unique_ptr<Subscriber>> subs;
        for (int i = 0; i < subscribers; ++i) {
            auto s = std::make_unique<Subscriber>();
            s->link = std::make_unique<dsoc::scaleout::NatsLink>(options);
            Subscriber* raw = s.get();
            s->sub = s->link->subscribe(
                "dsoc.fanout.tick",
                [raw](const dsoc::scaleout::NatsMessage& m) {
                    const std::uint64_t now = dsoc::scaleout::monotonic_ns();
                    auto tick = dsoc::scaleout::decode_world_tick(m.data, "fanout");
                    const std::lock_guard lock(raw->mutex);
                    raw->bytes += m.data.size();
                    if (!tick.ok()) {
                        ++raw->bad;
                        return;
                    }
                    raw->latency_us.push_back(static_cast<double>(now - tick->published_ns) * 1e-3);
                },
                4);
            (void)s->link->flush(std::chrono::seconds(2));
            subs.push_back(std::move(s));
        }
        dsoc::scaleout::NatsLink publisher(options);
        const double server_cpu0 = server_pid > 0 ? cpu_seconds(server_pid) : 0.0;
        const auto period = std::chrono::nanoseconds(1'000'000'000LL / tick_rate);
        const auto start = Clock::now();
        const auto ticks = static_cast<std::uint64_t>(seconds * tick_rate);
        std::vector<std::byte> bytes;
        for (std::uint64_t t = 1; t <= ticks; ++t) {
            std::this_thread::sleep_until(start + period * t);
            dsoc::scaleout::encode_world_tick(world, key, t, bytes, dsoc::scaleout::monotonic_ns());
            (void)publisher.publish("dsoc.fanout.tick", bytes);
        }
        (void)publisher.flush(std::chrono::seconds(5));
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        const double server_cpu = server_pid > 0 ? cpu_seconds(server_pid) - server_cpu0 : 0.0;
        const double wall = std::chrono::duration<double>(Clock::now() - start).count();
        fmt::print("{} entities, {} bytes a tick, {} Hz, {} subscribers, {:.1f} s\n", entities,
                   bytes.size(), tick_rate, subscribers, wall);
        for (std::size_t i = 0; i < subs.size(); ++i) {
            Subscriber& s = *subs[i];
            const std::lock_guard lock(s.mutex);
            const auto l = dsoc::common::summarize(s.latency_us);
            fmt::print(
                "subscriber {}: {} of {} ticks ({} dropped by its limit, {} bad), {:.2f} MB/s, "
                "latency p50 {:.0f} us p99 {:.0f} us max {:.0f} us\n",
                i + 1, s.latency_us.size(), ticks, s.sub->dropped(), s.bad,
                static_cast<double>(s.bytes) / wall / 1e6, l.p50, l.p99, l.max);
        }
        if (server_pid > 0) {
            fmt::print("nats-server: {:.2f} s of CPU over the run, {:.1f}% of a core\n", server_cpu,
                       100.0 * server_cpu / wall);
        }
        for (auto& s : subs) {
            s->sub.reset();
        }
    } catch (const dsoc::scaleout::NatsError& e) {
        fmt::print(stderr, "dsoc-nats-fanout: {}\n", e.what());
        return dsoc::cli::exit_failure;
    }
    return dsoc::cli::exit_ok;
}
