#include "dsoc/server/source_key.hpp"

namespace dsoc::server {

namespace asio = boost::asio;

SourceKey source_key(const asio::ip::address& a) {
    if (a.is_v4()) {
        return {a.to_v4().to_uint(), false};
    }
    const asio::ip::address_v6 v6 = a.to_v6();
    if (v6.is_v4_mapped()) { // an IPv4 peer on a dual-stack socket
        return {asio::ip::make_address_v4(asio::ip::v4_mapped, v6).to_uint(), false};
    }
    const auto bytes = v6.to_bytes();
    std::uint64_t prefix = 0;
    for (std::size_t i = 0; i < 8; ++i) {
        prefix = (prefix << 8) | bytes[i];
    }
    return {prefix, true};
}

} // namespace dsoc::server
