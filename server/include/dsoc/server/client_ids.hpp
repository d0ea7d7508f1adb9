#pragma once
// Client ids: the server's name for a connection in its maps, logs and ServerHello.

#include <cstdint>

namespace dsoc::server {

/// The next client id from `next`, which moves past it. Ids are 32 bits, so they wrap
/// after 2^32 connections (a day at 50,000 connects a second): an id `in_use(id)` says
/// a connection still holds is skipped, so that a new connection never takes another's
/// entries, and so is 0 (no client). Ends when any id is free (a server holds far fewer
/// than 2^32 connections).
template <class InUse>
[[nodiscard]] std::uint32_t take_free_client_id(std::uint32_t& next, const InUse& in_use) {
    for (;;) {
        const std::uint32_t id = next++;
        if (id != 0 && !in_use(id)) {
            return id;
        }
    }
}

} // namespace dsoc::server
