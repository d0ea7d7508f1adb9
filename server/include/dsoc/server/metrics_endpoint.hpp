#pragma once
// A minimal HTTP/1.1 endpoint (Boost.Beast) for the operator's probes:
// - GET /metrics: the text `render` returns, for Prometheus to scrape;
// - GET /healthz: 200 "ok" while the process answers at all (liveness);
// - GET /readyz: 200 "ready" when `ready` says so, else 503 "not ready: <why>"
//   (readiness: take players, or route none here).
// Anything else gets 404 (other paths) or 405 (other methods than GET). One request per
// connection; requests over 8 KiB or slower than 5 s are dropped, so a scraper cannot
// hold resources.
//
// Threading: runs on the io_context given to it and calls `render` and `ready` there;
// with the server on the same single-threaded io_context, they may read the server
// freely.

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>

#include <cstdint>
#include <functional>
#include <string>

namespace dsoc::server {

/// The answer to /readyz.
struct Readiness {
    bool ready = false;
    std::string why; ///< when not ready, in words: "loading map 'oa_dm4'", "shutting down"
};

class MetricsEndpoint {
public:
    using Render = std::function<std::string()>;
    using Ready = std::function<Readiness()>;

    /// Without `ready`, /readyz answers as /healthz does.
    MetricsEndpoint(boost::asio::io_context& io, Render render, Ready ready = {});

    /// Binds and starts accepting. Returns the bound port (port 0 picks a free one).
    /// Throws boost::system::system_error when the address cannot be bound.
    std::uint16_t start(const std::string& address, std::uint16_t port);

    /// Stops accepting; connections in progress finish on their own.
    void stop();

    /// /metrics requests answered (the probes are not counted).
    [[nodiscard]] std::uint64_t requests_served() const { return requests_served_; }

private:
    void accept_next();

    boost::asio::ip::tcp::acceptor acceptor_;
    Render render_;
    Ready ready_;
    std::uint64_t requests_served_ = 0;
};

} // namespace dsoc::server
