#pragma once
// A TCP forwarder on loopback between one client and a server, for tests that cut one
// process's connection while the others keep theirs (a NATS client cut off from its
// server: the world process's link down while the gateways' stay up). Everything
// accepted on port() is relayed to 127.0.0.1:`target_port`, both ways, until cut().
// While cut, every connection is closed and new ones are closed as soon as accepted
// (a client sees its server go away and its reconnections fail); restore() lets them
// through again. Its own thread; stopped when destroyed.

#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace dsoc::testing {

class TcpProxy {
public:
    explicit TcpProxy(int target_port) : target_port_(target_port) {
        listener_ = ::socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in address = loopback(0);
        socklen_t length = sizeof address;
        if (listener_ < 0 ||
            ::bind(listener_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
            ::listen(listener_, 16) != 0 ||
            ::getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
            throw std::runtime_error("TcpProxy: cannot listen on loopback");
        }
        port_ = ntohs(address.sin_port);
        thread_ = std::thread([this] { run(); });
    }
    TcpProxy(const TcpProxy&) = delete;
    TcpProxy& operator=(const TcpProxy&) = delete;
    ~TcpProxy() {
        stop_ = true;
        thread_.join();
        for (const auto& [a, b] : pairs_) {
            ::close(a);
            ::close(b);
        }
        ::close(listener_);
    }

    [[nodiscard]] int port() const { return port_; }
    [[nodiscard]] std::string url() const { return "nats://127.0.0.1:" + std::to_string(port_); }
    /// Closes every relayed connection and refuses new ones (effective within 10 ms).
    void cut() { cut_ = true; }
    /// Relays new connections again.
    void restore() { cut_ = false; }

private:
    static sockaddr_in loopback(int port) {
        sockaddr_in address{};
        address.sin_family = AF_INET;
        address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        address.sin_port = htons(static_cast<std::uint16_t>(port));
        return address;
    }
    /// Reads what `from` has and writes all of it to `to`; false when `from` ended.
    static bool relay(int from, int to) {
        char buffer[16384];
        const ssize_t n = ::read(from, buffer, sizeof buffer);
        if (n <= 0) {
            return false;
        }
        for (ssize_t done = 0; done < n;) {
            const ssize_t w = ::write(to, buffer + done, static_cast<std::size_t>(n - done));
            if (w <= 0) {
                return false;
            }
            done += w;
        }
        return true;
    }
    void close_all() {
        for (const auto& [a, b] : pairs_) {
            ::close(a);
            ::close(b);
        }
        pairs_.clear();
    }
    void run() {
        while (!stop_) {
            if (cut_) {
                close_all();
            }
            std::vector<pollfd> fds{{listener_, POLLIN, 0}};
            for (const auto& [a, b] : pairs_) {
                fds.push_back({a, POLLIN, 0});
                fds.push_back({b, POLLIN, 0});
            }
            if (::poll(fds.data(), fds.size(), 10) <= 0) {
                continue;
            }
            std::vector<std::size_t> ended;
            for (std::size_t i = 0; i < pairs_.size(); ++i) {
                const auto [a, b] = pairs_[i];
                if (((fds[1 + 2 * i].revents & (POLLIN | POLLHUP | POLLERR)) != 0 &&
                     !relay(a, b)) ||
                    ((fds[2 + 2 * i].revents & (POLLIN | POLLHUP | POLLERR)) != 0 &&
                     !relay(b, a))) {
                    ended.push_back(i);
                }
            }
            for (auto it = ended.rbegin(); it != ended.rend(); ++it) {
                ::close(pairs_[*it].first);
                ::close(pairs_[*it].second);
                pairs_.erase(pairs_.begin() + static_cast<long>(*it));
            }
            if ((fds[0].revents & POLLIN) != 0) {
                accept_one();
            }
        }
    }
    void accept_one() {
        const int client = ::accept(listener_, nullptr, nullptr);
        if (client < 0) {
            return;
        }
        if (cut_) {
            ::close(client);
            return;
        }
        const int server = ::socket(AF_INET, SOCK_STREAM, 0);
        const sockaddr_in target = loopback(target_port_);
        if (server < 0 ||
            ::connect(server, reinterpret_cast<const sockaddr*>(&target), sizeof target) != 0) {
            ::close(client);
            if (server >= 0) {
                ::close(server);
            }
            return;
        }
        pairs_.emplace_back(client, server);
    }

    int target_port_;
    int listener_ = -1;
    int port_ = 0;
    std::atomic<bool> cut_{false};
    std::atomic<bool> stop_{false};
    std::vector<std::pair<int, int>> pairs_; ///< (accepted, to the target), the thread's
    std::thread thread_;
};

} // namespace dsoc::testing
