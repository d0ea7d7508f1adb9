// Fuzzes the UDP datagram layer (datagram.hpp) as one receiving end meets it: the input
// is a sequence of datagrams, each a u16 little-endian length and that many bytes (fewer
// at the end of the input), fed in order to read_datagram and then, by kind, to the
// body readers, one SnapshotAssembler and one ReplayWindow. Whatever the bytes, nothing
// may crash, overflow or read past a body, and:
// - a header read_datagram reads writes back (begin_datagram) to the same 18 bytes and
//   names one of the kinds (which error a broken header gets, in the spec's order, is
//   for tests/protocol/datagram_test.cpp: a copy of the parser's rules here would only
//   ever agree with the parser);
// - a hello (request, response), accepted, message or input body that reads writes back,
//   through the writers, to a datagram that reads the same; an input body is exactly
//   its ack, count and sized inputs;
// - the assembler agrees with a model of its contract (the newest tick started is
//   assembled; older ticks, the completed tick, duplicates and a fragment whose count
//   disagrees are ignored), and a complete snapshot is exactly its fragments' bytes in
//   order, never more than kMaxSnapshotBytes, and splits again into the same fragments;
// - the replay window accepts a sequence exactly when a set of those it took says so.

#include "dsoc/protocol/datagram.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <set>
#include <span>
#include <string>
#include <vector>

namespace {

using namespace dsoc::protocol;
using Bytes = std::vector<std::uint8_t>;
using View = std::span<const std::uint8_t>;

constexpr std::size_t kFragmentHeaderBytes = 10; // u64 tick, u8 index, u8 count
constexpr std::size_t kBodyRoom = kMaxDatagramBytes - kDatagramHeaderBytes;

void require(bool condition) {
    if (!condition) {
        std::abort();
    }
}

bool same(View a, View b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end());
}

bool same(View a, const std::string& b) {
    return same(a, View(reinterpret_cast<const std::uint8_t*>(b.data()), b.size()));
}

/// Reads a datagram we wrote ourselves: it must read, with `header`.
View reread(const Bytes& datagram, const DatagramHeader& header) {
    require(datagram.size() <= kMaxDatagramBytes);
    DatagramHeader again;
    View body;
    require(read_datagram(datagram, again, body) == DatagramError::none);
    require(again.kind == header.kind && again.session == header.session &&
            again.sequence == header.sequence);
    return body;
}

void check_hello(const DatagramHeader& header, View body) {
    View cookie;
    View hello;
    if (read_hello_body(header.kind, body, cookie, hello) != DatagramError::none) {
        return;
    }
    const bool response = header.kind == DatagramKind::response;
    const std::size_t before = response ? kCookieBytes + 2 : 2;
    require(hello.data() == body.data() + before);
    if (response) {
        require(cookie.data() == body.data() && cookie.size() == kCookieBytes);
        require(body.size() == before + hello.size());
    } else {
        require(cookie.empty() && body.size() == kBodyRoom);
        require(std::all_of(body.begin() + static_cast<std::ptrdiff_t>(before + hello.size()),
                            body.end(), [](std::uint8_t b) { return b == 0; }));
    }
    pb::Envelope envelope;
    if (!envelope.ParseFromArray(hello.data(), static_cast<int>(hello.size()))) {
        return;
    }
    const std::string serialized = envelope.SerializeAsString();
    Bytes out;
    const bool written = response ? write_response(header.session, cookie, envelope, out)
                                  : write_request(header.session, envelope, out);
    require(written == (before + serialized.size() <= kBodyRoom));
    if (!written) {
        require(out.empty());
        return;
    }
    require(!response || out.size() == kDatagramHeaderBytes + before + serialized.size());
    require(response || out.size() == kMaxDatagramBytes);
    const View again = reread(out, {header.kind, header.session, 0});
    View cookie_again;
    View hello_again;
    require(read_hello_body(header.kind, again, cookie_again, hello_again) == DatagramError::none);
    require(same(cookie_again, cookie) && same(hello_again, serialized));
    if (same(hello, serialized)) {
        require(same(again, body)); // canonical bytes: the very same body
    }
}

/// write_envelope_datagram of `prefix` and the envelope `bytes` hold (if they parse)
/// reads back as the prefix and that envelope.
void check_envelope_rewrite(const DatagramHeader& header, View prefix, View bytes) {
    pb::Envelope envelope;
    if (!envelope.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) {
        return;
    }
    const std::string serialized = envelope.SerializeAsString();
    Bytes out;
    const bool written = write_envelope_datagram(header, prefix, &envelope, out);
    require(written == (prefix.size() + serialized.size() <= kBodyRoom));
    if (!written) {
        require(out.empty());
        return;
    }
    const View again = reread(out, header);
    require(same(again.first(prefix.size()), prefix) &&
            same(again.subspan(prefix.size()), serialized));
}

void check_accepted(const DatagramHeader& header, View body) {
    std::uint64_t session = 0;
    View envelope;
    const DatagramError error = read_accepted_body(body, session, envelope);
    require(error != DatagramError::truncated || body.size() < 8);
    if (error != DatagramError::none) {
        return;
    }
    require(session != 0 && body.size() >= 8 && envelope.data() == body.data() + 8 &&
            envelope.size() == body.size() - 8);
    check_envelope_rewrite(header, body.first(8), envelope);
}

void check_input(const DatagramHeader& header, View body) {
    InputBody input;
    if (read_input_body(body, input) != DatagramError::none) {
        return;
    }
    require(input.count >= 1 && input.count <= kMaxRedundantInputs);
    // The body is exactly u64 ack, u8 count, then count times u16 length and the bytes.
    Bytes rebuilt;
    for (int i = 0; i < 8; ++i) {
        rebuilt.push_back(static_cast<std::uint8_t>(input.ack >> (8 * i)));
    }
    rebuilt.push_back(static_cast<std::uint8_t>(input.count));
    std::vector<pb::ClientInput> parsed(input.count);
    bool all_parse = true;
    std::size_t serialized_bytes = 0;
    for (std::size_t i = 0; i < input.count; ++i) {
        const View bytes = input.inputs[i];
        require(bytes.data() >= body.data() &&
                bytes.data() + bytes.size() <= body.data() + body.size());
        rebuilt.push_back(static_cast<std::uint8_t>(bytes.size()));
        rebuilt.push_back(static_cast<std::uint8_t>(bytes.size() >> 8));
        rebuilt.insert(rebuilt.end(), bytes.begin(), bytes.end());
        all_parse =
            all_parse && parsed[i].ParseFromArray(bytes.data(), static_cast<int>(bytes.size()));
        serialized_bytes += 2 + parsed[i].ByteSizeLong();
    }
    require(same(rebuilt, body));
    if (!all_parse) {
        return;
    }
    Bytes out;
    const bool written = write_input(header, input.ack, parsed, out);
    require(written == (9 + serialized_bytes <= kBodyRoom));
    if (!written) {
        require(out.empty());
        return;
    }
    InputBody again;
    require(read_input_body(reread(out, header), again) == DatagramError::none);
    require(again.ack == input.ack && again.count == input.count);
    for (std::size_t i = 0; i < input.count; ++i) {
        require(same(again.inputs[i], parsed[i].SerializeAsString()));
    }
}

/// The assembler's contract, kept with copies of the fragments it should hold.
struct AssemblerModel {
    std::uint64_t tick = 0;
    std::uint8_t count = 0;
    bool done = false;
    std::map<std::uint8_t, Bytes> held;
    std::uint64_t abandoned = 0;

    SnapshotAssembler::Result add(const SnapshotFragment& f) {
        using R = SnapshotAssembler::Result;
        if (f.tick < tick || (f.tick == tick && done)) {
            return R::ignored;
        }
        if (f.tick > tick) {
            abandoned += tick != 0 && !done ? 1 : 0;
            tick = f.tick;
            count = f.count;
            done = false;
            held.clear();
        }
        if (f.count != count || held.count(f.index) != 0) {
            return R::ignored;
        }
        held.emplace(f.index, Bytes(f.bytes.begin(), f.bytes.end()));
        done = held.size() == count;
        return done ? R::complete : R::incomplete;
    }
};

void check_snapshot(const DatagramHeader& header, View body, SnapshotAssembler& assembler,
                    AssemblerModel& model) {
    SnapshotFragment fragment;
    const DatagramError error = read_snapshot_body(body, fragment);
    require(error != DatagramError::truncated || body.size() < kFragmentHeaderBytes);
    if (error != DatagramError::none) {
        return;
    }
    require(fragment.tick != 0 && fragment.count >= 1 && fragment.count <= kMaxSnapshotFragments &&
            fragment.index < fragment.count);
    require(!fragment.bytes.empty() && fragment.bytes.size() <= kSnapshotFragmentBytes);
    require(fragment.index + 1 == fragment.count ||
            fragment.bytes.size() == kSnapshotFragmentBytes);
    require(fragment.bytes.data() == body.data() + kFragmentHeaderBytes &&
            fragment.bytes.size() == body.size() - kFragmentHeaderBytes);

    View envelope;
    const auto expected = model.add(fragment);
    const auto result = assembler.add(fragment, envelope);
    require(result == expected && assembler.abandoned() == model.abandoned);
    if (result != SnapshotAssembler::Result::complete) {
        return;
    }
    require(!envelope.empty() && envelope.size() <= kMaxSnapshotBytes);
    Bytes joined;
    for (const auto& [index, bytes] : model.held) {
        joined.insert(joined.end(), bytes.begin(), bytes.end());
    }
    require(same(envelope, joined));
    // Split again, the same fragments come out.
    Bytes stream;
    const std::size_t count =
        write_snapshot_datagrams(header.session, 1, fragment.tick, envelope, stream);
    require(count == fragment.count);
    std::size_t at = 0;
    for (std::size_t i = 0; i < count; ++i) {
        require(at + 2 <= stream.size());
        const std::size_t length = stream[at] | static_cast<std::size_t>(stream[at + 1]) << 8;
        at += 2;
        require(length <= kMaxDatagramBytes && at + length <= stream.size());
        const Bytes datagram(stream.begin() + static_cast<std::ptrdiff_t>(at),
                             stream.begin() + static_cast<std::ptrdiff_t>(at + length));
        at += length;
        SnapshotFragment again;
        require(read_snapshot_body(reread(datagram, {DatagramKind::snapshot, header.session,
                                                     static_cast<std::uint32_t>(1 + i)}),
                                   again) == DatagramError::none);
        require(again.tick == fragment.tick && again.index == i && again.count == count &&
                same(again.bytes, model.held.at(static_cast<std::uint8_t>(i))));
    }
    require(at == stream.size());
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    SnapshotAssembler assembler;
    AssemblerModel model;
    ReplayWindow window;
    std::set<std::uint32_t> taken;
    std::uint32_t newest = 0;
    Bytes header_bytes;
    for (std::size_t at = 0; at + 2 <= size;) {
        const std::size_t wanted = data[at] | static_cast<std::size_t>(data[at + 1]) << 8;
        at += 2;
        const View datagram(data + at, std::min(wanted, size - at));
        at += datagram.size();

        DatagramHeader header;
        View body;
        if (read_datagram(datagram, header, body) != DatagramError::none) {
            continue;
        }
        require(datagram.size() <= kMaxDatagramBytes); // a larger one is never read
        begin_datagram(header, header_bytes);
        require(same(header_bytes, datagram.first(kDatagramHeaderBytes)));
        require(body.data() == datagram.data() + kDatagramHeaderBytes &&
                body.size() == datagram.size() - kDatagramHeaderBytes);

        const std::uint32_t s = header.sequence;
        const bool fresh =
            s != 0 && taken.count(s) == 0 &&
            (s > newest ? s - newest <= ReplayWindow::kMaxSequenceJump : newest - s < 64);
        require(window.accept(s) == fresh);
        if (fresh) {
            taken.insert(s);
            newest = std::max(newest, s);
        }
        require(window.newest() == newest);

        if (header.kind != DatagramKind::request && header.kind != DatagramKind::response) {
            View cookie;
            View hello;
            require(read_hello_body(header.kind, body, cookie, hello) == DatagramError::bad_body);
        }
        switch (header.kind) {
        case DatagramKind::request:
        case DatagramKind::response:
            check_hello(header, body);
            break;
        case DatagramKind::challenge: {
            Bytes out;
            require(write_envelope_datagram(header, body, nullptr, out));
            require(same(out, datagram)); // a raw prefix: the very same bytes
            break;
        }
        case DatagramKind::accepted:
            check_accepted(header, body);
            break;
        case DatagramKind::message:
            check_envelope_rewrite(header, {}, body);
            break;
        case DatagramKind::input:
            check_input(header, body);
            break;
        case DatagramKind::snapshot:
            check_snapshot(header, body, assembler, model);
            break;
        default:
            require(false); // a kind DatagramKind does not name
        }
    }
    return 0;
}
