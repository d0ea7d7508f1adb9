#include "dsoc/server/world_role.hpp"

#include "dsoc/server/interest_setup.hpp"
#include "dsoc/server/metrics.hpp"
#include "dsoc/server/tick_schedule.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <thread>

namespace dsoc::server {

namespace {

scaleout::NatsLinkOptions link_options(const ServerConfig& config) {
    scaleout::NatsLinkOptions options;
    options.url = config.nats_url;
    options.name = "dsoc-world:" + config.world_name;
    return options;
}

} // namespace

WorldRole::WorldRole(const ServerConfig& config, std::shared_ptr<const maps::Map> map)
    : config_(config), link_(link_options(config)),
      process_(std::move(map), world_settings(config), config.tick_rate, link_, config.world_name) {
}

void WorldRole::run(const std::atomic<bool>& stop) {
    using Clock = std::chrono::steady_clock;
    const auto period = std::chrono::nanoseconds(1'000'000'000LL / config_.tick_rate);
    const auto start = Clock::now();
    const auto end = config_.duration_s > 0.0
                         ? start + std::chrono::duration_cast<Clock::duration>(
                                       std::chrono::duration<double>(config_.duration_s))
                         : Clock::time_point::max();
    TickSchedule schedule(start, period);
    auto last_log = start;
    spdlog::info("world '{}' (instance {:016x}) on {}: {} Hz, publishing on {}", config_.world_name,
                 process_.instance(), config_.nats_url, config_.tick_rate,
                 scaleout::world_subject(config_.world_name, "tick"));
    while (!stop.load() && Clock::now() < end) {
        std::this_thread::sleep_until(std::min(schedule.next_due(), end));
        if (stop.load() || Clock::now() >= end) {
            break;
        }
        const auto now = Clock::now();
        skipped_ticks_ += schedule.skip_missed(now);
        late_ticks_ += schedule.start_tick(now) ? 1 : 0;
        process_.tick();
        if (now - last_log >= std::chrono::seconds(10)) {
            last_log = now;
            const scaleout::WorldProcessStats s = process_.stats();
            spdlog::info("world: {} ticks ({} not published), {} players joined, {} left, {} bad "
                         "messages, {} of another instance, {} reservations past the last id{}{}",
                         s.ticks, s.ticks_not_published, s.joins, s.leaves, s.bad_messages,
                         s.other_instance, s.ids_exhausted,
                         s.last_error.empty() ? "" : "; last: ", s.last_error);
        }
    }
}

std::string WorldRole::render_metrics() const {
    const scaleout::WorldProcessStats s = process_.stats();
    const auto d = [](auto v) { return static_cast<double>(v); };
    PrometheusText out;
    out.counter("dsoc_world_ticks_total", "World ticks stepped and published.", d(s.ticks));
    out.counter("dsoc_world_ticks_not_published_total",
                "World ticks the NATS link refused (no connection, its buffer full).",
                d(s.ticks_not_published));
    out.counter("dsoc_world_late_ticks_total", "Ticks that started more than one period late.",
                d(late_ticks_.load()));
    out.counter("dsoc_world_skipped_ticks_total",
                "Ticks dropped because the loop fell a whole period or more behind.",
                d(skipped_ticks_.load()));
    out.counter("dsoc_world_ids_reserved_total", "Entity ids reserved for gateways.",
                d(s.ids_reserved));
    out.counter("dsoc_world_joins_total", "Players spawned for gateways.", d(s.joins));
    out.counter("dsoc_world_leaves_total", "Players removed for gateways.", d(s.leaves));
    out.counter("dsoc_world_inputs_total", "Player inputs applied.", d(s.inputs));
    out.counter("dsoc_world_bad_messages_total", "Gateway messages that did not decode.",
                d(s.bad_messages));
    out.counter("dsoc_world_for_strangers_total",
                "Joins of ids not reserved for the sender, inputs and leaves for entities that "
                "are not its players.",
                d(s.for_strangers));
    out.counter("dsoc_world_repeated_total",
                "Joins of players already joined and leaves of players already gone (a "
                "gateway's re-sends): nothing changed.",
                d(s.repeated));
    out.counter("dsoc_world_gateways_lost_total",
                "Gateways silent past the timeout, their players removed.", d(s.gateways_lost));
    out.counter("dsoc_world_gateways_back_total",
                "Lost gateways heard again (their re-joins bring their players back).",
                d(s.gateways_back));
    out.counter("dsoc_world_gateways_forgotten_total",
                "Lost gateways whose reserved ids were released to make room for others.",
                d(s.gateways_forgotten));
    out.counter("dsoc_world_other_instance_total",
                "Gateway messages naming another world instance (a gateway that follows another "
                "world process on this name): dropped.",
                d(s.other_instance));
    out.counter("dsoc_world_ids_exhausted_total",
                "Reserve requests refused: fewer ids than asked for left below 2^32.",
                d(s.ids_exhausted));
    out.counter("dsoc_world_nats_disconnects_total", "Connections to NATS lost.",
                d(link_.disconnects()));
    out.counter("dsoc_world_nats_reconnects_total", "Connections to NATS regained.",
                d(link_.reconnects()));
    return out.text();
}

} // namespace dsoc::server
