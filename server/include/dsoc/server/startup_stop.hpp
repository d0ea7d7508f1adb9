#pragma once
// A stop asked for while the server starts, before its loop serves and takes SIGINT and
// SIGTERM itself: the first bake of a map's table can take most of an hour, and an
// operator's Ctrl-C then should keep the work done (the bake saves its partial file at
// once, bake_partial.hpp) rather than kill the process with up to a checkpoint's
// interval of it lost.
//
// Threading: the flag is lock-free; a signal handler sets it, any thread reads it.

namespace dsoc::server {

/// Makes SIGINT and SIGTERM set the flag (until a boost::asio::signal_set takes them;
/// whoever installs one asks the flag once after, so a signal in between is not lost).
void catch_startup_signals();

/// Whether SIGINT or SIGTERM came since catch_startup_signals().
[[nodiscard]] bool startup_stop_requested();

} // namespace dsoc::server
