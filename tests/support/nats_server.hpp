#pragma once
// A real nats-server for tests: Debian's binary (scripts/setup installs package
// nats-server; $DSOC_NATS_SERVER names another), on loopback, on a free port, with
// its own temporary directory; stopped (SIGTERM, then SIGKILL) when destroyed.
// Tests call nats_server_binary() first and GTEST_SKIP with its reason when absent.

#include "support/child_process.hpp"

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

namespace dsoc::testing {

/// Why a test that needs nats-server is skipped when nats_server_binary() is "".
inline constexpr const char* kNoNatsServer =
    "nats-server not found (scripts/setup installs Debian's nats-server; or set "
    "DSOC_NATS_SERVER)";

/// The nats-server to run, or "" when there is none.
inline std::string nats_server_binary() {
    if (const char* named = std::getenv("DSOC_NATS_SERVER"); named != nullptr && *named != '\0') {
        return std::filesystem::exists(named) ? named : "";
    }
    for (const char* path :
         {"/usr/sbin/nats-server", "/usr/bin/nats-server", "/usr/local/bin/nats-server"}) {
        if (std::filesystem::exists(path)) {
            return path;
        }
    }
    return "";
}

/// A TCP port on 127.0.0.1 that nothing listened on a moment ago.
inline int free_loopback_port() {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof address;
    if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
        ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
        if (fd >= 0) {
            ::close(fd);
        }
        throw std::runtime_error("no free loopback port");
    }
    ::close(fd);
    return ntohs(address.sin_port);
}

/// True once something accepts TCP connections on 127.0.0.1:`port`.
inline bool accepting(int port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    address.sin_port = htons(static_cast<std::uint16_t>(port));
    const bool ok =
        fd >= 0 && ::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
    if (fd >= 0) {
        ::close(fd);
    }
    return ok;
}

class NatsServer {
public:
    /// Starts nats-server on a free loopback port; throws if it does not accept
    /// connections within 10 s.
    NatsServer() : port_(free_loopback_port()) { start(); }

    [[nodiscard]] std::string url() const { return "nats://127.0.0.1:" + std::to_string(port_); }
    [[nodiscard]] int port() const { return port_; }

    /// Stops the server (SIGTERM, then SIGKILL after 5 s).
    void stop() {
        if (process_) {
            process_->signal(SIGTERM);
            (void)process_->wait(std::chrono::seconds(5));
            process_.reset();
        }
    }
    /// Starts it again on the same port.
    void start() {
        process_ = std::make_unique<ChildProcess>(std::vector<std::string>{
            nats_server_binary(), "-a", "127.0.0.1", "-p", std::to_string(port_)});
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
        while (!accepting(port_)) {
            if (!process_->running() || std::chrono::steady_clock::now() > deadline) {
                throw std::runtime_error("nats-server did not start on port " +
                                         std::to_string(port_) + ": " + process_->err());
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
    }

private:
    int port_;
    std::unique_ptr<ChildProcess> process_;
};

} // namespace dsoc::testing
