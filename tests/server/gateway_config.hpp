#pragma once
// The settings of an interest gateway for the tests that run one: as
// `dsoc-server --role gateway --nats-url URL --world-name NAME` (docs/scale-out.md).

#include "dsoc/server/server_config.hpp"

#include <string>

namespace dsoc::testing {

inline server::ServerConfig gateway_config(const std::string& nats_url,
                                           const std::string& world_name) {
    server::ServerConfig config;
    config.role = "gateway";
    config.nats_url = nats_url;
    config.world_name = world_name;
    return config;
}

} // namespace dsoc::testing
