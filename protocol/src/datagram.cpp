#include "dsoc/protocol/datagram.hpp"

#include <algorithm>
#include <cstring>

namespace dsoc::protocol {

namespace {

constexpr std::size_t kFragmentHeaderBytes = 10; // u64 tick, u8 index, u8 count
static_assert(kSnapshotFragmentBytes + kDatagramHeaderBytes + kFragmentHeaderBytes ==
              kMaxDatagramBytes);
static_assert(kMaxSnapshotFragments <= 64, "SnapshotAssembler keeps one bit per fragment");

void put_u16(std::vector<std::uint8_t>& out, std::uint16_t v) {
    out.push_back(static_cast<std::uint8_t>(v));
    out.push_back(static_cast<std::uint8_t>(v >> 8));
}

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) {
        out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
}

void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) {
        out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
}

std::uint64_t get_le(const std::uint8_t* in, int bytes) {
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) {
        v |= static_cast<std::uint64_t>(in[i]) << (8 * i);
    }
    return v;
}

/// Appends `message` serialized after a u16 length. False when it is larger than `room`
/// (then nothing is appended).
bool put_sized_message(const google::protobuf::MessageLite& message, std::size_t room,
                       std::vector<std::uint8_t>& out) {
    const std::size_t size = message.ByteSizeLong();
    if (size + 2 > room) {
        return false;
    }
    put_u16(out, static_cast<std::uint16_t>(size));
    const std::size_t at = out.size();
    out.resize(at + size);
    return message.SerializeToArray(out.data() + at, static_cast<int>(size));
}

/// Reads a u16 length and that many bytes from `body` at `at`.
bool take_sized(std::span<const std::uint8_t> body, std::size_t& at,
                std::span<const std::uint8_t>& out) {
    if (body.size() - at < 2) {
        return false;
    }
    const auto size = static_cast<std::size_t>(get_le(body.data() + at, 2));
    at += 2;
    if (body.size() - at < size) {
        return false;
    }
    out = body.subspan(at, size);
    at += size;
    return true;
}

} // namespace

const char* to_string(DatagramError error) noexcept {
    switch (error) {
    case DatagramError::none:
        return "none";
    case DatagramError::truncated:
        return "truncated";
    case DatagramError::oversized:
        return "oversized";
    case DatagramError::not_dsoc:
        return "not_dsoc";
    case DatagramError::wrong_version:
        return "wrong_version";
    case DatagramError::unknown_kind:
        return "unknown_kind";
    case DatagramError::bad_body:
        return "bad_body";
    }
    return "unknown";
}

void begin_datagram(const DatagramHeader& header, std::vector<std::uint8_t>& out) {
    out.clear();
    for (const std::uint8_t b : kDatagramProtocolId) {
        out.push_back(b);
    }
    out.push_back(kDatagramVersion);
    out.push_back(static_cast<std::uint8_t>(header.kind));
    put_u64(out, header.session);
    put_u32(out, header.sequence);
}

DatagramError read_datagram(std::span<const std::uint8_t> datagram, DatagramHeader& header,
                            std::span<const std::uint8_t>& body) {
    if (datagram.size() > kMaxDatagramBytes) {
        return DatagramError::oversized;
    }
    if (datagram.size() < kDatagramHeaderBytes) {
        return DatagramError::truncated;
    }
    if (!std::equal(kDatagramProtocolId.begin(), kDatagramProtocolId.end(), datagram.begin())) {
        return DatagramError::not_dsoc;
    }
    if (datagram[4] != kDatagramVersion) {
        return DatagramError::wrong_version;
    }
    const std::uint8_t kind = datagram[5];
    if (kind < static_cast<std::uint8_t>(DatagramKind::request) ||
        kind > static_cast<std::uint8_t>(DatagramKind::snapshot)) {
        return DatagramError::unknown_kind;
    }
    header.kind = static_cast<DatagramKind>(kind);
    header.session = get_le(datagram.data() + 6, 8);
    header.sequence = static_cast<std::uint32_t>(get_le(datagram.data() + 14, 4));
    body = datagram.subspan(kDatagramHeaderBytes);
    return DatagramError::none;
}

DatagramError read_hello_body(DatagramKind kind, std::span<const std::uint8_t> body,
                              std::span<const std::uint8_t>& cookie,
                              std::span<const std::uint8_t>& hello) {
    std::size_t at = 0;
    cookie = {};
    if (kind == DatagramKind::response) {
        if (body.size() < kCookieBytes) {
            return DatagramError::truncated;
        }
        cookie = body.first(kCookieBytes);
        at = kCookieBytes;
    } else if (kind != DatagramKind::request) {
        return DatagramError::bad_body;
    } else if (body.size() + kDatagramHeaderBytes != kMaxDatagramBytes) {
        return DatagramError::truncated; // a request is always padded to the full size
    }
    if (!take_sized(body, at, hello)) {
        return DatagramError::truncated;
    }
    const auto rest = body.subspan(at);
    if (kind == DatagramKind::response
            ? !rest.empty()
            : std::any_of(rest.begin(), rest.end(), [](std::uint8_t b) { return b != 0; })) {
        return DatagramError::bad_body;
    }
    return DatagramError::none;
}

bool write_request(std::uint64_t nonce, const pb::Envelope& hello, std::vector<std::uint8_t>& out) {
    begin_datagram({DatagramKind::request, nonce, 0}, out);
    if (!put_sized_message(hello, kMaxDatagramBytes - out.size(), out)) {
        out.clear();
        return false;
    }
    out.resize(kMaxDatagramBytes, 0);
    return true;
}

bool write_response(std::uint64_t nonce, std::span<const std::uint8_t> cookie,
                    const pb::Envelope& hello, std::vector<std::uint8_t>& out) {
    begin_datagram({DatagramKind::response, nonce, 0}, out);
    if (cookie.size() != kCookieBytes) {
        out.clear();
        return false;
    }
    out.insert(out.end(), cookie.begin(), cookie.end());
    if (!put_sized_message(hello, kMaxDatagramBytes - out.size(), out)) {
        out.clear();
        return false;
    }
    return true;
}

bool write_envelope_datagram(const DatagramHeader& header, std::span<const std::uint8_t> prefix,
                             const pb::Envelope* message, std::vector<std::uint8_t>& out) {
    begin_datagram(header, out);
    out.insert(out.end(), prefix.begin(), prefix.end());
    if (message != nullptr) {
        const std::size_t size = message->ByteSizeLong();
        if (out.size() + size > kMaxDatagramBytes) {
            out.clear();
            return false;
        }
        const std::size_t at = out.size();
        out.resize(at + size);
        if (!message->SerializeToArray(out.data() + at, static_cast<int>(size))) {
            out.clear();
            return false;
        }
    }
    if (out.size() > kMaxDatagramBytes) {
        out.clear();
        return false;
    }
    return true;
}

DatagramError read_accepted_body(std::span<const std::uint8_t> body, std::uint64_t& session,
                                 std::span<const std::uint8_t>& envelope) {
    if (body.size() < 8) {
        return DatagramError::truncated;
    }
    session = get_le(body.data(), 8);
    envelope = body.subspan(8);
    return session == 0 ? DatagramError::bad_body : DatagramError::none;
}

bool write_input(const DatagramHeader& header, std::uint64_t ack,
                 std::span<const pb::ClientInput> inputs, std::vector<std::uint8_t>& out) {
    begin_datagram(header, out);
    if (inputs.empty() || inputs.size() > kMaxRedundantInputs) {
        out.clear();
        return false;
    }
    put_u64(out, ack);
    out.push_back(static_cast<std::uint8_t>(inputs.size()));
    for (const pb::ClientInput& input : inputs) {
        if (!put_sized_message(input, kMaxDatagramBytes - out.size(), out)) {
            out.clear();
            return false;
        }
    }
    return true;
}

DatagramError read_input_body(std::span<const std::uint8_t> body, InputBody& out) {
    if (body.size() < 9) {
        return DatagramError::truncated;
    }
    out.ack = get_le(body.data(), 8);
    out.count = body[8];
    if (out.count == 0 || out.count > kMaxRedundantInputs) {
        return DatagramError::bad_body;
    }
    std::size_t at = 9;
    for (std::size_t i = 0; i < out.count; ++i) {
        if (!take_sized(body, at, out.inputs[i])) {
            return DatagramError::truncated;
        }
    }
    return at == body.size() ? DatagramError::none : DatagramError::bad_body;
}

std::size_t write_snapshot_datagrams(std::uint64_t session, std::uint32_t first_sequence,
                                     std::uint64_t tick, std::span<const std::uint8_t> envelope,
                                     std::vector<std::uint8_t>& out) {
    if (envelope.empty() || envelope.size() > kMaxSnapshotBytes || tick == 0) {
        return 0;
    }
    const std::size_t count =
        (envelope.size() + kSnapshotFragmentBytes - 1) / kSnapshotFragmentBytes;
    std::vector<std::uint8_t> header;
    for (std::size_t i = 0; i < count; ++i) {
        const std::size_t at = i * kSnapshotFragmentBytes;
        const std::size_t size = std::min(kSnapshotFragmentBytes, envelope.size() - at);
        begin_datagram(
            {DatagramKind::snapshot, session, first_sequence + static_cast<std::uint32_t>(i)},
            header);
        put_u64(header, tick);
        header.push_back(static_cast<std::uint8_t>(i));
        header.push_back(static_cast<std::uint8_t>(count));
        put_u16(out, static_cast<std::uint16_t>(header.size() + size));
        out.insert(out.end(), header.begin(), header.end());
        out.insert(out.end(), envelope.begin() + static_cast<std::ptrdiff_t>(at),
                   envelope.begin() + static_cast<std::ptrdiff_t>(at + size));
    }
    return count;
}

DatagramError read_snapshot_body(std::span<const std::uint8_t> body, SnapshotFragment& out) {
    if (body.size() < kFragmentHeaderBytes) {
        return DatagramError::truncated;
    }
    out.tick = get_le(body.data(), 8);
    out.index = body[8];
    out.count = body[9];
    out.bytes = body.subspan(kFragmentHeaderBytes);
    const bool last = out.index + 1 == out.count;
    if (out.count == 0 || out.count > kMaxSnapshotFragments || out.index >= out.count ||
        out.tick == 0 || out.bytes.empty() ||
        (last ? out.bytes.size() > kSnapshotFragmentBytes
              : out.bytes.size() != kSnapshotFragmentBytes)) {
        return DatagramError::bad_body;
    }
    return DatagramError::none;
}

SnapshotAssembler::Result SnapshotAssembler::add(const SnapshotFragment& fragment,
                                                 std::span<const std::uint8_t>& envelope) {
    if (fragment.tick < tick_ || (fragment.tick == tick_ && done_)) {
        return Result::ignored;
    }
    if (fragment.tick > tick_) {
        abandoned_ += static_cast<std::uint64_t>(tick_ != 0 && !done_);
        tick_ = fragment.tick;
        have_mask_ = 0;
        count_ = fragment.count;
        last_bytes_ = 0;
        done_ = false;
        bytes_.resize(static_cast<std::size_t>(count_) * kSnapshotFragmentBytes);
    }
    const std::uint64_t bit = std::uint64_t{1} << fragment.index;
    if (fragment.count != count_ || (have_mask_ & bit) != 0) {
        return Result::ignored;
    }
    std::memcpy(bytes_.data() + static_cast<std::size_t>(fragment.index) * kSnapshotFragmentBytes,
                fragment.bytes.data(), fragment.bytes.size());
    if (fragment.index + 1 == count_) {
        last_bytes_ = fragment.bytes.size();
    }
    have_mask_ |= bit;
    const std::uint64_t all = count_ == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << count_) - 1;
    if (have_mask_ != all) {
        return Result::incomplete;
    }
    done_ = true;
    envelope = std::span<const std::uint8_t>(bytes_).first(
        static_cast<std::size_t>(count_ - 1) * kSnapshotFragmentBytes + last_bytes_);
    return Result::complete;
}

bool ReplayWindow::accept(std::uint32_t sequence) {
    if (sequence == 0) {
        return false;
    }
    if (sequence > newest_) {
        const std::uint32_t shift = sequence - newest_;
        if (shift > kMaxSequenceJump) { // the first too: newest_ counts as 0 before it
            return false;
        }
        seen_ = shift >= 64 ? 0 : seen_ << shift;
        seen_ |= 1;
        newest_ = sequence;
        return true;
    }
    const std::uint32_t behind = newest_ - sequence;
    if (behind >= 64) {
        return false;
    }
    const std::uint64_t bit = std::uint64_t{1} << behind;
    if ((seen_ & bit) != 0) {
        return false;
    }
    seen_ |= bit;
    return true;
}

} // namespace dsoc::protocol
