#include "dsoc/protocol/framing.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

namespace dsoc::protocol {
namespace {

std::vector<std::uint8_t> bytes_of(const std::string& s) {
    return {s.begin(), s.end()};
}

/// Feeds `stream` in pieces cut at `cuts` and collects every frame payload.
std::vector<std::vector<std::uint8_t>> decode_in_pieces(const std::vector<std::uint8_t>& stream,
                                                        const std::vector<std::size_t>& cuts,
                                                        FrameDecoder& decoder) {
    std::vector<std::vector<std::uint8_t>> frames;
    std::size_t begin = 0;
    auto drain = [&] {
        std::span<const std::uint8_t> payload;
        while (decoder.next(payload) == FrameDecoder::Status::frame) {
            frames.emplace_back(payload.begin(), payload.end());
        }
    };
    for (std::size_t cut : cuts) {
        decoder.feed(std::span(stream).subspan(begin, cut - begin));
        drain();
        begin = cut;
    }
    decoder.feed(std::span(stream).subspan(begin));
    drain();
    return frames;
}

TEST(Framing, HeaderIsLittleEndianLength) {
    std::vector<std::uint8_t> out;
    append_frame(out, bytes_of("abc"));
    ASSERT_EQ(out.size(), 7u);
    EXPECT_EQ(out[0], 3);
    EXPECT_EQ(out[1], 0);
    EXPECT_EQ(out[2], 0);
    EXPECT_EQ(out[3], 0);
    EXPECT_EQ(out[4], 'a');

    std::uint8_t header[4];
    write_frame_header(header, 0x01020304u);
    EXPECT_EQ(header[0], 0x04);
    EXPECT_EQ(header[3], 0x01);
}

TEST(Framing, RoundTripsSeveralFramesInOneRead) {
    std::vector<std::uint8_t> stream;
    const std::vector<std::string> payloads = {"hello", "", std::string(1000, 'x'), "z"};
    for (const auto& p : payloads) {
        append_frame(stream, bytes_of(p));
    }
    FrameDecoder decoder;
    const auto frames = decode_in_pieces(stream, {}, decoder);
    ASSERT_EQ(frames.size(), payloads.size());
    for (std::size_t i = 0; i < payloads.size(); ++i) {
        EXPECT_EQ(frames[i], bytes_of(payloads[i])) << "frame " << i;
    }
    EXPECT_EQ(decoder.buffered_bytes(), 0u);
}

TEST(Framing, SplitAtEveryByteBoundary) {
    std::vector<std::uint8_t> stream;
    append_frame(stream, bytes_of("first frame"));
    append_frame(stream, bytes_of("second"));
    for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
        FrameDecoder decoder;
        const auto frames = decode_in_pieces(stream, {cut}, decoder);
        ASSERT_EQ(frames.size(), 2u) << "cut at " << cut;
        EXPECT_EQ(frames[0], bytes_of("first frame"));
        EXPECT_EQ(frames[1], bytes_of("second"));
    }
}

TEST(Framing, OneByteAtATime) {
    std::vector<std::uint8_t> stream;
    append_frame(stream, bytes_of("trickle"));
    std::vector<std::size_t> cuts;
    for (std::size_t i = 1; i < stream.size(); ++i) {
        cuts.push_back(i);
    }
    FrameDecoder decoder;
    const auto frames = decode_in_pieces(stream, cuts, decoder);
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_EQ(frames[0], bytes_of("trickle"));
}

TEST(Framing, RandomPiecesRandomPayloads) {
    std::mt19937 rng(42);
    for (int round = 0; round < 200; ++round) {
        std::vector<std::vector<std::uint8_t>> payloads(
            std::uniform_int_distribution<int>(1, 8)(rng));
        std::vector<std::uint8_t> stream;
        for (auto& p : payloads) {
            p.resize(std::uniform_int_distribution<std::size_t>(0, 300)(rng));
            for (auto& b : p) {
                b = static_cast<std::uint8_t>(rng());
            }
            append_frame(stream, p);
        }
        std::vector<std::size_t> cuts;
        for (std::size_t i = 1; i < stream.size(); ++i) {
            if (rng() % 7 == 0) {
                cuts.push_back(i);
            }
        }
        FrameDecoder decoder;
        EXPECT_EQ(decode_in_pieces(stream, cuts, decoder), payloads) << "round " << round;
    }
}

TEST(Framing, OversizedLengthIsRejectedAndSticks) {
    FrameDecoder decoder(1024);
    std::vector<std::uint8_t> stream(4);
    write_frame_header(stream.data(), 1025);
    decoder.feed(stream);
    std::span<const std::uint8_t> payload;
    EXPECT_EQ(decoder.next(payload), FrameDecoder::Status::too_large);
    EXPECT_EQ(decoder.rejected_length(), 1025u);
    // No resynchronisation: a valid frame after it is not accepted.
    std::vector<std::uint8_t> more;
    append_frame(more, bytes_of("ok"));
    decoder.feed(more);
    EXPECT_EQ(decoder.next(payload), FrameDecoder::Status::too_large);
}

TEST(Framing, ExactlyMaxSizeIsAccepted) {
    FrameDecoder decoder(16);
    std::vector<std::uint8_t> stream;
    append_frame(stream, std::vector<std::uint8_t>(16, 7));
    decoder.feed(stream);
    std::span<const std::uint8_t> payload;
    ASSERT_EQ(decoder.next(payload), FrameDecoder::Status::frame);
    EXPECT_EQ(payload.size(), 16u);
}

TEST(Framing, GarbageBytesNeverCrashAndEndInOneOfTheStatuses) {
    std::mt19937 rng(7);
    for (int round = 0; round < 500; ++round) {
        FrameDecoder decoder(4096);
        std::vector<std::uint8_t> garbage(std::uniform_int_distribution<std::size_t>(0, 64)(rng));
        for (auto& b : garbage) {
            b = static_cast<std::uint8_t>(rng());
        }
        decoder.feed(garbage);
        std::span<const std::uint8_t> payload;
        int frames = 0;
        FrameDecoder::Status status;
        while ((status = decoder.next(payload)) == FrameDecoder::Status::frame) {
            ++frames;
            ASSERT_LE(payload.size(), 4096u);
        }
        EXPECT_TRUE(status == FrameDecoder::Status::need_more ||
                    status == FrameDecoder::Status::too_large);
        EXPECT_LE(decoder.buffered_bytes(), garbage.size());
    }
}

TEST(Framing, TruncatedFrameWaitsForMore) {
    std::vector<std::uint8_t> stream;
    append_frame(stream, bytes_of("truncated payload"));
    stream.pop_back();
    FrameDecoder decoder;
    decoder.feed(stream);
    std::span<const std::uint8_t> payload;
    EXPECT_EQ(decoder.next(payload), FrameDecoder::Status::need_more);
    EXPECT_EQ(decoder.buffered_bytes(), stream.size());
    const std::uint8_t last = 'd';
    decoder.feed(std::span(&last, 1));
    ASSERT_EQ(decoder.next(payload), FrameDecoder::Status::frame);
    EXPECT_EQ(std::vector<std::uint8_t>(payload.begin(), payload.end()),
              bytes_of("truncated payload"));
}

} // namespace
} // namespace dsoc::protocol
