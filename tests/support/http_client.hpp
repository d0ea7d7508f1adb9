#pragma once
// One HTTP/1.1 request to a server on 127.0.0.1, for tests of the metrics endpoint:
// connect, send, read until the server closes (it answers one request a connection).

#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>

#include <cstdint>
#include <string>

namespace dsoc::testing {

/// Sends `request` to 127.0.0.1:port and returns the whole response (empty when the
/// server closes without answering). Throws boost::system::system_error when the
/// connection is refused.
inline std::string http_exchange(std::uint16_t port, const std::string& request) {
    boost::asio::io_context io;
    boost::asio::ip::tcp::socket socket(io);
    socket.connect({boost::asio::ip::make_address("127.0.0.1"), port});
    boost::asio::write(socket, boost::asio::buffer(request));
    std::string response;
    boost::system::error_code ec;
    boost::asio::read(socket, boost::asio::dynamic_buffer(response), ec);
    return response;
}

/// GET `path`: the whole response, status line first ("HTTP/1.1 200 OK\r\n...").
inline std::string http_get(std::uint16_t port, const std::string& path) {
    return http_exchange(port, "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
}

/// The status code of a response ("HTTP/1.1 503 ..." -> 503), 0 when there is none.
inline int http_status(const std::string& response) {
    const auto space = response.find(' ');
    if (response.rfind("HTTP/", 0) != 0 || space == std::string::npos) {
        return 0;
    }
    return std::atoi(response.c_str() + space + 1);
}

/// The body of a response (after the blank line), empty when there is none.
inline std::string http_body(const std::string& response) {
    const auto end = response.find("\r\n\r\n");
    return end == std::string::npos ? std::string() : response.substr(end + 4);
}

} // namespace dsoc::testing
