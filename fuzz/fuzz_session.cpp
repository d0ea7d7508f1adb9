// Fuzzes every server-side message handler through a real Session: the input is
// the byte stream a client sends (in pieces whose sizes the input chooses), run
// through framing, decoding, the handshake, connect-token verification (as the
// server does it), input checks and clamping, the rate cap, pings and disconnects.
// Invariants: inputs reaching the game are finite and in range, the host hears of a
// close exactly once, and the send queue stays within its bound.

#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/connect_token.hpp"
#include "dsoc/server/session.hpp"

#include <boost/asio/io_context.hpp>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

namespace {

namespace pb = dsoc::protocol::pb;
using dsoc::server::Session;

const dsoc::protocol::TokenKey& fuzz_key() {
    static const dsoc::protocol::TokenKey key = [] {
        dsoc::protocol::TokenKey k;
        for (std::size_t i = 0; i < k.bytes.size(); ++i) {
            k.bytes[i] = static_cast<std::uint8_t>(i * 7 + 1);
        }
        return k;
    }();
    return key;
}

class FuzzHost final : public dsoc::server::ConnectionHost {
public:
    void on_hello(dsoc::server::Connection& session, const pb::ClientHello& hello) override {
        const auto& token = hello.connect_token();
        const auto check = dsoc::protocol::verify_connect_token(
            fuzz_key(),
            std::span(reinterpret_cast<const std::uint8_t*>(token.data()), token.size()),
            1'700'000'000);
        if (!token.empty() && check.status != dsoc::protocol::TokenStatus::valid) {
            session.disconnect(pb::DISCONNECT_REASON_UNAUTHORIZED, check.why);
            return;
        }
        pb::Envelope reply;
        reply.mutable_server_hello()->set_client_id(session.client_id());
        session.send(reply);
        session.set_entity_id(1);
        session.mark_active();
    }
    void on_input(dsoc::server::Connection& session, const pb::ClientInput& in) override {
        const double length =
            std::sqrt(double(in.move_x()) * in.move_x() + double(in.move_y()) * in.move_y() +
                      double(in.move_z()) * in.move_z());
        if (!session.active() || !(length <= 1.0 + 1e-6) || !(in.view_yaw() >= -180.0f) ||
            !(in.view_yaw() < 180.0f) || !(in.view_pitch() >= -90.0f) ||
            !(in.view_pitch() <= 90.0f)) {
            std::abort(); // an unchecked input reached the game
        }
    }
    void on_closed(dsoc::server::Connection&) override { ++closes; }
    int closes = 0;
};

} // namespace

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
    spdlog::set_level(spdlog::level::off); // a disconnect per input would flood the log
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) {
        return 0;
    }
    dsoc::server::ServerConfig config;
    config.insecure = true;
    config.max_frame_bytes = 4096;
    config.max_send_queue_bytes = 8192;
    config.max_inputs_per_second = 50;
    const std::size_t piece = static_cast<std::size_t>(data[0]) + 1;
    FuzzHost host;
    {
        boost::asio::io_context io;
        // Never opened: writes fail at once, which exercises the close path too.
        boost::asio::ip::tcp::socket socket(io);
        auto session = std::make_shared<Session>(std::move(socket), 1, config, host);
        std::span<const std::uint8_t> rest(data + 1, size - 1);
        while (!rest.empty()) {
            const std::size_t n = std::min(piece, rest.size());
            session->receive(rest.first(n));
            rest = rest.subspan(n);
            if (session->offer_snapshot(Session::Clock::now(), 1)) {
                pb::Envelope snapshot;
                snapshot.mutable_snapshot()->set_server_tick(1);
                session->send_snapshot(snapshot);
            }
            if (session->queued_bytes() > config.max_send_queue_bytes + 1024) {
                std::abort(); // beyond the bound plus one Disconnect frame
            }
            io.poll();
        }
        io.poll();
    }
    if (host.closes > 1) {
        std::abort();
    }
    return 0;
}
