#include "dsoc/simclient/failure_reason.hpp"

#include <boost/asio/error.hpp>

namespace dsoc::simclient::failure {

namespace pb = protocol::pb;

std::string_view of_connect_error(const boost::system::error_code& ec, bool resolving) {
    namespace error = boost::asio::error;
    if (resolving) {
        if (ec == error::host_not_found || ec == error::host_not_found_try_again ||
            ec == error::no_data || ec == error::no_recovery || ec == error::service_not_found) {
            return unresolvable;
        }
        return connect_error;
    }
    if (ec == error::connection_refused) {
        return refused;
    }
    if (ec == error::timed_out) {
        return timeout;
    }
    return connect_error;
}

std::string_view of_disconnect(pb::DisconnectReason reason) {
    switch (reason) {
    case pb::DISCONNECT_REASON_UNSPECIFIED:
    case pb::DISCONNECT_REASON_CLIENT_QUIT:
        return {};
    case pb::DISCONNECT_REASON_UNAUTHORIZED:
        return unauthorized;
    case pb::DISCONNECT_REASON_VERSION_MISMATCH:
        return version_mismatch;
    case pb::DISCONNECT_REASON_SERVER_SHUTDOWN:
        return server_shutdown;
    case pb::DISCONNECT_REASON_WORLD_RESTARTED:
        return world_restarted;
    case pb::DISCONNECT_REASON_TRY_AGAIN:
        return try_again;
    default:
        return dropped_by_server;
    }
}

} // namespace dsoc::simclient::failure
