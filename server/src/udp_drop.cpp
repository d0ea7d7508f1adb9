#include "dsoc/server/udp_drop.hpp"

namespace dsoc::server {

const char* udp_drop_name(UdpDrop drop) noexcept {
    switch (drop) {
    case UdpDrop::truncated:
        return "truncated";
    case UdpDrop::oversized:
        return "oversized";
    case UdpDrop::not_dsoc:
        return "not_dsoc";
    case UdpDrop::wrong_version:
        return "wrong_version";
    case UdpDrop::unknown_kind:
        return "unknown_kind";
    case UdpDrop::bad_body:
        return "bad_body";
    case UdpDrop::unexpected_kind:
        return "unexpected_kind";
    case UdpDrop::unknown_session:
        return "unknown_session";
    case UdpDrop::closed_session:
        return "closed_session";
    case UdpDrop::wrong_source:
        return "wrong_source";
    case UdpDrop::replayed:
        return "replayed";
    case UdpDrop::rate_limited:
        return "rate_limited";
    case UdpDrop::forged_cookie:
        return "forged_cookie";
    case UdpDrop::expired_cookie:
        return "expired_cookie";
    case UdpDrop::over_challenge_rate:
        return "over_challenge_rate";
    case UdpDrop::count_:
        break;
    }
    return "unknown";
}

UdpDrop udp_drop_of(protocol::DatagramError error) noexcept {
    switch (error) {
    case protocol::DatagramError::truncated:
        return UdpDrop::truncated;
    case protocol::DatagramError::oversized:
        return UdpDrop::oversized;
    case protocol::DatagramError::not_dsoc:
        return UdpDrop::not_dsoc;
    case protocol::DatagramError::wrong_version:
        return UdpDrop::wrong_version;
    case protocol::DatagramError::unknown_kind:
        return UdpDrop::unknown_kind;
    case protocol::DatagramError::none:
    case protocol::DatagramError::bad_body:
        break;
    }
    return UdpDrop::bad_body;
}

} // namespace dsoc::server
