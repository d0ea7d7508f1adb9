// Fuzzes the server's TOML config loader: any text gives problems or a config;
// whatever loads is validated, and a config that validates prints to TOML that
// loads back to the same text.

#include "dsoc/server/config_file.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    dsoc::server::ServerConfig config;
    config.insecure = true;
    if (!dsoc::server::apply_config_toml(text, "fuzz.toml", config).empty()) {
        return 0;
    }
    if (!dsoc::server::validate(config).empty()) {
        return 0;
    }
    const std::string printed = dsoc::server::format_config_toml(config);
    dsoc::server::ServerConfig again;
    if (!dsoc::server::apply_config_toml(printed, "printed.toml", again).empty() ||
        dsoc::server::format_config_toml(again) != printed) {
        std::abort(); // --print-config wrote something the loader reads differently
    }
    return 0;
}
