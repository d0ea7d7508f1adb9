#include "dsoc/protocol/codec.hpp"

#include <cctype>

namespace dsoc::protocol {

std::string disconnect_reason_name(pb::DisconnectReason reason) {
    std::string name = pb::DisconnectReason_Name(reason);
    constexpr std::string_view prefix = "DISCONNECT_REASON_";
    if (name.empty()) {
        return "unknown_" + std::to_string(static_cast<int>(reason));
    }
    if (name.starts_with(prefix)) {
        name.erase(0, prefix.size());
    }
    for (char& c : name) {
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    return name;
}

} // namespace dsoc::protocol
