#pragma once
// Why the server's UDP endpoint dropped a datagram: one counter per reason, served in
// /metrics as dsoc_udp_datagrams_dropped_total{reason}. A dropped datagram is never
// answered and never disturbs a session.

#include "dsoc/protocol/datagram.hpp"

#include <array>
#include <cstddef>
#include <cstdint>

namespace dsoc::server {

enum class UdpDrop : std::uint8_t {
    truncated,           ///< shorter than its header or body says
    oversized,           ///< longer than protocol::kMaxDatagramBytes
    not_dsoc,            ///< not our protocol id
    wrong_version,       ///< another datagram format version
    unknown_kind,        ///< a kind byte this build does not know
    bad_body,            ///< a body that does not parse (a length, a count, padding, a message)
    unexpected_kind,     ///< a kind the server never receives (challenge, accepted, snapshot)
    unknown_session,     ///< names no open session, nor one closed in the last 10 s
    closed_session,      ///< names a session closed in the last 10 s (a late or repeated goodbye)
    wrong_source,        ///< a session's datagram from another address than its own
    replayed,            ///< a sequence number taken before, or far too old
    rate_limited,        ///< a response with a valid cookie over its source address's budget
    forged_cookie,       ///< a response whose cookie this server did not make for its sender
    expired_cookie,      ///< a response whose cookie is too old
    over_challenge_rate, ///< a request beyond the challenges the server answers a second
    count_,
};

inline constexpr std::size_t kUdpDropReasons = static_cast<std::size_t>(UdpDrop::count_);

/// The reason's name in metrics and logs, e.g. "wrong_source". Static storage.
const char* udp_drop_name(UdpDrop drop) noexcept;

/// The drop reason of a datagram error (error != none).
UdpDrop udp_drop_of(protocol::DatagramError error) noexcept;

using UdpDropCounts = std::array<std::uint64_t, kUdpDropReasons>;

} // namespace dsoc::server
