#pragma once
// Runs a piece of work on the thread that runs an io_context, for tests that change
// or read what only that thread may touch (a server, a metrics endpoint's state).

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>

#include <future>

namespace dsoc::testing {

/// Posts `work` to `io` and waits until it has run there. `io` must be running on
/// another thread.
template <class Work>
void run_on_io_thread(boost::asio::io_context& io, Work&& work) {
    std::promise<void> done;
    boost::asio::post(io, [&] {
        work();
        done.set_value();
    });
    done.get_future().wait();
}

} // namespace dsoc::testing
