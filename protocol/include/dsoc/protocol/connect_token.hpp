#pragma once
// Connect tokens: who may connect. A backend that knows the server's secret key
// mints a token for one client id with an expiry; the client presents it in its
// ClientHello; the server checks the HMAC-SHA256 signature (OpenSSL libcrypto) and
// the expiry before it spawns anything for the connection.
//
// Wire format, version 1, 49 bytes:
//   [0]      version = 1
//   [1, 9)   client id, uint64 little-endian
//   [9, 17)  expiry, seconds since the Unix epoch (UTC), uint64 little-endian
//   [17, 49) HMAC-SHA256(key, bytes [0, 17))
// The token is signed, not encrypted: its id and expiry are readable by anyone who
// holds it. It is a bearer token: whoever presents it within its lifetime is that
// client, so keep lifetimes short (minutes) and deliver tokens over a secure channel.
//
// Thread-safe: every function is pure or uses only its arguments.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace dsoc::protocol {

inline constexpr std::size_t kTokenKeyBytes = 32;
inline constexpr std::size_t kConnectTokenBytes = 49;
inline constexpr std::uint8_t kConnectTokenVersion = 1;

/// The server's secret. Never logged or printed by the server.
struct TokenKey {
    std::array<std::uint8_t, kTokenKeyBytes> bytes{};
};

/// What a token grants.
struct ConnectToken {
    std::uint64_t client_id = 0;      ///< >= 1; 0 is reserved and never verifies
    std::uint64_t expires_unix_s = 0; ///< valid while now < expires_unix_s
};

/// A fresh random key from OpenSSL's CSPRNG. Throws std::runtime_error if the CSPRNG
/// fails (it does not on a working system).
[[nodiscard]] TokenKey generate_token_key();

/// 64 lowercase hex digits.
[[nodiscard]] std::string format_token_key(const TokenKey& key);

/// Parses 64 hex digits (either case; ASCII whitespace anywhere is ignored). On
/// failure returns false and says why in `error`.
[[nodiscard]] bool parse_token_key(std::string_view text, TokenKey& key, std::string& error);

/// Reads a key file (the format of parse_token_key). `error` names the path and why.
[[nodiscard]] bool load_token_key(const std::string& path, TokenKey& key, std::string& error);

/// The 49-byte token for `token`, signed with `key`.
[[nodiscard]] std::vector<std::uint8_t> mint_connect_token(const TokenKey& key,
                                                           const ConnectToken& token);

enum class TokenStatus : std::uint8_t {
    valid,
    malformed,     ///< wrong length or version, or client id 0
    bad_signature, ///< not signed with this server's key (or altered)
    expired,       ///< signed, but now >= expiry
};

struct TokenCheck {
    TokenStatus status = TokenStatus::malformed;
    ConnectToken token; ///< filled when the signature is good (valid or expired)
    std::string why;    ///< readable reason when not valid, e.g. "expired 12 s ago"
};

/// Checks `bytes` against `key` at `now_unix_s`. Never trusts the bytes: any input
/// gives an answer. The signature is compared in constant time.
[[nodiscard]] TokenCheck verify_connect_token(const TokenKey& key,
                                              std::span<const std::uint8_t> bytes,
                                              std::uint64_t now_unix_s);

/// Seconds since the Unix epoch now (system clock).
[[nodiscard]] std::uint64_t unix_now_s();

/// Lowercase hex of `bytes`, and back (false on odd length or a non-hex digit).
[[nodiscard]] std::string to_hex(std::span<const std::uint8_t> bytes);
[[nodiscard]] bool from_hex(std::string_view hex, std::vector<std::uint8_t>& out);

} // namespace dsoc::protocol
