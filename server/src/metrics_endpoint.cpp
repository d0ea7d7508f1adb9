#include "dsoc/server/metrics_endpoint.hpp"

#include "dsoc/server/metrics.hpp"

#include <boost/beast/core/flat_buffer.hpp>
#include <boost/beast/core/tcp_stream.hpp>
#include <boost/beast/http/read.hpp>
#include <boost/beast/http/string_body.hpp>
#include <boost/beast/http/write.hpp>
#include <spdlog/spdlog.h>

#include <memory>

namespace dsoc::server {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;

namespace {

constexpr std::size_t kMaxRequestBytes = 8 * 1024;
constexpr auto kRequestTimeout = std::chrono::seconds(5);

/// One request: read it, answer, close.
class Exchange : public std::enable_shared_from_this<Exchange> {
public:
    Exchange(asio::ip::tcp::socket socket, const MetricsEndpoint::Render& render,
             const MetricsEndpoint::Ready& ready, std::uint64_t& served)
        : stream_(std::move(socket)), render_(render), ready_(ready), served_(served) {}

    void start() {
        parser_.header_limit(kMaxRequestBytes);
        parser_.body_limit(kMaxRequestBytes);
        stream_.expires_after(kRequestTimeout);
        http::async_read(stream_, buffer_, parser_,
                         [self = shared_from_this()](beast::error_code ec, std::size_t) {
                             if (!ec) {
                                 self->respond();
                             }
                         });
    }

private:
    void respond() {
        const auto& request = parser_.get();
        const auto target = request.target();
        response_.version(request.version());
        response_.keep_alive(false);
        response_.set(http::field::server, "dsoc-server");
        if (target != "/metrics" && target != "/healthz" && target != "/readyz") {
            text(http::status::not_found, "not found: /metrics, /healthz and /readyz are here\n");
        } else if (request.method() != http::verb::get) {
            response_.set(http::field::allow, "GET");
            text(http::status::method_not_allowed, "only GET\n");
        } else if (target == "/healthz") {
            text(http::status::ok, "ok\n");
        } else if (target == "/readyz") {
            const Readiness readiness = ready_ ? ready_() : Readiness{true, {}};
            if (readiness.ready) {
                text(http::status::ok, "ready\n");
            } else {
                text(http::status::service_unavailable, "not ready: " + readiness.why + "\n");
            }
        } else {
            response_.result(http::status::ok);
            response_.set(http::field::content_type, std::string(kPrometheusContentType));
            response_.body() = render_();
            ++served_;
        }
        response_.prepare_payload();
        http::async_write(
            stream_, response_, [self = shared_from_this()](beast::error_code, std::size_t) {
                beast::error_code ignored;
                self->stream_.socket().shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
            });
    }

    void text(http::status status, std::string body) {
        response_.result(status);
        response_.set(http::field::content_type, "text/plain; charset=utf-8");
        response_.body() = std::move(body);
    }

    beast::tcp_stream stream_;
    beast::flat_buffer buffer_;
    http::request_parser<http::string_body> parser_;
    http::response<http::string_body> response_;
    const MetricsEndpoint::Render& render_;
    const MetricsEndpoint::Ready& ready_;
    std::uint64_t& served_;
};

} // namespace

MetricsEndpoint::MetricsEndpoint(asio::io_context& io, Render render, Ready ready)
    : acceptor_(io), render_(std::move(render)), ready_(std::move(ready)) {}

std::uint16_t MetricsEndpoint::start(const std::string& address, std::uint16_t port) {
    const asio::ip::tcp::endpoint endpoint(asio::ip::make_address(address), port);
    acceptor_.open(endpoint.protocol());
    acceptor_.set_option(asio::socket_base::reuse_address(true));
    acceptor_.bind(endpoint);
    acceptor_.listen();
    accept_next();
    return acceptor_.local_endpoint().port();
}

void MetricsEndpoint::stop() {
    beast::error_code ignored;
    acceptor_.close(ignored);
}

void MetricsEndpoint::accept_next() {
    acceptor_.async_accept([this](beast::error_code ec, asio::ip::tcp::socket socket) {
        if (ec) {
            if (ec != asio::error::operation_aborted) {
                spdlog::warn("metrics: accept failed: {}", ec.message());
                accept_next();
            }
            return;
        }
        std::make_shared<Exchange>(std::move(socket), render_, ready_, requests_served_)->start();
        accept_next();
    });
}

} // namespace dsoc::server
