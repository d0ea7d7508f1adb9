#pragma once
// The UDP handshake's challenge cookie (docs/protocol.md, "UDP transport"): proof that a
// client receives datagrams at the address it sends from, before the server keeps any
// state for it. The server answers a request with a cookie bound to the request's source
// address, port and nonce and to the time; only a client that receives it can echo it in
// its response. The server stores nothing between the two: the cookie is checked with
// the server's cookie key alone.
//
// Layout, kCookieBytes = 24: u64 issue time in milliseconds since the Unix epoch
// (little-endian), then the first 16 bytes of HMAC-SHA256(key, "dsoc-cookie-1" | address
// (16 bytes, IPv4 as IPv4-mapped IPv6) | port (u16 LE) | nonce (u64 LE) | issue time).
//
// Thread-safe: pure functions of their arguments.

#include "dsoc/protocol/connect_token.hpp"
#include "dsoc/protocol/datagram.hpp"

#include <array>
#include <cstdint>
#include <span>

namespace dsoc::protocol {

/// Where a datagram came from, as the cookie binds it.
struct SourceAddress {
    std::array<std::uint8_t, 16> address{}; ///< IPv6, or IPv4-mapped IPv6
    std::uint16_t port = 0;
};

using ChallengeCookie = std::array<std::uint8_t, kCookieBytes>;

[[nodiscard]] ChallengeCookie make_challenge_cookie(const TokenKey& key, const SourceAddress& from,
                                                    std::uint64_t nonce, std::uint64_t now_ms);

enum class CookieStatus : std::uint8_t {
    valid,
    forged,  ///< not made by this key for this address, port and nonce
    expired, ///< made more than max_age_ms ago, or in the future
};

/// Checks `cookie` (any bytes) in constant time.
[[nodiscard]] CookieStatus check_challenge_cookie(const TokenKey& key,
                                                  std::span<const std::uint8_t> cookie,
                                                  const SourceAddress& from, std::uint64_t nonce,
                                                  std::uint64_t now_ms, std::uint64_t max_age_ms);

/// 64 random bits from OpenSSL's CSPRNG (session ids, nonces); never 0. Throws
/// std::runtime_error if the CSPRNG fails.
[[nodiscard]] std::uint64_t random_nonzero_u64();

} // namespace dsoc::protocol
