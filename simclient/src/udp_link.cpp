#include "dsoc/simclient/udp_link.hpp"

#include "dsoc/protocol/challenge_cookie.hpp"
#include "dsoc/protocol/codec.hpp"
#include "dsoc/simclient/receive_time.hpp"

#include <boost/asio/buffer.hpp>

#include <algorithm>

namespace dsoc::simclient {

namespace asio = boost::asio;
namespace pb = protocol::pb;
using protocol::DatagramKind;

namespace {
constexpr auto kHandshakeRetry = std::chrono::milliseconds(250);
/// The first block of a thread's decoding arena: a whole snapshot fits.
constexpr std::size_t kIncomingArenaBytes = 256 * 1024;
} // namespace

UdpLink::UdpLink(asio::io_context& io, Handlers handlers, const DatagramFaults& faults,
                 std::uint64_t seed)
    : handlers_(std::move(handlers)), socket_(io), retry_timer_(io), faults_(faults), rng_(seed) {}

bool UdpLink::connect(std::vector<asio::ip::udp::endpoint> servers, const pb::Envelope& hello,
                      std::shared_ptr<void> owner, std::string& error) {
    owner_ = owner;
    servers_ = std::move(servers);
    next_server_ = 0;
    tried_.clear();
    nonce_ = protocol::random_nonzero_u64();
    if (servers_.empty()) {
        error = "no address to send to";
        return false;
    }
    if (!protocol::write_request(nonce_, hello, request_) ||
        !protocol::write_response(nonce_, protocol::ChallengeCookie{}, hello, response_)) {
        error = "the hello does not fit in one datagram";
        return false;
    }
    response_.clear(); // written for real once the cookie arrives
    if (!open_next_that_opens(error)) {
        return false;
    }
    retry_handshake();
    return true;
}

bool UdpLink::open_next(std::string& error) {
    server_ = servers_[next_server_++];
    boost::system::error_code ec;
    socket_.close(ec); // the address tried before, if any
    socket_.open(server_.protocol(), ec);
    if (!ec) {
        socket_.connect(server_, ec); // the kernel then drops datagrams from anywhere else
    }
    if (ec) {
        error = server_name() + ": cannot open a UDP socket towards it: " + ec.message();
        return false;
    }
    socket_.non_blocking(true, ec);
    enable_receive_times(socket_.native_handle());
    receive_next();
    send(request_);
    return true;
}

bool UdpLink::open_next_that_opens(std::string& error) {
    error.clear();
    while (next_server_ < servers_.size()) {
        std::string why;
        if (open_next(why)) {
            return true;
        }
        error += (error.empty() ? "" : "; ") + why;
        tried_.push_back(std::move(why));
    }
    return false;
}

std::string UdpLink::server_name() const {
    const std::string host = server_.address().to_string();
    const std::string port = std::to_string(server_.port());
    return server_.address().is_v6() ? "[" + host + "]:" + port : host + ":" + port;
}

void UdpLink::retry_handshake() {
    auto keep = owner_.lock();
    if (!keep) {
        return;
    }
    retry_timer_.expires_after(kHandshakeRetry);
    retry_timer_.async_wait([this, keep](const boost::system::error_code& ec) {
        if (ec || closed_ || session_ != 0) {
            return;
        }
        send(response_.empty() ? request_ : response_);
        retry_handshake();
    });
}

void UdpLink::send_message(const pb::Envelope& message) {
    if (session_ == 0 || closed_) {
        return;
    }
    if (protocol::write_envelope_datagram({DatagramKind::message, session_, next_sequence_}, {},
                                          &message, datagram_)) {
        ++next_sequence_;
        send(datagram_);
    }
}

void UdpLink::send_input(const pb::ClientInput& input, std::uint64_t ack) {
    // The newest first, in place: the oldest message's memory takes the new input (an
    // input every tick; no allocation once three are held).
    if (recent_inputs_.size() < protocol::kMaxRedundantInputs) {
        recent_inputs_.emplace_back();
    }
    std::rotate(recent_inputs_.rbegin(), recent_inputs_.rbegin() + 1, recent_inputs_.rend());
    recent_inputs_.front() = input;
    if (session_ == 0 || closed_) {
        return;
    }
    if (protocol::write_input({DatagramKind::input, session_, next_sequence_}, ack, recent_inputs_,
                              datagram_)) {
        ++next_sequence_;
        send(datagram_);
    }
}

void UdpLink::close() {
    closed_ = true;
    retry_timer_.cancel();
    boost::system::error_code ec;
    socket_.close(ec);
}

bool UdpLink::happens(double probability) {
    return probability > 0.0 && std::bernoulli_distribution(probability)(rng_);
}

void UdpLink::send(std::span<const std::uint8_t> datagram) {
    if (happens(faults_.loss)) {
        ++emulated_losses_;
        return;
    }
    if (held_out_.empty() && happens(faults_.reorder)) {
        held_out_.assign(datagram.begin(), datagram.end()); // goes after the next one
        return;
    }
    transmit(datagram);
    if (happens(faults_.duplicate)) {
        transmit(datagram);
    }
    if (!held_out_.empty()) {
        std::vector<std::uint8_t> held;
        held.swap(held_out_);
        transmit(held);
    }
}

void UdpLink::transmit(std::span<const std::uint8_t> datagram) {
    boost::system::error_code ec;
    const std::size_t n = socket_.send(asio::buffer(datagram.data(), datagram.size()), 0, ec);
    if (!ec && handlers_.on_bytes_up) {
        handlers_.on_bytes_up(n);
    }
}

void UdpLink::receive_next() {
    // Woken when the socket has something, then every datagram waiting is read, up to
    // kReadBatch to a system call, each with its arrival (receive_time.hpp): a snapshot's
    // datagrams come together, and a read apiece cost a read that found nothing before
    // each wait. The reactor wakes on new data only (edge-triggered), so the socket is
    // drained before waiting again: until a read finds it empty or returns fewer than it
    // asked for (asio's wait re-arms the registration, which reports data that came since).
    // The wait holds the owner weakly (no cycle through the socket): a link closed, or
    // destroyed with its owner, still completes it (aborted), and its handler must then
    // not touch `this`, which may be gone.
    socket_.async_wait(asio::socket_base::wait_read,
                       [this, owner = owner_](const boost::system::error_code& ec) {
                           const auto keep = owner.lock();
                           if (!keep || ec == asio::error::operation_aborted || closed_) {
                               return;
                           }
                           if (ec) { // waiting again would fail again, at once
                               stop_reading("its wait failed: " + ec.message());
                               return;
                           }
                           if (!drain()) {
                               return; // moved to another address, closed or given up
                           }
                           if (!closed_) {
                               receive_next();
                           }
                       });
}

bool UdpLink::drain() {
    std::array<std::span<std::uint8_t>, kReadBatch> buffers;
    for (std::size_t k = 0; k < kReadBatch; ++k) {
        buffers[k] = buffers_[k];
    }
    bool read_any = false;
    for (;;) {
        const std::size_t got = receive_stamped(socket_.native_handle(), buffers, reads_);
        if (got == 0) {
            const int error = reads_[0].error;
            if (error == EAGAIN || error == EWOULDBLOCK) {
                // Woken with nothing to read: a socket shut down for reading is reported
                // readable for ever, with nothing after what was queued, so waiting again
                // would spin.
                if (!read_any && shut_down_for_reading(socket_.native_handle())) {
                    stop_reading("it is shut down for reading");
                    return false;
                }
                return true;
            }
            if (error == ECONNREFUSED) {
                if (session_ != 0 || refusal_reported_) {
                    continue; // a lost server shows as silence; the owner knows already
                }
                // Nothing listens at this address: the next one the name resolved to, as
                // a TCP connect tries each, or the owner's to decide.
                tried_.push_back(
                    server_name() + ": " +
                    boost::system::error_code(ECONNREFUSED, boost::system::system_category())
                        .message());
                std::string why;
                if (open_next_that_opens(why)) {
                    return false; // receiving on the new socket
                }
                refusal_reported_ = true;
                if (handlers_.on_refused) {
                    std::string all;
                    for (const std::string& t : tried_) {
                        all += (all.empty() ? "" : "; ") + t;
                    }
                    handlers_.on_refused(all);
                }
                return !closed_; // the owner closes the link
            }
            return true; // another error of the socket (none expected): wait again
        }
        read_any = true;
        for (std::size_t k = 0; k < got; ++k) {
            arrival_ = reads_[k].arrival;
            on_datagram(std::span<const std::uint8_t>(buffers_[k].data(), reads_[k].bytes));
            if (closed_) {
                return false;
            }
        }
        if (got < kReadBatch) {
            // None was left when they were read, or an error followed them; a datagram
            // that came since, or the error, wakes the next wait (asio re-arms the
            // edge-triggered registration, which reports what is waiting).
            return true;
        }
    }
}

void UdpLink::stop_reading(const std::string& why) {
    if (handlers_.on_socket_error) {
        handlers_.on_socket_error("UDP socket towards " + server_name() +
                                  " can no longer be read: " + why);
    }
}

void UdpLink::on_datagram(std::span<const std::uint8_t> datagram) {
    if (handlers_.on_bytes_down) {
        handlers_.on_bytes_down(datagram.size());
    }
    if (happens(faults_.loss)) {
        ++emulated_losses_;
        return;
    }
    if (held_in_.empty() && happens(faults_.reorder)) {
        held_in_.assign(datagram.begin(), datagram.end()); // handled after the next one
        return;
    }
    process(datagram);
    if (!closed_ && happens(faults_.duplicate)) {
        process(datagram);
    }
    if (!closed_ && !held_in_.empty()) {
        std::vector<std::uint8_t> held;
        held.swap(held_in_);
        process(held);
    }
}

void UdpLink::process(std::span<const std::uint8_t> datagram) {
    protocol::DatagramHeader header;
    std::span<const std::uint8_t> body;
    if (protocol::read_datagram(datagram, header, body) != protocol::DatagramError::none) {
        ++dropped_;
        return;
    }
    thread_local protocol::EnvelopeArena incoming(kIncomingArenaBytes);
    const pb::Envelope* message = nullptr;
    switch (header.kind) {
    case DatagramKind::challenge:
        if (header.session != nonce_ || session_ != 0 || body.size() != protocol::kCookieBytes) {
            ++dropped_;
            return;
        }
        if (response_.empty()) {
            pb::Envelope hello;
            std::span<const std::uint8_t> cookie;
            std::span<const std::uint8_t> hello_bytes;
            // The request holds the hello: read it back rather than keep a copy.
            const auto request_body =
                std::span<const std::uint8_t>(request_).subspan(protocol::kDatagramHeaderBytes);
            if (protocol::read_hello_body(DatagramKind::request, request_body, cookie,
                                          hello_bytes) != protocol::DatagramError::none ||
                !hello.ParseFromArray(hello_bytes.data(), static_cast<int>(hello_bytes.size())) ||
                !protocol::write_response(nonce_, body, hello, response_)) {
                handlers_.on_error("udp_response_unwritable");
                return;
            }
        }
        send(response_);
        return;
    case DatagramKind::accepted: {
        std::uint64_t session = 0;
        std::span<const std::uint8_t> envelope;
        if (header.session != nonce_ || session_ != 0 ||
            protocol::read_accepted_body(body, session, envelope) !=
                protocol::DatagramError::none ||
            incoming.decode(envelope, message) != protocol::DecodeError::none) {
            ++dropped_;
            return;
        }
        session_ = session;
        retry_timer_.cancel();
        handlers_.on_envelope(*message);
        return;
    }
    case DatagramKind::message:
    case DatagramKind::snapshot:
        break;
    default:
        ++dropped_;
        return;
    }
    if (session_ == 0 || header.session != session_ || !window_.accept(header.sequence)) {
        ++dropped_;
        return;
    }
    if (header.kind == DatagramKind::message) {
        if (incoming.decode(body, message) != protocol::DecodeError::none) {
            handlers_.on_error("undecodable_message");
            return;
        }
        handlers_.on_envelope(*message);
        return;
    }
    protocol::SnapshotFragment fragment;
    if (protocol::read_snapshot_body(body, fragment) != protocol::DatagramError::none) {
        handlers_.on_error("bad_snapshot_fragment");
        return;
    }
    std::span<const std::uint8_t> whole;
    if (assembler_.add(fragment, whole) != protocol::SnapshotAssembler::Result::complete) {
        return;
    }
    if (incoming.decode(whole, message) != protocol::DecodeError::none ||
        !message->has_snapshot()) {
        handlers_.on_error("undecodable_snapshot");
        return;
    }
    handlers_.on_envelope(*message);
}

} // namespace dsoc::simclient
