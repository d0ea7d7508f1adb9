#pragma once
// Why a session failed: one name per failed session, counted in the progress lines,
// the summary, the JSON report and the time series (docs/simclient.md, "Failures").

#include "dsoc/protocol/messages.hpp"

#include <boost/system/error_code.hpp>

#include <string>
#include <string_view>

namespace dsoc::simclient::failure {

inline constexpr std::string_view unresolvable = "unresolvable"; ///< the host name has no address
inline constexpr std::string_view refused = "refused";           ///< nothing listens on the port
/// No TCP connection, or no server hello, within the connect timeout.
inline constexpr std::string_view timeout = "timeout";
inline constexpr std::string_view connect_error = "connect_error"; ///< another socket error
inline constexpr std::string_view unauthorized = "unauthorized";   ///< the token was refused
inline constexpr std::string_view version_mismatch = "version_mismatch";
/// The server shut down before the scenario's end.
inline constexpr std::string_view server_shutdown = "server_shutdown";
/// A gateway's world process restarted: the session's player is gone; connect again.
inline constexpr std::string_view world_restarted = "world_restarted";
/// The server cannot take a player yet (a gateway waiting for entity ids, or the
/// connection made room among too many waiting for their hello): connect again.
inline constexpr std::string_view try_again = "try_again";
/// The server ended the session for another reason (server_full, too_slow,
/// handshake_timeout, input_flood, ...; the reason is in disconnect_reasons).
inline constexpr std::string_view dropped_by_server = "dropped_by_server";
/// The connection closed or broke without a Disconnect from the server.
inline constexpr std::string_view connection_lost = "connection_lost";
/// The client saw a protocol error (protocol_errors_by_kind says which).
inline constexpr std::string_view protocol_error = "protocol_error";

/// The reason for an error while resolving (`resolving`) or connecting.
[[nodiscard]] std::string_view of_connect_error(const boost::system::error_code& ec,
                                                bool resolving);

/// The reason a Disconnect from the server means, or "" when it is no failure
/// (client_quit, unspecified). server_shutdown is returned as such; whether it came
/// before the scenario's end is the caller's to judge.
[[nodiscard]] std::string_view of_disconnect(protocol::pb::DisconnectReason reason);

} // namespace dsoc::simclient::failure
