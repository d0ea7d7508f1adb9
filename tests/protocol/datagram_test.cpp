#include "dsoc/protocol/datagram.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

namespace dsoc::protocol {
namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr std::size_t kFragmentHeaderBytes = 10; // u64 tick, u8 index, u8 count

std::string text_of(std::span<const std::uint8_t> bytes) {
    return {bytes.begin(), bytes.end()};
}

/// A ClientHello envelope whose connect token is `token_bytes` bytes long (a real
/// token's 49 by default).
pb::Envelope client_hello(std::size_t token_bytes = 49) {
    pb::Envelope envelope;
    auto* hello = envelope.mutable_client_hello();
    hello->set_protocol_version(kProtocolVersion);
    hello->set_name("datagram test");
    hello->set_connect_token(std::string(token_bytes, '\x5a'));
    return envelope;
}

/// A hello envelope of exactly `size` serialized bytes (its token's length chosen to fit).
pb::Envelope client_hello_of_size(std::size_t size) {
    for (std::size_t token = 0; token < size; ++token) {
        pb::Envelope envelope = client_hello(token);
        if (envelope.ByteSizeLong() == size) {
            return envelope;
        }
    }
    ADD_FAILURE() << "no hello of " << size << " bytes";
    return {};
}

pb::ClientInput client_input(std::uint64_t tick) {
    pb::ClientInput input;
    input.set_tick(tick);
    input.set_move_x(0.25f * static_cast<float>(tick));
    input.set_move_y(-1.0f);
    input.set_view_yaw(90.0f);
    input.set_view_pitch(-10.0f);
    input.set_jump(tick % 2 == 0);
    input.set_watch(static_cast<std::uint32_t>(tick * 3));
    input.set_fire(true);
    return input;
}

Bytes cookie_bytes() {
    Bytes cookie(kCookieBytes);
    for (std::size_t i = 0; i < cookie.size(); ++i) {
        cookie[i] = static_cast<std::uint8_t>(0xc0 + i);
    }
    return cookie;
}

/// Reads a datagram that must be well formed, checking its header.
std::span<const std::uint8_t> body_of(std::span<const std::uint8_t> datagram,
                                      const DatagramHeader& expected) {
    DatagramHeader header;
    std::span<const std::uint8_t> body;
    EXPECT_EQ(read_datagram(datagram, header, body), DatagramError::none);
    EXPECT_EQ(header.kind, expected.kind);
    EXPECT_EQ(header.session, expected.session);
    EXPECT_EQ(header.sequence, expected.sequence);
    return body;
}

/// The datagrams of write_snapshot_datagrams' output: [u16 length][datagram]...
std::vector<Bytes> split_stream(const Bytes& stream) {
    std::vector<Bytes> datagrams;
    std::size_t at = 0;
    while (at < stream.size()) {
        EXPECT_LE(at + 2, stream.size());
        const std::size_t length = stream[at] | static_cast<std::size_t>(stream[at + 1]) << 8;
        at += 2;
        EXPECT_LE(at + length, stream.size());
        datagrams.emplace_back(stream.begin() + static_cast<std::ptrdiff_t>(at),
                               stream.begin() + static_cast<std::ptrdiff_t>(at + length));
        at += length;
    }
    return datagrams;
}

// ---------------------------------------------------------------------------------------
// The header.

TEST(DatagramHeader, IsWrittenInTheDocumentedLayout) {
    Bytes out{9, 9, 9}; // begin_datagram clears what was there
    begin_datagram({DatagramKind::input, 0x0102030405060708u, 0xa1b2c3d4u}, out);
    const Bytes expected{
        0x44, 0x53, 0x4f, 0x43, kDatagramVersion, 6, 0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01,
        0xd4, 0xc3, 0xb2, 0xa1};
    EXPECT_EQ(out, expected);
    EXPECT_EQ(out.size(), kDatagramHeaderBytes);
}

TEST(DatagramHeader, EveryKindRoundTripsWithItsSessionAndSequence) {
    for (std::uint8_t kind = 1; kind <= 7; ++kind) {
        const DatagramHeader written{static_cast<DatagramKind>(kind), 0xfedcba9876543210u + kind,
                                     0xfffffff0u + kind};
        Bytes out;
        begin_datagram(written, out);
        out.push_back(0x77);
        const auto body = body_of(out, written);
        ASSERT_EQ(body.size(), 1u) << "kind " << int{kind};
        EXPECT_EQ(body[0], 0x77);
    }
}

TEST(DatagramHeader, AHeaderAloneAndAFullSizeDatagramAreRead) {
    Bytes out;
    begin_datagram({DatagramKind::message, 1, 1}, out);
    EXPECT_TRUE(body_of(out, {DatagramKind::message, 1, 1}).empty());
    out.resize(kMaxDatagramBytes, 0xee);
    EXPECT_EQ(body_of(out, {DatagramKind::message, 1, 1}).size(),
              kMaxDatagramBytes - kDatagramHeaderBytes);
}

TEST(DatagramHeader, EveryMalformedHeaderGivesItsError) {
    Bytes valid;
    begin_datagram({DatagramKind::message, 5, 5}, valid);
    DatagramHeader header;
    std::span<const std::uint8_t> body;

    EXPECT_EQ(read_datagram({}, header, body), DatagramError::truncated);
    EXPECT_EQ(read_datagram(std::span(valid).first(kDatagramHeaderBytes - 1), header, body),
              DatagramError::truncated);

    Bytes big = valid;
    big.resize(kMaxDatagramBytes + 1);
    EXPECT_EQ(read_datagram(big, header, body), DatagramError::oversized);
    const Bytes big_garbage(kMaxDatagramBytes + 1, 0xff); // size is checked first
    EXPECT_EQ(read_datagram(big_garbage, header, body), DatagramError::oversized);

    for (std::size_t i = 0; i < 4; ++i) {
        Bytes altered = valid;
        altered[i] ^= 0x20; // "dSOC", "DsOC", ...
        EXPECT_EQ(read_datagram(altered, header, body), DatagramError::not_dsoc) << "byte " << i;
    }
    for (const std::uint8_t version : {0, 2, 255}) {
        Bytes altered = valid;
        altered[4] = version;
        EXPECT_EQ(read_datagram(altered, header, body), DatagramError::wrong_version)
            << "version " << int{version};
    }
    for (const std::uint8_t kind : {0, 8, 255}) {
        Bytes altered = valid;
        altered[5] = kind;
        EXPECT_EQ(read_datagram(altered, header, body), DatagramError::unknown_kind)
            << "kind " << int{kind};
    }
}

TEST(DatagramError, EveryErrorHasItsName) {
    EXPECT_STREQ(to_string(DatagramError::none), "none");
    EXPECT_STREQ(to_string(DatagramError::truncated), "truncated");
    EXPECT_STREQ(to_string(DatagramError::oversized), "oversized");
    EXPECT_STREQ(to_string(DatagramError::not_dsoc), "not_dsoc");
    EXPECT_STREQ(to_string(DatagramError::wrong_version), "wrong_version");
    EXPECT_STREQ(to_string(DatagramError::unknown_kind), "unknown_kind");
    EXPECT_STREQ(to_string(DatagramError::bad_body), "bad_body");
}

// ---------------------------------------------------------------------------------------
// The handshake: request, challenge, response, accepted.

TEST(DatagramRequest, IsExactlyMaxDatagramBytesAndCarriesItsHello) {
    const pb::Envelope hello = client_hello();
    Bytes out;
    ASSERT_TRUE(write_request(0x1122334455667788u, hello, out));
    ASSERT_EQ(out.size(), kMaxDatagramBytes); // never smaller: no amplification
    const auto body = body_of(out, {DatagramKind::request, 0x1122334455667788u, 0});
    std::span<const std::uint8_t> cookie;
    std::span<const std::uint8_t> hello_bytes;
    ASSERT_EQ(read_hello_body(DatagramKind::request, body, cookie, hello_bytes),
              DatagramError::none);
    EXPECT_TRUE(cookie.empty());
    EXPECT_EQ(text_of(hello_bytes), hello.SerializeAsString());
    // Everything after the hello is zero padding.
    const std::size_t padding_at = kDatagramHeaderBytes + 2 + hello_bytes.size();
    EXPECT_TRUE(std::all_of(out.begin() + static_cast<std::ptrdiff_t>(padding_at), out.end(),
                            [](std::uint8_t b) { return b == 0; }));
}

TEST(DatagramRequest, ANonzeroPaddingByteAnywhereIsBadBody) {
    Bytes out;
    ASSERT_TRUE(write_request(7, client_hello(), out));
    const std::size_t padding_at =
        kDatagramHeaderBytes + 2 + static_cast<std::size_t>(client_hello().ByteSizeLong());
    ASSERT_LT(padding_at, out.size());
    for (std::size_t i = padding_at; i < out.size(); ++i) {
        Bytes altered = out;
        altered[i] = 1;
        DatagramHeader header;
        std::span<const std::uint8_t> body;
        std::span<const std::uint8_t> cookie;
        std::span<const std::uint8_t> hello;
        ASSERT_EQ(read_datagram(altered, header, body), DatagramError::none);
        EXPECT_EQ(read_hello_body(DatagramKind::request, body, cookie, hello),
                  DatagramError::bad_body)
            << "byte " << i;
    }
}

TEST(DatagramRequest, ARequestShorterThanTheFullSizeOrWithALengthPastItsEndIsTruncated) {
    Bytes out;
    ASSERT_TRUE(write_request(7, client_hello(), out));
    std::span<const std::uint8_t> cookie;
    std::span<const std::uint8_t> hello;
    const auto body = std::span<const std::uint8_t>(out).subspan(kDatagramHeaderBytes);
    EXPECT_EQ(read_hello_body(DatagramKind::request, body.first(body.size() - 1), cookie, hello),
              DatagramError::truncated);
    Bytes long_hello = out;
    long_hello[kDatagramHeaderBytes] = 0xff; // hello length 0xffff: past the body
    long_hello[kDatagramHeaderBytes + 1] = 0xff;
    EXPECT_EQ(
        read_hello_body(DatagramKind::request,
                        std::span<const std::uint8_t>(long_hello).subspan(kDatagramHeaderBytes),
                        cookie, hello),
        DatagramError::truncated);
}

TEST(DatagramRequest, TheLargestHelloThatFitsIsWrittenAndOneByteMoreIsRefused) {
    // The body holds the u16 length and the hello: 1200 - 18 - 2 = 1180 hello bytes.
    constexpr std::size_t kLargest = kMaxDatagramBytes - kDatagramHeaderBytes - 2;
    Bytes out;
    ASSERT_TRUE(write_request(9, client_hello_of_size(kLargest), out));
    EXPECT_EQ(out.size(), kMaxDatagramBytes);
    std::span<const std::uint8_t> cookie;
    std::span<const std::uint8_t> hello;
    EXPECT_EQ(read_hello_body(DatagramKind::request,
                              std::span<const std::uint8_t>(out).subspan(kDatagramHeaderBytes),
                              cookie, hello),
              DatagramError::none);
    EXPECT_EQ(hello.size(), kLargest);

    out.assign(5, 1);
    EXPECT_FALSE(write_request(9, client_hello_of_size(kLargest + 1), out));
    EXPECT_TRUE(out.empty());
}

TEST(DatagramChallenge, CarriesTheCookieAlone) {
    const Bytes cookie = cookie_bytes();
    Bytes out;
    ASSERT_TRUE(write_envelope_datagram({DatagramKind::challenge, 42, 0}, cookie, nullptr, out));
    EXPECT_EQ(out.size(), kDatagramHeaderBytes + kCookieBytes);
    const auto body = body_of(out, {DatagramKind::challenge, 42, 0});
    EXPECT_EQ(Bytes(body.begin(), body.end()), cookie);
}

TEST(DatagramResponse, RoundTripsItsCookieAndHello) {
    const Bytes cookie = cookie_bytes();
    const pb::Envelope hello = client_hello();
    Bytes out;
    ASSERT_TRUE(write_response(0xabcdef, cookie, hello, out));
    EXPECT_EQ(out.size(), kDatagramHeaderBytes + kCookieBytes + 2 + hello.ByteSizeLong());
    const auto body = body_of(out, {DatagramKind::response, 0xabcdef, 0});
    std::span<const std::uint8_t> read_cookie;
    std::span<const std::uint8_t> hello_bytes;
    ASSERT_EQ(read_hello_body(DatagramKind::response, body, read_cookie, hello_bytes),
              DatagramError::none);
    EXPECT_EQ(Bytes(read_cookie.begin(), read_cookie.end()), cookie);
    EXPECT_EQ(text_of(hello_bytes), hello.SerializeAsString());
}

TEST(DatagramResponse, ACookieOfTheWrongSizeOrAHelloTooLargeIsNotWritten) {
    const pb::Envelope hello = client_hello();
    for (const std::size_t size : {std::size_t{0}, kCookieBytes - 1, kCookieBytes + 1}) {
        Bytes out(3, 1);
        EXPECT_FALSE(write_response(1, Bytes(size, 7), hello, out)) << size;
        EXPECT_TRUE(out.empty());
    }
    // Header, cookie and u16 length leave 1200 - 18 - 24 - 2 = 1156 hello bytes.
    constexpr std::size_t kLargest = kMaxDatagramBytes - kDatagramHeaderBytes - kCookieBytes - 2;
    Bytes out;
    ASSERT_TRUE(write_response(1, cookie_bytes(), client_hello_of_size(kLargest), out));
    EXPECT_EQ(out.size(), kMaxDatagramBytes);
    EXPECT_FALSE(write_response(1, cookie_bytes(), client_hello_of_size(kLargest + 1), out));
    EXPECT_TRUE(out.empty());
}

TEST(DatagramResponse, ExtraBytesAreBadBodyAndMissingOnesTruncated) {
    Bytes out;
    ASSERT_TRUE(write_response(1, cookie_bytes(), client_hello(), out));
    std::span<const std::uint8_t> cookie;
    std::span<const std::uint8_t> hello;
    Bytes longer = out;
    longer.push_back(0); // even a zero: a response has no padding
    EXPECT_EQ(read_hello_body(DatagramKind::response,
                              std::span<const std::uint8_t>(longer).subspan(kDatagramHeaderBytes),
                              cookie, hello),
              DatagramError::bad_body);
    const auto body = std::span<const std::uint8_t>(out).subspan(kDatagramHeaderBytes);
    EXPECT_EQ(read_hello_body(DatagramKind::response, body.first(body.size() - 1), cookie, hello),
              DatagramError::truncated);
    EXPECT_EQ(read_hello_body(DatagramKind::response, body.first(kCookieBytes + 1), cookie, hello),
              DatagramError::truncated); // half a length
    EXPECT_EQ(read_hello_body(DatagramKind::response, body.first(kCookieBytes - 1), cookie, hello),
              DatagramError::truncated); // not even the cookie
}

TEST(DatagramHello, OnlyRequestsAndResponsesCarryAHello) {
    Bytes out;
    ASSERT_TRUE(write_response(1, cookie_bytes(), client_hello(), out));
    const auto body = std::span<const std::uint8_t>(out).subspan(kDatagramHeaderBytes);
    for (const DatagramKind kind :
         {DatagramKind::challenge, DatagramKind::accepted, DatagramKind::message,
          DatagramKind::input, DatagramKind::snapshot}) {
        std::span<const std::uint8_t> cookie;
        std::span<const std::uint8_t> hello;
        EXPECT_EQ(read_hello_body(kind, body, cookie, hello), DatagramError::bad_body)
            << "kind " << static_cast<int>(kind);
    }
}

TEST(DatagramAccepted, RoundTripsTheSessionIdAndTheServerHello) {
    pb::Envelope reply;
    reply.mutable_server_hello()->set_client_id(17);
    reply.mutable_server_hello()->set_map_name("oa_dm4");
    const std::uint64_t session = 0x8000000000000001u;
    Bytes prefix;
    for (int i = 0; i < 8; ++i) {
        prefix.push_back(static_cast<std::uint8_t>(session >> (8 * i)));
    }
    Bytes out;
    ASSERT_TRUE(write_envelope_datagram({DatagramKind::accepted, 99, 0}, prefix, &reply, out));
    const auto body = body_of(out, {DatagramKind::accepted, 99, 0});
    std::uint64_t read_session = 0;
    std::span<const std::uint8_t> envelope;
    ASSERT_EQ(read_accepted_body(body, read_session, envelope), DatagramError::none);
    EXPECT_EQ(read_session, session);
    EXPECT_EQ(text_of(envelope), reply.SerializeAsString());
}

TEST(DatagramAccepted, SessionZeroIsBadBodyAndLessThanASessionIdTruncated) {
    std::uint64_t session = 0;
    std::span<const std::uint8_t> envelope;
    const Bytes zero(8 + 3, 0);
    EXPECT_EQ(read_accepted_body(zero, session, envelope), DatagramError::bad_body);
    const Bytes seven(7, 1);
    EXPECT_EQ(read_accepted_body(seven, session, envelope), DatagramError::truncated);
    const Bytes eight(8, 1); // a session id and an empty envelope
    EXPECT_EQ(read_accepted_body(eight, session, envelope), DatagramError::none);
    EXPECT_EQ(session, 0x0101010101010101u);
    EXPECT_TRUE(envelope.empty());
}

TEST(DatagramMessage, RoundTripsAnEnvelope) {
    pb::Envelope ping;
    ping.mutable_ping()->set_nonce(3);
    ping.mutable_ping()->set_client_time_us(123456789);
    Bytes out;
    ASSERT_TRUE(write_envelope_datagram({DatagramKind::message, 5, 77}, {}, &ping, out));
    EXPECT_EQ(out.size(), kDatagramHeaderBytes + ping.ByteSizeLong());
    const auto body = body_of(out, {DatagramKind::message, 5, 77});
    pb::Envelope read;
    ASSERT_TRUE(read.ParseFromArray(body.data(), static_cast<int>(body.size())));
    EXPECT_EQ(read.SerializeAsString(), ping.SerializeAsString());
}

TEST(DatagramMessage, WhatDoesNotFitInMaxDatagramBytesIsNotWritten) {
    pb::Envelope bye;
    bye.mutable_disconnect()->set_reason(pb::DISCONNECT_REASON_SERVER_SHUTDOWN);
    constexpr std::size_t kRoom = kMaxDatagramBytes - kDatagramHeaderBytes;
    for (std::size_t text = 0; bye.ByteSizeLong() < kRoom; ++text) {
        bye.mutable_disconnect()->set_text(std::string(text, 'x'));
    }
    ASSERT_EQ(bye.ByteSizeLong(), kRoom);
    Bytes out;
    ASSERT_TRUE(write_envelope_datagram({DatagramKind::message, 1, 1}, {}, &bye, out));
    EXPECT_EQ(out.size(), kMaxDatagramBytes);
    const Bytes one(1, 0); // the same message after a one-byte prefix: one byte too many
    EXPECT_FALSE(write_envelope_datagram({DatagramKind::message, 1, 1}, one, &bye, out));
    EXPECT_TRUE(out.empty());
    const Bytes huge_prefix(kRoom + 1, 0);
    EXPECT_FALSE(
        write_envelope_datagram({DatagramKind::challenge, 1, 0}, huge_prefix, nullptr, out));
    EXPECT_TRUE(out.empty());
}

// ---------------------------------------------------------------------------------------
// Inputs.

TEST(DatagramInput, OneToThreeInputsRoundTripNewestFirst) {
    for (std::size_t count = 1; count <= kMaxRedundantInputs; ++count) {
        SCOPED_TRACE("count " + std::to_string(count));
        std::vector<pb::ClientInput> inputs;
        for (std::size_t i = 0; i < count; ++i) {
            inputs.push_back(client_input(100 - i));
        }
        const std::uint64_t ack = count == 1 ? 0 : 0xfffffffffffffff0u + count;
        Bytes out;
        ASSERT_TRUE(write_input({DatagramKind::input, 12, 34}, ack, inputs, out));
        EXPECT_LE(out.size(), kMaxDatagramBytes);
        InputBody read;
        ASSERT_EQ(read_input_body(body_of(out, {DatagramKind::input, 12, 34}), read),
                  DatagramError::none);
        EXPECT_EQ(read.ack, ack);
        ASSERT_EQ(read.count, count);
        for (std::size_t i = 0; i < count; ++i) {
            pb::ClientInput parsed;
            ASSERT_TRUE(parsed.ParseFromArray(read.inputs[i].data(),
                                              static_cast<int>(read.inputs[i].size())));
            EXPECT_EQ(parsed.tick(), 100 - i);
            EXPECT_EQ(parsed.SerializeAsString(), inputs[i].SerializeAsString());
        }
    }
}

TEST(DatagramInput, NoInputsOrMoreThanThreeAreNotWritten) {
    Bytes out(4, 1);
    EXPECT_FALSE(write_input({DatagramKind::input, 1, 1}, 0, {}, out));
    EXPECT_TRUE(out.empty());
    const std::vector<pb::ClientInput> four{client_input(4), client_input(3), client_input(2),
                                            client_input(1)};
    out.assign(4, 1);
    EXPECT_FALSE(write_input({DatagramKind::input, 1, 1}, 0, four, out));
    EXPECT_TRUE(out.empty());
}

TEST(DatagramInput, ACountOfZeroOrMoreThanThreeIsBadBody) {
    const std::vector<pb::ClientInput> three{client_input(3), client_input(2), client_input(1)};
    Bytes out;
    ASSERT_TRUE(write_input({DatagramKind::input, 1, 1}, 5, three, out));
    const std::size_t count_at = kDatagramHeaderBytes + 8;
    ASSERT_EQ(out[count_at], 3);
    for (const std::uint8_t count : {0, 4, 255}) {
        Bytes altered = out;
        altered[count_at] = count;
        InputBody read;
        EXPECT_EQ(read_input_body(
                      std::span<const std::uint8_t>(altered).subspan(kDatagramHeaderBytes), read),
                  DatagramError::bad_body)
            << "count " << int{count};
    }
    // An ack and a count of 0, nothing after: no input at all.
    InputBody read;
    EXPECT_EQ(read_input_body(Bytes(9, 0), read), DatagramError::bad_body);
}

TEST(DatagramInput, ExtraBytesAreBadBodyAndMissingOnesTruncated) {
    const std::vector<pb::ClientInput> two{client_input(2), client_input(1)};
    Bytes out;
    ASSERT_TRUE(write_input({DatagramKind::input, 1, 1}, 5, two, out));
    const auto body = std::span<const std::uint8_t>(out).subspan(kDatagramHeaderBytes);
    InputBody read;
    Bytes longer(body.begin(), body.end());
    longer.push_back(0);
    EXPECT_EQ(read_input_body(longer, read), DatagramError::bad_body);
    EXPECT_EQ(read_input_body(body.first(body.size() - 1), read), DatagramError::truncated);
    EXPECT_EQ(read_input_body(body.first(8), read), DatagramError::truncated);  // no count
    EXPECT_EQ(read_input_body(body.first(10), read), DatagramError::truncated); // half a length
    // The first input's length says more than the body holds.
    Bytes lying(body.begin(), body.end());
    lying[9] = 0xff;
    lying[10] = 0x7f;
    EXPECT_EQ(read_input_body(lying, read), DatagramError::truncated);
}

TEST(DatagramInput, EmptyInputsRoundTripAsZeroLengths) {
    const std::vector<pb::ClientInput> empty(3); // every field default: 0 bytes each
    Bytes out;
    ASSERT_TRUE(write_input({DatagramKind::input, 1, 1}, 0, empty, out));
    EXPECT_EQ(out.size(), kDatagramHeaderBytes + 9 + 3 * 2);
    InputBody read;
    ASSERT_EQ(
        read_input_body(std::span<const std::uint8_t>(out).subspan(kDatagramHeaderBytes), read),
        DatagramError::none);
    EXPECT_EQ(read.count, 3u);
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_TRUE(read.inputs[i].empty());
    }
}

// ---------------------------------------------------------------------------------------
// Snapshots: fragments, the split and the reassembly.

/// A snapshot body: the fragment header and `bytes` bytes.
Bytes snapshot_body(std::uint64_t tick, std::uint8_t index, std::uint8_t count, std::size_t bytes) {
    Bytes body;
    for (int i = 0; i < 8; ++i) {
        body.push_back(static_cast<std::uint8_t>(tick >> (8 * i)));
    }
    body.push_back(index);
    body.push_back(count);
    body.resize(body.size() + bytes, 0x3c);
    return body;
}

TEST(SnapshotFragment, AValidFragmentIsRead) {
    SnapshotFragment fragment;
    const Bytes last = snapshot_body(0x0102030405060708u, 2, 3, 17);
    ASSERT_EQ(read_snapshot_body(last, fragment), DatagramError::none);
    EXPECT_EQ(fragment.tick, 0x0102030405060708u);
    EXPECT_EQ(fragment.index, 2);
    EXPECT_EQ(fragment.count, 3);
    EXPECT_EQ(fragment.bytes.size(), 17u);
    EXPECT_EQ(fragment.bytes.data(), last.data() + kFragmentHeaderBytes); // a view, no copy
    EXPECT_EQ(read_snapshot_body(snapshot_body(1, 0, 2, kSnapshotFragmentBytes), fragment),
              DatagramError::none);
    EXPECT_EQ(read_snapshot_body(snapshot_body(1, 1, 2, kSnapshotFragmentBytes), fragment),
              DatagramError::none); // a full last fragment
    EXPECT_EQ(read_snapshot_body(snapshot_body(1, 63, 64, 1), fragment), DatagramError::none);
}

TEST(SnapshotFragment, EveryInconsistentFragmentIsBadBody) {
    SnapshotFragment fragment;
    EXPECT_EQ(read_snapshot_body(Bytes(kFragmentHeaderBytes - 1, 1), fragment),
              DatagramError::truncated);
    const auto bad = [&](const Bytes& body) { return read_snapshot_body(body, fragment); };
    EXPECT_EQ(bad(snapshot_body(1, 0, 0, 5)), DatagramError::bad_body); // no fragments
    // Each of these is well formed but for the one thing it says.
    EXPECT_EQ(bad(snapshot_body(1, 0, 65, kSnapshotFragmentBytes)), DatagramError::bad_body);
    EXPECT_EQ(bad(snapshot_body(1, 64, 65, 5)), DatagramError::bad_body); // too many
    EXPECT_EQ(bad(snapshot_body(1, 3, 3, kSnapshotFragmentBytes)), DatagramError::bad_body);
    EXPECT_EQ(bad(snapshot_body(1, 3, 3, 5)), DatagramError::bad_body); // index past count
    EXPECT_EQ(bad(snapshot_body(1, 200, 3, 5)), DatagramError::bad_body);
    EXPECT_EQ(bad(snapshot_body(0, 0, 1, 5)), DatagramError::bad_body); // tick 0
    EXPECT_EQ(bad(snapshot_body(1, 0, 1, 0)), DatagramError::bad_body); // no bytes
    // Every fragment but the last is exactly kSnapshotFragmentBytes; the last at most that.
    EXPECT_EQ(bad(snapshot_body(1, 0, 2, kSnapshotFragmentBytes - 1)), DatagramError::bad_body);
    EXPECT_EQ(bad(snapshot_body(1, 0, 2, kSnapshotFragmentBytes + 1)), DatagramError::bad_body);
    EXPECT_EQ(bad(snapshot_body(1, 1, 2, kSnapshotFragmentBytes + 1)), DatagramError::bad_body);
}

TEST(SnapshotDatagrams, AnEnvelopeTooLargeOrEmptyOrOfTickZeroGivesNoDatagramsAndWritesNothing) {
    const Bytes before{1, 2, 3};
    Bytes out = before;
    EXPECT_EQ(write_snapshot_datagrams(1, 1, 1, Bytes(kMaxSnapshotBytes + 1, 9), out), 0u);
    EXPECT_EQ(out, before);
    EXPECT_EQ(write_snapshot_datagrams(1, 1, 1, {}, out), 0u);
    EXPECT_EQ(out, before);
    // A receiver refuses tick 0 (read_snapshot_body): it is never written either.
    EXPECT_EQ(write_snapshot_datagrams(1, 1, 0, Bytes(10, 9), out), 0u);
    EXPECT_EQ(out, before);
}

TEST(SnapshotDatagrams, FragmentsAreFullSizeButTheLastAndNumberedFromTheFirstSequence) {
    constexpr std::size_t F = kSnapshotFragmentBytes;
    for (const std::size_t size : {std::size_t{1}, F - 1, F, F + 1, 2 * F, 10 * F + 7,
                                   kMaxSnapshotBytes - 1, kMaxSnapshotBytes}) {
        SCOPED_TRACE("envelope of " + std::to_string(size) + " bytes");
        Bytes envelope(size);
        for (std::size_t i = 0; i < size; ++i) {
            envelope[i] = static_cast<std::uint8_t>(i * 31 + i / 251);
        }
        Bytes out{0xaa}; // appended after what is there
        const std::size_t count = write_snapshot_datagrams(0x5e55, 1000, 77, envelope, out);
        ASSERT_EQ(count, (size + F - 1) / F);
        ASSERT_LE(count, kMaxSnapshotFragments);
        EXPECT_EQ(out[0], 0xaa);
        const auto datagrams = split_stream(Bytes(out.begin() + 1, out.end()));
        ASSERT_EQ(datagrams.size(), count);
        Bytes joined;
        for (std::size_t i = 0; i < count; ++i) {
            const Bytes& datagram = datagrams[i];
            EXPECT_LE(datagram.size(), kMaxDatagramBytes);
            if (i + 1 < count) {
                EXPECT_EQ(datagram.size(), kMaxDatagramBytes);
            }
            const auto body = body_of(
                datagram, {DatagramKind::snapshot, 0x5e55, 1000 + static_cast<std::uint32_t>(i)});
            SnapshotFragment fragment;
            ASSERT_EQ(read_snapshot_body(body, fragment), DatagramError::none);
            EXPECT_EQ(fragment.tick, 77u);
            EXPECT_EQ(fragment.index, i);
            EXPECT_EQ(fragment.count, count);
            joined.insert(joined.end(), fragment.bytes.begin(), fragment.bytes.end());
        }
        EXPECT_EQ(joined, envelope);
    }
}

TEST(SnapshotAssembler, AssemblesOneTickInAnyOrderAndIgnoresItAfterwards) {
    const Bytes envelope(2 * kSnapshotFragmentBytes + 5, 0x42);
    Bytes stream;
    ASSERT_EQ(write_snapshot_datagrams(1, 1, 10, envelope, stream), 3u);
    const auto datagrams = split_stream(stream);
    std::vector<SnapshotFragment> fragments(3);
    for (std::size_t i = 0; i < 3; ++i) {
        ASSERT_EQ(read_snapshot_body(
                      std::span<const std::uint8_t>(datagrams[i]).subspan(kDatagramHeaderBytes),
                      fragments[i]),
                  DatagramError::none);
    }
    SnapshotAssembler assembler;
    std::span<const std::uint8_t> out;
    using R = SnapshotAssembler::Result;
    EXPECT_EQ(assembler.add(fragments[2], out), R::incomplete);
    EXPECT_EQ(assembler.add(fragments[2], out), R::ignored); // a duplicate
    EXPECT_EQ(assembler.add(fragments[0], out), R::incomplete);
    EXPECT_EQ(assembler.add(fragments[1], out), R::complete);
    EXPECT_EQ(Bytes(out.begin(), out.end()), envelope);
    EXPECT_EQ(assembler.add(fragments[1], out), R::ignored); // already completed
    EXPECT_EQ(assembler.abandoned(), 0u);
}

TEST(SnapshotAssembler, ANewerTickAbandonsTheOneInProgressAndOlderTicksAreIgnored) {
    using R = SnapshotAssembler::Result;
    SnapshotAssembler assembler;
    std::span<const std::uint8_t> out;
    const Bytes full = snapshot_body(5, 0, 2, kSnapshotFragmentBytes);
    const Bytes last = snapshot_body(5, 1, 2, 3);
    const Bytes newer = snapshot_body(6, 0, 1, 4);
    const Bytes other_count = snapshot_body(7, 0, 2, kSnapshotFragmentBytes);
    // A fragment of tick 7 whose count disagrees (with 2 fragments, index 1 would be the
    // last; with 3 it is a full one): it must not be taken, let alone written past the end.
    const Bytes other_count_middle = snapshot_body(7, 1, 3, kSnapshotFragmentBytes);
    SnapshotFragment f;
    ASSERT_EQ(read_snapshot_body(full, f), DatagramError::none);
    EXPECT_EQ(assembler.add(f, out), R::incomplete);
    ASSERT_EQ(read_snapshot_body(newer, f), DatagramError::none);
    EXPECT_EQ(assembler.add(f, out), R::complete); // tick 5 is given up
    EXPECT_EQ(out.size(), 4u);
    EXPECT_EQ(assembler.abandoned(), 1u);
    ASSERT_EQ(read_snapshot_body(last, f), DatagramError::none);
    EXPECT_EQ(assembler.add(f, out), R::ignored); // tick 5 is older
    ASSERT_EQ(read_snapshot_body(other_count, f), DatagramError::none);
    EXPECT_EQ(assembler.add(f, out), R::incomplete);
    ASSERT_EQ(read_snapshot_body(other_count_middle, f), DatagramError::none);
    EXPECT_EQ(assembler.add(f, out), R::ignored); // disagrees on the count
    EXPECT_EQ(assembler.abandoned(), 1u);         // tick 6 completed, tick 7 still in progress
}

/// The assembler's contract, simply: the newest tick started is assembled; a fragment of
/// an older tick, of a completed tick, or a duplicate is ignored.
struct AssemblerModel {
    std::uint64_t tick = 0;
    bool done = false;
    std::set<std::uint8_t> held;
    std::uint64_t abandoned = 0;

    SnapshotAssembler::Result add(std::uint64_t fragment_tick, std::uint8_t index,
                                  std::uint8_t count) {
        using R = SnapshotAssembler::Result;
        if (fragment_tick < tick || (fragment_tick == tick && done)) {
            return R::ignored;
        }
        if (fragment_tick > tick) {
            abandoned += tick != 0 && !done ? 1 : 0;
            tick = fragment_tick;
            held.clear();
            done = false;
        }
        if (!held.insert(index).second) {
            return R::ignored;
        }
        done = held.size() == count;
        return done ? R::complete : R::incomplete;
    }
};

TEST(SnapshotAssembler,
     ShuffledDuplicatedAndDroppedFragmentsCompleteExactlyWhenTheNewestTickIsWhole) {
    constexpr std::size_t F = kSnapshotFragmentBytes;
    const std::array<std::size_t, 8> edges{
        1, F - 1, F, F + 1, 2 * F, 63 * F + 1, kMaxSnapshotBytes - 1, kMaxSnapshotBytes};
    std::size_t completes = 0;
    std::size_t newest_whole = 0;
    std::size_t newest_lost = 0;
    for (const std::uint32_t seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        std::mt19937_64 rng(seed);
        for (int trial = 0; trial < 60; ++trial) {
            SCOPED_TRACE("trial " + std::to_string(trial));
            const auto pick = [&](std::uint64_t n) { return rng() % n; };
            // An older tick, the tick of interest and a newer one, each a random envelope.
            const std::uint64_t tick = 2 + pick(1'000'000);
            const std::array<std::uint64_t, 3> ticks{tick - 1 - pick(tick - 1), tick,
                                                     tick + 1 + pick(5)};
            const double drop = std::array{0.0, 0.02, 0.2}[pick(3)];
            const double duplicate = std::array{0.0, 0.3}[pick(2)];
            std::map<std::uint64_t, Bytes> envelopes;
            std::map<std::uint64_t, std::set<std::uint8_t>> delivered; // distinct indices
            std::map<std::uint64_t, std::size_t> fragment_count;
            std::vector<std::vector<Bytes>> blocks;
            std::uint32_t sequence = 1 + static_cast<std::uint32_t>(pick(1000));
            for (const std::uint64_t t : ticks) {
                const std::size_t size =
                    pick(4) == 0 ? edges[pick(edges.size())] : 1 + pick(kMaxSnapshotBytes);
                Bytes& envelope = envelopes[t];
                envelope.resize(size);
                for (auto& b : envelope) {
                    b = static_cast<std::uint8_t>(rng());
                }
                Bytes stream;
                const std::size_t count =
                    write_snapshot_datagrams(42, sequence, t, envelope, stream);
                ASSERT_EQ(count, (size + F - 1) / F);
                sequence += static_cast<std::uint32_t>(count);
                fragment_count[t] = count;
                std::vector<Bytes> block;
                for (Bytes& datagram : split_stream(stream)) {
                    ASSERT_LE(datagram.size(), kMaxDatagramBytes);
                    if (std::uniform_real_distribution<double>(0, 1)(rng) < drop) {
                        continue;
                    }
                    const std::uint8_t index = datagram[kDatagramHeaderBytes + 8];
                    delivered[t].insert(index);
                    if (std::uniform_real_distribution<double>(0, 1)(rng) < duplicate) {
                        block.push_back(datagram);
                    }
                    block.push_back(std::move(datagram));
                }
                std::shuffle(block.begin(), block.end(), rng);
                blocks.push_back(std::move(block));
            }
            // The ticks' blocks in a random order, either one after the other or all mixed.
            std::shuffle(blocks.begin(), blocks.end(), rng);
            std::vector<Bytes> delivery;
            for (auto& block : blocks) {
                delivery.insert(delivery.end(), block.begin(), block.end());
            }
            if (pick(2) == 0) {
                std::shuffle(delivery.begin(), delivery.end(), rng);
            }

            SnapshotAssembler assembler;
            AssemblerModel model;
            std::uint64_t newest_started = 0;
            std::uint64_t last_completed = 0;
            for (const Bytes& datagram : delivery) {
                DatagramHeader header;
                std::span<const std::uint8_t> body;
                ASSERT_EQ(read_datagram(datagram, header, body), DatagramError::none);
                ASSERT_EQ(header.kind, DatagramKind::snapshot);
                SnapshotFragment fragment;
                ASSERT_EQ(read_snapshot_body(body, fragment), DatagramError::none);
                newest_started = std::max(newest_started, fragment.tick);
                std::span<const std::uint8_t> envelope;
                const auto expected = model.add(fragment.tick, fragment.index, fragment.count);
                const auto result = assembler.add(fragment, envelope);
                ASSERT_EQ(result, expected) << "tick " << fragment.tick << " fragment "
                                            << int{fragment.index} << " of " << int{fragment.count};
                if (result == SnapshotAssembler::Result::complete) {
                    ++completes;
                    last_completed = fragment.tick;
                    EXPECT_EQ(fragment.tick, newest_started);
                    ASSERT_EQ(Bytes(envelope.begin(), envelope.end()), envelopes[fragment.tick]);
                }
                EXPECT_EQ(assembler.abandoned(), model.abandoned);
            }
            // Once every fragment is in: the newest tick that started is complete exactly
            // when none of its fragments was lost.
            if (newest_started != 0) {
                const bool whole =
                    delivered[newest_started].size() == fragment_count[newest_started];
                EXPECT_EQ(last_completed == newest_started, whole);
                ++(whole ? newest_whole : newest_lost);
            }
        }
    }
    // The trials reach both outcomes and assemble many snapshots.
    EXPECT_GT(newest_whole, 100u);
    EXPECT_GT(newest_lost, 50u);
    EXPECT_GT(completes, 200u);
}

// ---------------------------------------------------------------------------------------
// The replay window.

TEST(ReplayWindow, ZeroIsNeverAccepted) {
    ReplayWindow window;
    EXPECT_FALSE(window.accept(0));
    EXPECT_TRUE(window.accept(1));
    EXPECT_FALSE(window.accept(0));
    EXPECT_EQ(window.newest(), 1u);
}

TEST(ReplayWindow, RemembersTheLast64AndForgetsAllBehindAJumpOf64) {
    ReplayWindow window;
    EXPECT_TRUE(window.accept(1));
    EXPECT_TRUE(window.accept(64)); // 1 is 63 behind: still known
    EXPECT_FALSE(window.accept(1));
    EXPECT_TRUE(window.accept(2));
    EXPECT_FALSE(window.accept(64));

    ReplayWindow jumped;
    EXPECT_TRUE(jumped.accept(1));
    EXPECT_TRUE(jumped.accept(65)); // 1 is 64 behind: too late to tell
    EXPECT_FALSE(jumped.accept(1));
    EXPECT_TRUE(jumped.accept(2)); // 63 behind, never seen
    EXPECT_TRUE(jumped.accept(60'000));
    EXPECT_FALSE(jumped.accept(65));
    EXPECT_TRUE(jumped.accept(60'000 - 63));
    EXPECT_FALSE(jumped.accept(60'000 - 64));
}

TEST(ReplayWindow, RefusesAJumpFurtherAheadThanAnHonestSenderSkips) {
    ReplayWindow window;
    EXPECT_TRUE(window.accept(100)); // the first counts from 0
    EXPECT_FALSE(window.accept(100 + ReplayWindow::kMaxSequenceJump + 1));
    EXPECT_FALSE(window.accept(0xffffffffu)); // a forged top would lock the sender out
    EXPECT_EQ(window.newest(), 100u);
    EXPECT_TRUE(window.accept(100 + ReplayWindow::kMaxSequenceJump));
}

TEST(ReplayWindow, TheFirstSequenceIsAJumpFromZeroSoAForgedFirstCannotLockTheSenderOut) {
    ReplayWindow forged;
    EXPECT_FALSE(forged.accept(0xfffffff0u)); // a session's first datagram, forged
    EXPECT_FALSE(forged.accept(ReplayWindow::kMaxSequenceJump + 1));
    EXPECT_EQ(forged.newest(), 0u);
    EXPECT_TRUE(forged.accept(1)); // the sender's own first still counts
    ReplayWindow far;
    EXPECT_TRUE(far.accept(ReplayWindow::kMaxSequenceJump)); // as far as the rule goes
}

/// `window` moved on to `sequence` in the largest steps it takes; `taken` (if any) gets
/// the sequences it took.
void climb_to(ReplayWindow& window, std::uint32_t sequence,
              std::set<std::uint32_t>* taken = nullptr) {
    while (window.newest() < sequence) {
        const std::uint32_t left = sequence - window.newest();
        const std::uint32_t next = window.newest() + std::min(left, ReplayWindow::kMaxSequenceJump);
        ASSERT_TRUE(window.accept(next));
        if (taken != nullptr) {
            taken->insert(next);
        }
    }
}

TEST(ReplayWindow, WorksAtTheTopOfTheSequenceRange) {
    constexpr std::uint32_t kTop = 0xffffffffu;
    ReplayWindow window;
    climb_to(window, kTop - 2);
    EXPECT_TRUE(window.accept(kTop - 1));
    EXPECT_TRUE(window.accept(kTop));
    EXPECT_FALSE(window.accept(kTop));
    EXPECT_FALSE(window.accept(kTop - 1));
    EXPECT_TRUE(window.accept(kTop - 63));
    EXPECT_FALSE(window.accept(kTop - 64));
    EXPECT_FALSE(window.accept(1)); // no wrap-around
    EXPECT_EQ(window.newest(), kTop);
}

TEST(ReplayWindow, AgreesWithASetOfEverySequenceTaken) {
    // The contract: accept s iff s != 0, s was never accepted, and s is less than 64
    // behind the newest or newer by at most kMaxSequenceJump (the newest counting as 0
    // before the first).
    constexpr std::int64_t kTop = 0xffffffff;
    std::size_t accepted = 0;
    std::size_t refused = 0;
    for (const std::uint32_t seed : {1u, 2u, 3u, 4u}) {
        std::mt19937_64 rng(seed);
        const auto pick = [&](std::int64_t lo, std::int64_t hi) {
            return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng);
        };
        for (const std::int64_t start : {std::int64_t{0}, std::int64_t{100'000}, kTop - 3000}) {
            for (int run = 0; run < 8; ++run) {
                SCOPED_TRACE("seed " + std::to_string(seed) + " start " + std::to_string(start) +
                             " run " + std::to_string(run));
                const bool wild = run % 4 == 0; // also jumps anywhere, and to the very top
                ReplayWindow window;
                std::set<std::uint32_t> taken;
                climb_to(window, static_cast<std::uint32_t>(start), &taken); // (from 0: none)
                std::int64_t newest = window.newest(); // the model's: the window's newest()
                for (int step = 0; step < 2000; ++step) {
                    const std::int64_t from = std::max(newest, start);
                    const std::int64_t r = pick(0, 999);
                    std::int64_t s = 0;
                    if (r < 450) {
                        s = from + pick(-70, 3); // around the newest: replays, late, in-window
                    } else if (r < 800 || (r >= 990 && !wild)) {
                        s = from + pick(1, 3); // in order
                    } else if (r < 880) {
                        constexpr std::array<std::int64_t, 6> kJumps{63, 64, 65, 100, 1000, 70'000};
                        s = from + kJumps[static_cast<std::size_t>(pick(0, 5))];
                    } else if (r < 960) {
                        s = newest - pick(60, 68); // right at the window's edge
                    } else if (r < 990) {
                        s = 0;
                    } else if (r < 995) {
                        s = kTop - pick(0, 80); // near the top of the range
                    } else {
                        s = pick(0, kTop);
                    }
                    s = std::clamp<std::int64_t>(s, 0, kTop);
                    const auto sequence = static_cast<std::uint32_t>(s);
                    const bool expected = sequence != 0 && taken.count(sequence) == 0 &&
                                          (s > newest ? s - newest <= ReplayWindow::kMaxSequenceJump
                                                      : newest - s < 64);
                    ASSERT_EQ(window.accept(sequence), expected)
                        << "step " << step << " sequence " << sequence << " newest " << newest;
                    if (expected) {
                        taken.insert(sequence);
                        newest = std::max(newest, s);
                        ++accepted;
                    } else {
                        ++refused;
                    }
                    ASSERT_EQ(window.newest(), static_cast<std::uint32_t>(newest));
                }
            }
        }
    }
    EXPECT_GT(accepted, 50'000u);
    EXPECT_GT(refused, 20'000u);
}

} // namespace
} // namespace dsoc::protocol
