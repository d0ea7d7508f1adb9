#pragma once
// UDP datagrams (docs/protocol.md, "UDP transport"): the byte layout of every datagram
// the server and its clients exchange over UDP, the handshake that proves a client's
// address before the server keeps any state for it, the window that refuses replayed
// sequence numbers, and the split of a snapshot into datagrams no larger than
// kMaxDatagramBytes. No sockets here: the server and the simclient own those.
//
// Every datagram starts with an 18-byte header, integers little-endian:
//   [0, 4)   protocol id "DSOC" (0x44 0x53 0x4f 0x43)
//   [4]      datagram format version, kDatagramVersion
//   [5]      kind (DatagramKind)
//   [6, 14)  session: the client's nonce in request, challenge, response and accepted
//            (whose body carries the session id the server assigned); that session id in
//            everything after
//   [14, 18) sequence: per sender and session, increasing from 1 (0 in request,
//            challenge, response)
// followed by the kind's body (DatagramKind). Decoding never trusts the bytes: every
// failure comes back as a DatagramError.
//
// Threading: pure functions; ReplayWindow and SnapshotAssembler one per session end.

#include "dsoc/protocol/messages.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace dsoc::protocol {

inline constexpr std::array<std::uint8_t, 4> kDatagramProtocolId{0x44, 0x53, 0x4f, 0x43};
inline constexpr std::uint8_t kDatagramVersion = 1;
inline constexpr std::size_t kDatagramHeaderBytes = 18;
/// The largest datagram either side sends, and the exact size of a request: every path
/// MTU of the Internet carries it whole (IPv6's minimum is 1,280 with headers). [Units: bytes]
inline constexpr std::size_t kMaxDatagramBytes = 1200;
/// The most inputs one input datagram carries (the newest and the ones before it).
inline constexpr std::size_t kMaxRedundantInputs = 3;
/// The most datagrams one snapshot is split into. [Units: datagrams]
inline constexpr std::size_t kMaxSnapshotFragments = 64;
/// Snapshot bytes one datagram carries: what is left after the header and the fragment
/// header (tick, index, count). [Units: bytes]
inline constexpr std::size_t kSnapshotFragmentBytes = kMaxDatagramBytes - kDatagramHeaderBytes - 10;
/// The largest serialized snapshot envelope that can be sent. [Units: bytes]
inline constexpr std::size_t kMaxSnapshotBytes = kMaxSnapshotFragments * kSnapshotFragmentBytes;
/// The size of a challenge cookie (what the server's challenge carries and the client's
/// response echoes). [Units: bytes]
inline constexpr std::size_t kCookieBytes = 24;

enum class DatagramKind : std::uint8_t {
    /// Client -> server, session = the client's random nonce. Body: u16 hello length, a
    /// serialized Envelope holding a ClientHello, zeros up to exactly kMaxDatagramBytes
    /// (so that no answer before the handshake is larger than what asked for it).
    request = 1,
    /// Server -> client, session = the request's nonce. Body: the cookie (kCookieBytes).
    challenge = 2,
    /// Client -> server, session = the nonce. Body: the cookie, u16 hello length, the
    /// serialized hello envelope.
    response = 3,
    /// Server -> client, session = the nonce. Body: u64 session id, then a serialized
    /// Envelope holding the ServerHello (or a Disconnect saying why not).
    accepted = 4,
    /// Either way. Body: one serialized Envelope (ping, pong, disconnect).
    message = 5,
    /// Client -> server. Body: u64 ack (the newest snapshot tick the client applied, 0:
    /// none), u8 count (1..kMaxRedundantInputs), then count times u16 length and a
    /// serialized ClientInput, the newest first.
    input = 6,
    /// Server -> client. Body: u64 snapshot tick, u8 fragment index, u8 fragment count
    /// (1..kMaxSnapshotFragments), then that fragment's bytes of the serialized Envelope
    /// holding the Snapshot (every fragment but the last exactly kSnapshotFragmentBytes).
    snapshot = 7,
};

enum class DatagramError : std::uint8_t {
    none,
    truncated,     ///< shorter than a header, or than its body says
    oversized,     ///< longer than kMaxDatagramBytes
    not_dsoc,      ///< wrong protocol id: not ours
    wrong_version, ///< a datagram format version this build does not speak
    unknown_kind,
    bad_body, ///< the body is inconsistent (a length, a count or a padding byte)
};

/// Readable name, e.g. "wrong_version". Static storage.
const char* to_string(DatagramError error) noexcept;

struct DatagramHeader {
    DatagramKind kind = DatagramKind::message;
    std::uint64_t session = 0;
    std::uint32_t sequence = 0;
};

/// Clears `out` and writes `header` into it (the body is appended after).
void begin_datagram(const DatagramHeader& header, std::vector<std::uint8_t>& out);

/// Reads the header of `datagram`; on none, `body` views the rest.
[[nodiscard]] DatagramError read_datagram(std::span<const std::uint8_t> datagram,
                                          DatagramHeader& header,
                                          std::span<const std::uint8_t>& body);

/// The hello of a request or response body (`kind` says which; the response's cookie is
/// returned in `cookie`), as the serialized envelope bytes.
[[nodiscard]] DatagramError read_hello_body(DatagramKind kind, std::span<const std::uint8_t> body,
                                            std::span<const std::uint8_t>& cookie,
                                            std::span<const std::uint8_t>& hello);

/// A whole request datagram: `hello` serialized, padded to kMaxDatagramBytes. Returns
/// false (and leaves `out` empty) when the hello does not fit.
[[nodiscard]] bool write_request(std::uint64_t nonce, const pb::Envelope& hello,
                                 std::vector<std::uint8_t>& out);
/// A whole response datagram. Returns false when it does not fit.
[[nodiscard]] bool write_response(std::uint64_t nonce, std::span<const std::uint8_t> cookie,
                                  const pb::Envelope& hello, std::vector<std::uint8_t>& out);
/// A datagram of `kind` whose body is `prefix` (raw bytes, may be empty) then `message`
/// serialized: challenge (prefix = cookie, no message), accepted (prefix = u64 session
/// id), message. Returns false when it does not fit.
[[nodiscard]] bool write_envelope_datagram(const DatagramHeader& header,
                                           std::span<const std::uint8_t> prefix,
                                           const pb::Envelope* message,
                                           std::vector<std::uint8_t>& out);

/// The session id an accepted body names, and the envelope after it.
[[nodiscard]] DatagramError read_accepted_body(std::span<const std::uint8_t> body,
                                               std::uint64_t& session,
                                               std::span<const std::uint8_t>& envelope);

/// An input datagram: `ack` and `inputs` (1..kMaxRedundantInputs, the newest first).
/// Returns false when they do not fit.
[[nodiscard]] bool write_input(const DatagramHeader& header, std::uint64_t ack,
                               std::span<const pb::ClientInput> inputs,
                               std::vector<std::uint8_t>& out);

/// What an input body holds: views of each input's serialized bytes, the newest first.
struct InputBody {
    std::uint64_t ack = 0;
    std::size_t count = 0;
    std::array<std::span<const std::uint8_t>, kMaxRedundantInputs> inputs{};
};
[[nodiscard]] DatagramError read_input_body(std::span<const std::uint8_t> body, InputBody& out);

/// Splits `envelope` (a serialized snapshot envelope of 1..kMaxSnapshotBytes bytes) of
/// `tick` (>= 1) into datagrams, appended to `out` one after the other, each preceded by
/// its u16 length: [len][datagram][len][datagram]... The sequence numbers run from
/// `first_sequence`. Returns the number of datagrams (0: empty, too large or tick 0;
/// nothing written).
std::size_t write_snapshot_datagrams(std::uint64_t session, std::uint32_t first_sequence,
                                     std::uint64_t tick, std::span<const std::uint8_t> envelope,
                                     std::vector<std::uint8_t>& out);

/// One fragment of a snapshot, as read from a snapshot body.
struct SnapshotFragment {
    std::uint64_t tick = 0;
    std::uint8_t index = 0;
    std::uint8_t count = 0;
    std::span<const std::uint8_t> bytes;
};
[[nodiscard]] DatagramError read_snapshot_body(std::span<const std::uint8_t> body,
                                               SnapshotFragment& out);

/// Puts the fragments of snapshots back together. It assembles one snapshot at a time:
/// a fragment of a newer tick drops the one in progress (its other fragments were lost or
/// are late: the acknowledged-delta codec needs no lost snapshot again), one of an older
/// tick or of the tick already completed is ignored. Memory: at most kMaxSnapshotBytes.
class SnapshotAssembler {
public:
    enum class Result : std::uint8_t {
        incomplete, ///< kept; more fragments are needed
        complete,   ///< `envelope` holds the whole snapshot's bytes until the next add()
        ignored,    ///< old, duplicate or inconsistent with the fragments before it
    };
    Result add(const SnapshotFragment& fragment, std::span<const std::uint8_t>& envelope);
    /// Snapshots given up unfinished because a newer one started.
    [[nodiscard]] std::uint64_t abandoned() const { return abandoned_; }

private:
    std::vector<std::uint8_t> bytes_;
    std::uint64_t tick_ = 0;      ///< the snapshot being assembled (or completed last)
    std::uint64_t have_mask_ = 0; ///< fragments held, bit i for index i
    std::uint8_t count_ = 0;
    std::size_t last_bytes_ = 0; ///< size of the last fragment, once held
    bool done_ = false;          ///< tick_ was completed
    std::uint64_t abandoned_ = 0;
};

/// The receiver's record of the sequence numbers it took from one sender: refuses a
/// number taken before or 64 or more behind the newest (a replay, a duplicate, or so late
/// that the receiver no longer knows), and one more than kMaxSequenceJump ahead of the
/// newest (no honest sender skips that many: one forged datagram must not push the
/// window to the top of the range and lock the sender out).
class ReplayWindow {
public:
    static constexpr std::uint32_t kMaxSequenceJump = 1u << 16;
    /// True (and records it) when `sequence` (>= 1) is new; false for a replay.
    bool accept(std::uint32_t sequence);
    [[nodiscard]] std::uint32_t newest() const { return newest_; }

private:
    std::uint32_t newest_ = 0;
    std::uint64_t seen_ = 0; ///< bit i: newest_ - i was taken
};

} // namespace dsoc::protocol
