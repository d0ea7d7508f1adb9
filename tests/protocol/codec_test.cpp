#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/framing.hpp"

#include <gtest/gtest.h>

namespace dsoc::protocol {
namespace {

TEST(Codec, SnapshotRoundTripsThroughAFrame) {
    pb::Envelope sent;
    auto& snap = *sent.mutable_snapshot();
    snap.set_server_tick(99);
    auto& e = *snap.add_enter();
    e.set_id(5);
    e.set_x(-12);
    snap.add_leave(7);
    std::vector<std::uint8_t> stream;
    const std::size_t n = encode_frame(sent, stream);
    EXPECT_EQ(n, stream.size());

    FrameDecoder decoder;
    decoder.feed(stream);
    std::span<const std::uint8_t> payload;
    ASSERT_EQ(decoder.next(payload), FrameDecoder::Status::frame);
    pb::Envelope received;
    ASSERT_EQ(decode_payload(payload, received), DecodeError::none);
    ASSERT_EQ(received.body_case(), pb::Envelope::kSnapshot);
    EXPECT_EQ(received.snapshot().server_tick(), 99u);
    EXPECT_EQ(received.snapshot().enter(0).x(), -12);
    EXPECT_EQ(received.snapshot().leave(0), 7u);
}

TEST(Codec, MalformedAndEmptyPayloadsAreNamed) {
    pb::Envelope message;
    const std::vector<std::uint8_t> garbage(16, 0xff);
    EXPECT_EQ(decode_payload(garbage, message), DecodeError::malformed);
    EXPECT_EQ(decode_payload({}, message), DecodeError::empty_envelope);
    EXPECT_STREQ(to_string(DecodeError::malformed), "malformed");
}

TEST(Codec, TruncatedMessageIsMalformed) {
    pb::Envelope sent;
    sent.mutable_client_hello()->set_name("a name long enough to truncate");
    const std::string bytes = sent.SerializeAsString();
    const std::vector<std::uint8_t> truncated(bytes.begin(), bytes.end() - 3);
    pb::Envelope message;
    EXPECT_EQ(decode_payload(truncated, message), DecodeError::malformed);
}

TEST(Codec, DisconnectReasonNamesAreReadable) {
    EXPECT_EQ(disconnect_reason_name(pb::DISCONNECT_REASON_FRAME_TOO_LARGE), "frame_too_large");
    EXPECT_EQ(disconnect_reason_name(pb::DISCONNECT_REASON_SERVER_SHUTDOWN), "server_shutdown");
    EXPECT_EQ(disconnect_reason_name(static_cast<pb::DisconnectReason>(999)), "unknown_999");
}

} // namespace
} // namespace dsoc::protocol
