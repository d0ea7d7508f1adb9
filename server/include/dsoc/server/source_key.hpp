#pragma once
// Which source a peer's address counts as, for the limits kept per source (UDP handshake
// budgets, TCP connections waiting for their hello): an IPv4 address, also one that
// reaches a dual-stack socket as ::ffff:a.b.c.d, or an IPv6 /64 (one host holds a whole
// /64; keyed by the /128 it could spend as many budgets as it likes).

#include <boost/asio/ip/address.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>

namespace dsoc::server {

struct SourceKey {
    std::uint64_t bits = 0; ///< the IPv4 address, or the IPv6 address's first 64 bits
    bool v6 = false;
    friend bool operator==(const SourceKey&, const SourceKey&) = default;
};

struct SourceKeyHash {
    std::size_t operator()(const SourceKey& k) const noexcept {
        return std::hash<std::uint64_t>{}(k.bits) ^ static_cast<std::size_t>(k.v6);
    }
};

[[nodiscard]] SourceKey source_key(const boost::asio::ip::address& address);

} // namespace dsoc::server
