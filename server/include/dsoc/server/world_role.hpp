#pragma once
// dsoc-server --role world (docs/scale-out.md): the authoritative world of a scaled-out
// game, ticked at config.tick_rate and published on NATS for the interest gateways
// (scaleout::WorldProcess). No clients, no sockets of its own beyond NATS and /metrics.

#include "dsoc/maps/map.hpp"
#include "dsoc/scaleout/nats_link.hpp"
#include "dsoc/scaleout/world_process.hpp"
#include "dsoc/server/server_config.hpp"

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

namespace dsoc::server {

class WorldRole {
public:
    /// Connects to config.nats_url (throws scaleout::NatsError when no server answers)
    /// and builds the world on `map` from config's world settings.
    WorldRole(const ServerConfig& config, std::shared_ptr<const maps::Map> map);

    /// Ticks at config.tick_rate on the calling thread until `stop` is set or
    /// config.duration_s has passed. A tick that starts a whole period late drops the
    /// ticks it missed (counted), as the single-process server does.
    void run(const std::atomic<bool>& stop);

    /// What /metrics serves (Prometheus text; docs/operations.md lists the names).
    /// Safe from any thread.
    [[nodiscard]] std::string render_metrics() const;
    [[nodiscard]] scaleout::WorldProcessStats stats() const { return process_.stats(); }
    [[nodiscard]] std::uint64_t world_key() const { return process_.world_key(); }

private:
    ServerConfig config_;
    scaleout::NatsLink link_;
    scaleout::WorldProcess process_;
    std::atomic<std::uint64_t> late_ticks_{0};
    std::atomic<std::uint64_t> skipped_ticks_{0};
};

} // namespace dsoc::server
