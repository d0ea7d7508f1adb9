#include "dsoc/server/datagram_batch.hpp"

#include <algorithm>

namespace dsoc::server {

void DatagramBatch::clear() {
    sockets_.clear();
    messages_.clear();
    parts_.clear();
    refused_.clear();
}

std::size_t DatagramBatch::add(int socket, std::span<const std::uint8_t> bytes,
                               const sockaddr* peer, socklen_t peer_size) {
    sockets_.push_back(socket);
    parts_.push_back({const_cast<std::uint8_t*>(bytes.data()), bytes.size()}); // not written
    mmsghdr& m = messages_.emplace_back();
    m = {};
    m.msg_hdr.msg_name = const_cast<sockaddr*>(peer); // not written by sendmmsg
    m.msg_hdr.msg_namelen = peer_size;
    m.msg_hdr.msg_iovlen = 1;
    refused_.push_back(0);
    return messages_.size() - 1;
}

void DatagramBatch::send() {
    // The parts' addresses are final only now (the vector may have moved as it grew).
    for (std::size_t i = 0; i < messages_.size(); ++i) {
        messages_[i].msg_hdr.msg_iov = &parts_[i];
        messages_[i].msg_len = 0;
    }
    for (std::size_t from = 0; from < messages_.size();) {
        // The run of datagrams on from's socket, at most kMaxPerCall of them.
        std::size_t end = from + 1;
        while (end < messages_.size() && end - from < kMaxPerCall &&
               sockets_[end] == sockets_[from]) {
            ++end;
        }
        const auto count = static_cast<unsigned>(end - from);
        const int n =
            ::sendmmsg(sockets_[from], messages_.data() + from, count, MSG_DONTWAIT | MSG_NOSIGNAL);
        from += n > 0 ? static_cast<std::size_t>(n) : 0;
        if (n < static_cast<int>(count)) {
            refused_[from] = 1; // the first not sent: refused; try the ones after it
            ++from;
        }
    }
}

} // namespace dsoc::server
