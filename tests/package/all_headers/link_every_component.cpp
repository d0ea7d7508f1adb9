// One call into each installed component, so that linking needs every library and
// its system dependencies (libzip, fmt, protobuf) as the installed package names
// them. Exits non-zero, saying why, when an answer is not the documented one.

#include <dsoc/maps/map_spec.hpp>
#include <dsoc/protocol/codec.hpp>
#include <dsoc/sim/player_move.hpp>
#include <dsoc/trace/trace_reader.hpp>
#include <dsoc/visibility/version.hpp>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

int main() {
    int failures = 0;
    const auto expect = [&failures](bool ok, const char* what) {
        if (!ok) {
            std::fprintf(stderr, "link_every_component: %s\n", what);
            ++failures;
        }
    };
    expect(std::string(dsoc::version()).find('.') != std::string::npos,
           "dsoc::version() is not MAJOR.MINOR.PATCH");

    const auto parsed = dsoc::maps::parse_text_map("dsoc-map 1\nbox solid 0 0 0 1 1 1\n", "t");
    expect(parsed.ok() && parsed.value().brushes.size() == 1, "maps: a one-box map");

    expect(dsoc::sim::validate(dsoc::sim::MoveConfig{}).empty(), "sim: default MoveConfig");

    dsoc::trace::TraceReader reader;
    expect(!reader.open("/nonexistent/dsoc-trace.jsonl") && !reader.error().empty(),
           "trace: opening a missing file must fail with a reason");

    dsoc::protocol::pb::Envelope envelope;
    envelope.mutable_client_hello()->set_protocol_version(dsoc::protocol::kProtocolVersion);
    std::vector<std::uint8_t> frame;
    expect(dsoc::protocol::encode_frame(envelope, frame) == frame.size() && frame.size() > 4,
           "protocol: encoding a hello");
    expect(dsoc::protocol::disconnect_reason_name(
               dsoc::protocol::pb::DISCONNECT_REASON_VERSION_MISMATCH) == "version_mismatch",
           "protocol: the version mismatch reason's name");
    return failures == 0 ? 0 : 1;
}
