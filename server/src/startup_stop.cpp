#include "dsoc/server/startup_stop.hpp"

#include <atomic>
#include <csignal>

namespace dsoc::server {
namespace {

std::atomic<bool> g_stop_requested{false};
static_assert(std::atomic<bool>::is_always_lock_free, "set from a signal handler");

extern "C" void request_stop(int /*signal*/) {
    g_stop_requested.store(true, std::memory_order_relaxed);
}

} // namespace

void catch_startup_signals() {
    std::signal(SIGINT, request_stop);
    std::signal(SIGTERM, request_stop);
}

bool startup_stop_requested() {
    return g_stop_requested.load(std::memory_order_relaxed);
}

} // namespace dsoc::server
