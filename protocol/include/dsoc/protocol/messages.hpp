#pragma once
// The protobuf messages of the wire protocol (generated from proto/dsoc.proto).

#include "dsoc/protocol/dsoc.pb.h" // IWYU pragma: export

namespace dsoc::protocol {

namespace pb = dsoc::protocol::v1;

/// The protocol version this build speaks; peers with another version are refused.
inline constexpr std::uint32_t kProtocolVersion = pb::PROTOCOL_VERSION_CURRENT;

} // namespace dsoc::protocol
