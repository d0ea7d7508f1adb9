#pragma once
// A connection to a NATS server (the world process and the interest gateways talk
// through one), over the NATS C client: publish, subscribe, request. It reconnects on
// its own after the server goes away (forever, every `reconnect_wait_ms`); what is
// published meanwhile is buffered by the client up to its reconnect buffer and then
// refused (publish() returns false). Callbacks run on the client's threads, never on
// the caller's: hand work over to your own loop.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace dsoc::scaleout {

/// A NATS call failed: the message names the call, the server and the client's reason.
class NatsError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct NatsLinkOptions {
    /// "nats://host:port" (several, comma-separated: tried in turn).
    std::string url = "nats://127.0.0.1:4222";
    /// How this client names itself to the server (its monitoring shows it).
    std::string name = "dsoc";
    /// Between reconnection attempts. [Units: ms] [Limit: >= 10]
    int reconnect_wait_ms = 250;
    /// How long connect() waits for a first connection. [Units: ms] [Limit: >= 10]
    int connect_timeout_ms = 2000;
};

/// One message as a subscriber sees it. The views live for the callback only.
struct NatsMessage {
    std::string_view subject;
    std::span<const std::byte> data;
    std::string_view reply; ///< "" unless the sender waits for an answer (request())
};

class NatsLink;

/// A subscription; unsubscribes when destroyed, and no callback runs after the
/// destructor returns. Destroy it before its NatsLink, and never from its own handler.
class NatsSubscription {
public:
    NatsSubscription(NatsSubscription&&) = delete;
    NatsSubscription& operator=(NatsSubscription&&) = delete;
    ~NatsSubscription();
    /// Messages the client dropped because this subscriber fell behind its pending
    /// limit (NatsLink::subscribe's `pending_limit`).
    [[nodiscard]] std::uint64_t dropped() const;

private:
    friend class NatsLink;
    using Handler = std::function<void(const NatsMessage&)>;
    explicit NatsSubscription(Handler handler) : handler_(std::move(handler)) {}
    Handler handler_;
    void* sub_ = nullptr; ///< the client's natsSubscription
    std::mutex mutex_;
    std::condition_variable completed_;
    bool complete_ = false; ///< the client called its last handler for this subscription

public:
    /// For the client's callbacks (nats_link.cpp): a message, and the end of delivery.
    static void deliver(void* closure, const NatsMessage& message);
    static void complete(void* closure);
};

class NatsLink {
public:
    /// Connects; throws NatsError when no server answers within connect_timeout_ms.
    explicit NatsLink(NatsLinkOptions options);
    NatsLink(const NatsLink&) = delete;
    NatsLink& operator=(const NatsLink&) = delete;
    ~NatsLink();

    /// Publishes `data` on `subject`. False (nothing sent) when the connection is
    /// closed or the client's buffer for a reconnection is full.
    bool publish(std::string_view subject, std::span<const std::byte> data);
    /// Publishes `data` on `subject` with `reply` as the subject to answer on (a request
    /// whose answer arrives on a subscription of the caller's, not in a wait).
    bool publish_request(std::string_view subject, std::string_view reply,
                         std::span<const std::byte> data);
    /// A subject of its own for answers ("_INBOX.<unique>").
    [[nodiscard]] static std::string new_inbox();
    /// Calls `handler` for every message on `subject` (NATS wildcards allowed), one at a
    /// time, on a client thread. With `pending_limit` > 0, messages beyond that many
    /// waiting for the handler are dropped (counted): a slow subscriber skips ahead
    /// rather than falling further behind.
    [[nodiscard]] std::unique_ptr<NatsSubscription>
    subscribe(std::string_view subject, std::function<void(const NatsMessage&)> handler,
              int pending_limit = 0);
    /// Publishes `data` on `subject` and waits up to `timeout` for one reply; nothing on
    /// timeout or without a connection.
    [[nodiscard]] std::optional<std::vector<std::byte>> request(std::string_view subject,
                                                                std::span<const std::byte> data,
                                                                std::chrono::milliseconds timeout);
    /// Waits until the server has everything published so far; false on timeout.
    bool flush(std::chrono::milliseconds timeout);

    /// Whether the connection is up now.
    [[nodiscard]] bool connected() const;
    /// Connections lost and regained since connect.
    [[nodiscard]] std::uint64_t disconnects() const { return disconnects_.load(); }
    [[nodiscard]] std::uint64_t reconnects() const { return reconnects_.load(); }
    [[nodiscard]] const std::string& url() const { return options_.url; }

private:
public:
    /// For the client's callbacks (nats_link.cpp).
    static void count_disconnect(void* closure);
    static void count_reconnect(void* closure);
    static void mark_closed(void* closure);

private:
    NatsLinkOptions options_;
    void* conn_ = nullptr; ///< the client's natsConnection
    std::atomic<std::uint64_t> disconnects_{0};
    std::atomic<std::uint64_t> reconnects_{0};
    std::mutex closed_mutex_; ///< the client's closed callback, awaited by the destructor
    std::condition_variable closed_cv_;
    bool closed_ = false;
};

} // namespace dsoc::scaleout
