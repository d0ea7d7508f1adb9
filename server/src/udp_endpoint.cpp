#include "dsoc/server/udp_endpoint.hpp"

#include "dsoc/protocol/codec.hpp"

#include <boost/asio/buffer.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstring>

#include <netinet/in.h>

namespace dsoc::server {

namespace asio = boost::asio;
namespace pb = protocol::pb;
using protocol::DatagramKind;

namespace {

/// Sources whose handshake budget is remembered at most (a flood from many spoofed
/// addresses costs bounded memory); while all are spending, new sources are refused
/// until a sweep forgets the budgets that are full again.
constexpr std::size_t kMaxBudgets = 65536;
/// How long a challenge cookie is good for. [Units: ms]
constexpr std::uint64_t kCookieLifetimeMs = 10'000;
/// How long a closed session's id and nonce are remembered (closed_session): at least a
/// cookie's life, so that no response of a closed session can open a new one.
constexpr auto kRememberClosed = std::chrono::milliseconds(kCookieLifetimeMs + 1000);
/// How often silent connections and closed sessions past kRememberClosed are looked for.
constexpr auto kSweepPeriod = std::chrono::milliseconds(250);
/// Kernel buffers of the UDP socket: one socket carries every client's snapshots.
constexpr int kSocketBufferBytes = 8 * 1024 * 1024;

/// The cookies' clock: milliseconds of the steady clock (the key lives as long as the
/// process, so wall time adds nothing, and a step of the wall clock must not expire or
/// stretch cookies in flight).
std::uint64_t cookie_now_ms() {
    return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                          std::chrono::steady_clock::now().time_since_epoch())
                                          .count());
}

} // namespace

protocol::SourceAddress source_address(const asio::ip::udp::endpoint& peer) {
    protocol::SourceAddress out;
    const asio::ip::address a = peer.address();
    out.address = a.is_v6() ? a.to_v6().to_bytes()
                            : asio::ip::make_address_v6(asio::ip::v4_mapped, a.to_v4()).to_bytes();
    out.port = peer.port();
    return out;
}

UdpEndpoint::UdpEndpoint(asio::io_context& io, const ServerConfig& config, ConnectionHost& host,
                         std::function<std::uint32_t()> next_client_id, OpenConnection open)
    : config_(config), host_(host), next_client_id_(std::move(next_client_id)),
      open_(std::move(open)), socket_(io), sweep_timer_(io),
      cookie_key_(protocol::generate_token_key()),
      challenge_budget_{static_cast<double>(config.udp_challenge_rate), Clock::now()} {}

std::uint16_t UdpEndpoint::start(const std::string& address, std::uint16_t port) {
    const asio::ip::udp::endpoint endpoint(asio::ip::make_address(address), port);
    socket_.open(endpoint.protocol());
    socket_.bind(endpoint);
    socket_.non_blocking(true);
    boost::system::error_code ec; // best effort: the kernel caps them at its maxima
    socket_.set_option(asio::socket_base::send_buffer_size(kSocketBufferBytes), ec);
    socket_.set_option(asio::socket_base::receive_buffer_size(kSocketBufferBytes), ec);
    receive_buffers_.resize(kReceiveBatch);
    receive_sources_.resize(kReceiveBatch);
    receive_next();
    sweep();
    return socket_.local_endpoint().port();
}

void UdpEndpoint::stop() {
    stopped_ = true;
    boost::system::error_code ec;
    sweep_timer_.cancel();
    socket_.close(ec);
}

bool UdpEndpoint::send_to(const asio::ip::udp::endpoint& peer,
                          std::span<const std::uint8_t> bytes) {
    boost::system::error_code ec;
    socket_.send_to(asio::buffer(bytes.data(), bytes.size()), peer, 0, ec);
    return !ec;
}

void UdpEndpoint::forget(const UdpConnection& connection) {
    by_session_.erase(connection.session());
    session_of_nonce_.erase(connection.nonce());
    recently_closed_[connection.session()] = Clock::now();
    closed_nonces_[connection.nonce()] = Clock::now();
}

void UdpEndpoint::receive_next() {
    if (stopped_) {
        return;
    }
    socket_.async_receive_from(asio::buffer(buffer_), sender_,
                               [this](const boost::system::error_code& ec, std::size_t n) {
                                   if (ec == asio::error::operation_aborted || stopped_) {
                                       return;
                                   }
                                   if (!ec) {
                                       on_datagram(std::span(buffer_.data(), n));
                                       receive_waiting();
                                   }
                                   receive_next();
                               });
}

void UdpEndpoint::receive_waiting() {
    // At most kReceiveBatch * kMaxReceiveCalls datagrams, then the io_context's other
    // work (a flood cannot hold the thread); the rest are read by the next read.
    std::array<mmsghdr, kReceiveBatch> messages{};
    std::array<iovec, kReceiveBatch> parts{};
    for (int call = 0; call < kMaxReceiveCalls && !stopped_; ++call) {
        for (std::size_t k = 0; k < kReceiveBatch; ++k) {
            parts[k] = {receive_buffers_[k].data(), receive_buffers_[k].size()};
            msghdr& h = messages[k].msg_hdr;
            h = {};
            h.msg_name = &receive_sources_[k];
            h.msg_namelen = sizeof(sockaddr_storage);
            h.msg_iov = &parts[k];
            h.msg_iovlen = 1;
        }
        const int n = ::recvmmsg(socket_.native_handle(), messages.data(), kReceiveBatch,
                                 MSG_DONTWAIT, nullptr);
        if (n <= 0) {
            return; // none waiting, or an error: dropped, as receive_next()'s handler does
        }
        for (std::size_t k = 0; k < static_cast<std::size_t>(n) && !stopped_; ++k) {
            const socklen_t source_size = messages[k].msg_hdr.msg_namelen;
            if (source_size < sizeof(sockaddr_in) || source_size > sender_.capacity()) {
                continue; // not an IPv4 or IPv6 source: cannot be a client
            }
            std::memcpy(sender_.data(), &receive_sources_[k], source_size);
            sender_.resize(source_size);
            // Without MSG_TRUNC msg_len is what the buffer holds: one byte over the
            // largest datagram for an oversized one (dropped as such).
            const std::size_t bytes =
                std::min<std::size_t>(messages[k].msg_len, receive_buffers_[k].size());
            on_datagram(std::span(receive_buffers_[k].data(), bytes));
        }
        if (static_cast<std::size_t>(n) < kReceiveBatch) {
            return;
        }
    }
}

void UdpEndpoint::on_datagram(std::span<const std::uint8_t> datagram) {
    ++received_;
    const std::size_t bytes = datagram.size();
    protocol::DatagramHeader header;
    std::span<const std::uint8_t> body;
    const protocol::DatagramError error = protocol::read_datagram(datagram, header, body);
    if (error != protocol::DatagramError::none) {
        drop(udp_drop_of(error));
        return;
    }
    switch (header.kind) {
    case DatagramKind::request:
        on_request(header.session, body);
        return;
    case DatagramKind::response:
        on_response(header.session, body);
        return;
    case DatagramKind::message:
    case DatagramKind::input:
        break;
    case DatagramKind::challenge:
    case DatagramKind::accepted:
    case DatagramKind::snapshot:
        drop(UdpDrop::unexpected_kind);
        return;
    }
    const auto it = by_session_.find(header.session);
    if (it == by_session_.end()) {
        drop(recently_closed_.contains(header.session) ? UdpDrop::closed_session
                                                       : UdpDrop::unknown_session);
        return;
    }
    const std::shared_ptr<UdpConnection> connection = it->second; // may close below
    if (connection->peer() != sender_) {
        drop(UdpDrop::wrong_source);
        return;
    }
    if (!connection->replay_window().accept(header.sequence)) {
        drop(UdpDrop::replayed);
        return;
    }
    if (!connection->receive(header.kind, body, bytes, Clock::now())) {
        drop(UdpDrop::bad_body);
    }
}

bool UdpEndpoint::spend(Budget& b, double rate, Clock::time_point now) {
    b.tokens =
        std::min(rate, b.tokens + std::chrono::duration<double>(now - b.refilled).count() * rate);
    b.refilled = now;
    if (b.tokens < 1) {
        return false;
    }
    b.tokens -= 1;
    return true;
}

bool UdpEndpoint::within_handshake_budget(Clock::time_point now) {
    const auto rate = static_cast<double>(config_.udp_handshake_rate); // and the burst
    const SourceKey key = source_key(sender_.address());
    auto it = budgets_.find(key);
    if (it == budgets_.end()) {
        if (budgets_.size() >= kMaxBudgets) {
            return false; // every remembered source is spending: none new until a sweep
        }
        it = budgets_.emplace(key, Budget{rate, now}).first;
    }
    return spend(it->second, rate, now);
}

bool UdpEndpoint::read_handshake(DatagramKind kind, std::span<const std::uint8_t> body,
                                 std::span<const std::uint8_t>& cookie,
                                 std::span<const std::uint8_t>& hello) {
    if (const auto error = protocol::read_hello_body(kind, body, cookie, hello);
        error != protocol::DatagramError::none) {
        drop(udp_drop_of(error));
        return false;
    }
    return true;
}

void UdpEndpoint::on_request(std::uint64_t nonce, std::span<const std::uint8_t> body) {
    std::span<const std::uint8_t> cookie;
    std::span<const std::uint8_t> hello;
    if (!read_handshake(DatagramKind::request, body, cookie, hello)) {
        return;
    }
    // Not the sender's budget: a request proves nothing of its source address, and a
    // spoofer's requests must not lock that address out. The answers of all sources
    // together are capped instead.
    if (!spend(challenge_budget_, static_cast<double>(config_.udp_challenge_rate), Clock::now())) {
        drop(UdpDrop::over_challenge_rate);
        return;
    }
    const protocol::ChallengeCookie made = protocol::make_challenge_cookie(
        cookie_key_, source_address(sender_), nonce, cookie_now_ms());
    if (protocol::write_envelope_datagram({DatagramKind::challenge, nonce, 0}, made, nullptr,
                                          reply_)) {
        ++challenges_;
        send_to(sender_, reply_);
    }
}

void UdpEndpoint::on_response(std::uint64_t nonce, std::span<const std::uint8_t> body) {
    std::span<const std::uint8_t> cookie;
    std::span<const std::uint8_t> hello_bytes;
    if (!read_handshake(DatagramKind::response, body, cookie, hello_bytes)) {
        return;
    }
    // The cookie first: a response only a spoofer could send (one without the cookie its
    // address was given) must not spend that address's budget.
    switch (protocol::check_challenge_cookie(cookie_key_, cookie, source_address(sender_), nonce,
                                             cookie_now_ms(), kCookieLifetimeMs)) {
    case protocol::CookieStatus::valid:
        break;
    case protocol::CookieStatus::forged:
        drop(UdpDrop::forged_cookie);
        return;
    case protocol::CookieStatus::expired:
        drop(UdpDrop::expired_cookie);
        return;
    }
    // The address is proven from here on.
    if (!within_handshake_budget(Clock::now())) {
        drop(UdpDrop::rate_limited);
        return;
    }
    if (closed_nonces_.contains(nonce)) {
        drop(UdpDrop::closed_session); // a late or replayed response of a session now closed
        return;
    }
    if (const auto known = session_of_nonce_.find(nonce); known != session_of_nonce_.end()) {
        const auto it = by_session_.find(known->second);
        if (it != by_session_.end() && it->second->peer() == sender_) {
            it->second->resend_accepted(); // the accepted datagram was lost
        } else {
            drop(UdpDrop::wrong_source);
        }
        return;
    }
    pb::Envelope envelope;
    if (!envelope.ParseFromArray(hello_bytes.data(), static_cast<int>(hello_bytes.size())) ||
        !envelope.has_client_hello()) {
        drop(UdpDrop::bad_body);
        return;
    }
    std::uint64_t session = protocol::random_nonzero_u64();
    while (by_session_.contains(session)) {
        session = protocol::random_nonzero_u64();
    }
    auto connection = std::make_shared<UdpConnection>(*this, next_client_id_(), session, nonce,
                                                      sender_, config_, host_);
    by_session_.emplace(session, connection);
    session_of_nonce_.emplace(nonce, session);
    open_(connection); // as over TCP
    if (connection->state() == Connection::State::awaiting_hello) {
        connection->hello(envelope.client_hello());
    }
}

void UdpEndpoint::sweep() {
    if (stopped_) {
        return;
    }
    const auto now = Clock::now();
    std::vector<std::shared_ptr<UdpConnection>> open;
    open.reserve(by_session_.size());
    for (const auto& [session, connection] : by_session_) {
        open.push_back(connection);
    }
    for (const auto& connection : open) { // a timeout erases from by_session_
        connection->check_timeout(now);
    }
    std::erase_if(recently_closed_,
                  [&](const auto& entry) { return now - entry.second > kRememberClosed; });
    std::erase_if(closed_nonces_,
                  [&](const auto& entry) { return now - entry.second > kRememberClosed; });
    // Budgets back at their full burst are forgotten (a new one starts full anyway).
    const auto rate = static_cast<double>(config_.udp_handshake_rate);
    std::erase_if(budgets_, [&](const auto& entry) {
        return entry.second.tokens +
                   std::chrono::duration<double>(now - entry.second.refilled).count() * rate >=
               rate;
    });
    sweep_timer_.expires_after(kSweepPeriod);
    sweep_timer_.async_wait([this](const boost::system::error_code& ec) {
        if (!ec) {
            sweep();
        }
    });
}

} // namespace dsoc::server
