#include "dsoc/scaleout/nats_link.hpp"

#include <nats/nats.h>

#include <string>

namespace dsoc::scaleout {

namespace {

natsConnection* conn(void* p) {
    return static_cast<natsConnection*>(p);
}

/// Throws NatsError naming `call` when `status` is not NATS_OK.
void check(natsStatus status, const std::string& call, const std::string& url) {
    if (status != NATS_OK) {
        const char* last = nats_GetLastError(nullptr);
        throw NatsError(call + " (" + url + "): " + natsStatus_GetText(status) +
                        (last != nullptr && *last != '\0' ? std::string(": ") + last : ""));
    }
}

/// The client's options, destroyed with the scope.
struct Options {
    natsOptions* p = nullptr;
    Options(const Options&) = delete;
    Options& operator=(const Options&) = delete;
    Options() = default;
    ~Options() { natsOptions_Destroy(p); }
};

void on_message(natsConnection* /*nc*/, natsSubscription* /*sub*/, natsMsg* msg, void* closure) {
    const char* reply = natsMsg_GetReply(msg);
    const NatsMessage message{natsMsg_GetSubject(msg),
                              {reinterpret_cast<const std::byte*>(natsMsg_GetData(msg)),
                               static_cast<std::size_t>(natsMsg_GetDataLength(msg))},
                              reply != nullptr ? std::string_view(reply) : std::string_view()};
    NatsSubscription::deliver(closure, message);
    natsMsg_Destroy(msg);
}

void on_complete(void* closure) {
    NatsSubscription::complete(closure);
}

void on_disconnected(natsConnection* /*nc*/, void* closure) {
    NatsLink::count_disconnect(closure);
}

void on_reconnected(natsConnection* /*nc*/, void* closure) {
    NatsLink::count_reconnect(closure);
}

void on_closed(natsConnection* /*nc*/, void* closure) {
    NatsLink::mark_closed(closure);
}

} // namespace

void NatsSubscription::deliver(void* closure, const NatsMessage& message) {
    static_cast<NatsSubscription*>(closure)->handler_(message);
}

void NatsSubscription::complete(void* closure) {
    auto* self = static_cast<NatsSubscription*>(closure);
    const std::lock_guard lock(self->mutex_);
    self->complete_ = true;
    self->completed_.notify_all();
}

NatsSubscription::~NatsSubscription() {
    auto* sub = static_cast<natsSubscription*>(sub_);
    if (sub == nullptr) {
        return;
    }
    // Unsubscribe, then wait until the client has returned from the last handler call
    // (its completion callback, which the client makes for every closed asynchronous
    // subscription): a handler still running must not find this object gone.
    if (natsSubscription_Unsubscribe(sub) == NATS_OK) {
        std::unique_lock lock(mutex_);
        completed_.wait(lock, [this] { return complete_; });
    }
    natsSubscription_Destroy(sub);
}

std::uint64_t NatsSubscription::dropped() const {
    int64_t dropped = 0;
    (void)natsSubscription_GetDropped(static_cast<natsSubscription*>(sub_), &dropped);
    return static_cast<std::uint64_t>(dropped);
}

void NatsLink::count_disconnect(void* closure) {
    ++static_cast<NatsLink*>(closure)->disconnects_;
}

void NatsLink::count_reconnect(void* closure) {
    ++static_cast<NatsLink*>(closure)->reconnects_;
}

void NatsLink::mark_closed(void* closure) {
    auto* self = static_cast<NatsLink*>(closure);
    const std::lock_guard lock(self->closed_mutex_);
    self->closed_ = true;
    self->closed_cv_.notify_all();
}

NatsLink::NatsLink(NatsLinkOptions options) : options_(std::move(options)) {
    const std::string& url = options_.url;
    Options o;
    check(natsOptions_Create(&o.p), "natsOptions_Create", url);
    check(natsOptions_SetServers(o.p, nullptr, 0), "natsOptions_SetServers", url);
    check(natsOptions_SetURL(o.p, url.c_str()), "natsOptions_SetURL", url);
    check(natsOptions_SetName(o.p, options_.name.c_str()), "natsOptions_SetName", url);
    check(natsOptions_SetTimeout(o.p, options_.connect_timeout_ms), "natsOptions_SetTimeout", url);
    check(natsOptions_SetAllowReconnect(o.p, true), "natsOptions_SetAllowReconnect", url);
    check(natsOptions_SetMaxReconnect(o.p, -1), "natsOptions_SetMaxReconnect", url); // forever
    check(natsOptions_SetReconnectWait(o.p, options_.reconnect_wait_ms),
          "natsOptions_SetReconnectWait", url);
    check(natsOptions_SetDisconnectedCB(o.p, on_disconnected, this),
          "natsOptions_SetDisconnectedCB", url);
    check(natsOptions_SetReconnectedCB(o.p, on_reconnected, this), "natsOptions_SetReconnectedCB",
          url);
    check(natsOptions_SetClosedCB(o.p, on_closed, this), "natsOptions_SetClosedCB", url);
    natsConnection* c = nullptr;
    check(natsConnection_Connect(&c, o.p), "connect", url);
    conn_ = c;
}

NatsLink::~NatsLink() {
    if (conn_ != nullptr) {
        // The client calls its disconnected callback, then the closed one, on a thread of
        // its own after Close returns: both hold `this`, so wait for the last of them.
        natsConnection_Close(conn(conn_));
        {
            std::unique_lock lock(closed_mutex_);
            closed_cv_.wait(lock, [this] { return closed_; });
        }
        natsConnection_Destroy(conn(conn_));
    }
}

bool NatsLink::publish(std::string_view subject, std::span<const std::byte> data) {
    const std::string s(subject);
    return natsConnection_Publish(conn(conn_), s.c_str(), data.data(),
                                  static_cast<int>(data.size())) == NATS_OK;
}

bool NatsLink::publish_request(std::string_view subject, std::string_view reply,
                               std::span<const std::byte> data) {
    const std::string s(subject);
    const std::string r(reply);
    return natsConnection_PublishRequest(conn(conn_), s.c_str(), r.c_str(), data.data(),
                                         static_cast<int>(data.size())) == NATS_OK;
}

std::string NatsLink::new_inbox() {
    natsInbox* inbox = nullptr;
    if (natsInbox_Create(&inbox) != NATS_OK) {
        throw NatsError("natsInbox_Create failed");
    }
    std::string name(inbox);
    natsInbox_Destroy(inbox);
    return name;
}

std::unique_ptr<NatsSubscription>
NatsLink::subscribe(std::string_view subject, std::function<void(const NatsMessage&)> handler,
                    int pending_limit) {
    std::unique_ptr<NatsSubscription> subscription(new NatsSubscription(std::move(handler)));
    const std::string s(subject);
    natsSubscription* sub = nullptr;
    check(natsConnection_Subscribe(&sub, conn(conn_), s.c_str(), on_message, subscription.get()),
          "subscribe to " + s, options_.url);
    subscription->sub_ = sub;
    check(natsSubscription_SetOnCompleteCB(sub, on_complete, subscription.get()),
          "completion callback of " + s, options_.url);
    if (pending_limit > 0) {
        check(natsSubscription_SetPendingLimits(sub, pending_limit, -1), "pending limits of " + s,
              options_.url);
    }
    return subscription;
}

std::optional<std::vector<std::byte>> NatsLink::request(std::string_view subject,
                                                        std::span<const std::byte> data,
                                                        std::chrono::milliseconds timeout) {
    const std::string s(subject);
    natsMsg* reply = nullptr;
    if (natsConnection_Request(&reply, conn(conn_), s.c_str(), data.data(),
                               static_cast<int>(data.size()), timeout.count()) != NATS_OK) {
        return std::nullopt;
    }
    const auto* bytes = reinterpret_cast<const std::byte*>(natsMsg_GetData(reply));
    std::vector<std::byte> out(bytes, bytes + natsMsg_GetDataLength(reply));
    natsMsg_Destroy(reply);
    return out;
}

bool NatsLink::flush(std::chrono::milliseconds timeout) {
    return natsConnection_FlushTimeout(conn(conn_), timeout.count()) == NATS_OK;
}

bool NatsLink::connected() const {
    return natsConnection_Status(conn(conn_)) == NATS_CONN_STATUS_CONNECTED;
}

} // namespace dsoc::scaleout
