#pragma once
// A minimal HTTP/1.1 endpoint (Boost.Beast) that answers GET /metrics with the text
// `render` returns, for Prometheus to scrape. Anything else gets 404 (other paths)
// or 405 (other methods than GET). One request per connection; requests over 8 KiB or
// slower than 5 s are dropped, so a scraper cannot hold resources.
//
// Threading: runs on the io_context given to it and calls `render` there; with the
// server on the same single-threaded io_context, render may read the server freely.

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>

#include <cstdint>
#include <functional>
#include <string>

namespace dsoc::server {

class MetricsEndpoint {
public:
    using Render = std::function<std::string()>;

    MetricsEndpoint(boost::asio::io_context& io, Render render);

    /// Binds and starts accepting. Returns the bound port (port 0 picks a free one).
    /// Throws boost::system::system_error when the address cannot be bound.
    std::uint16_t start(const std::string& address, std::uint16_t port);

    /// Stops accepting; connections in progress finish on their own.
    void stop();

    [[nodiscard]] std::uint64_t requests_served() const { return requests_served_; }

private:
    void accept_next();

    boost::asio::ip::tcp::acceptor acceptor_;
    Render render_;
    std::uint64_t requests_served_ = 0;
};

} // namespace dsoc::server
