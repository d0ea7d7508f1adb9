#pragma once
// A fixed set of threads for the server's per-client tick work (interest evaluation
// and snapshot building). One loop over indexes at a time, in one of two forms:
//
// - run(count, body): fork-join. Hands the indexes 0..count-1 out one at a time to the
//   pool's threads and the calling thread, and returns when every call has returned.
// - start(count, body, done): the same on the pool's own threads only; returns at
//   once, and `done` is called (on a pool thread) once every call has returned. The
//   server uses it so that its I/O thread keeps serving sockets during the loop.
//
// With Caller::takes_part (for run()) a pool of N threads starts N-1 threads of its
// own and the caller is the N-th; N = 1 runs everything on the caller, in index order.
// With Caller::stays_out (for start()) it starts N threads of its own.
//
// Which thread runs which index is not deterministic; a body whose effect depends
// only on its index (and on state no other index writes) gives the same results
// whatever the thread count and whichever form runs it.
//
// Threading: run() and start() must not be called concurrently with each other, from
// inside a body, or while a start()ed loop is in flight (both throw
// std::logic_error on the latter). Everything the caller wrote before run()/start()
// is visible to the bodies; everything the bodies wrote is visible after run()
// returns, and to `done`, and to whatever `done` hands it to through a synchronising
// channel (asio::post, a mutex, a promise).

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace dsoc::server {

class WorkerPool {
public:
    /// The name of the pool's own threads (as top -H, perf and the thread metrics show
    /// them; at most 15 characters).
    static constexpr const char* kThreadName = "dsoc-worker";

    /// Whether the caller of run() counts as one of the pool's threads.
    enum class Caller : std::uint8_t { takes_part, stays_out };

    using Body = std::function<void(std::size_t)>;
    /// Called once a start()ed loop has finished: the first exception a body threw, or null.
    using Done = std::function<void(std::exception_ptr)>;

    /// `threads` >= 1 bodies at a time (0: std::thread::hardware_concurrency()). With
    /// Caller::takes_part the caller of run() is one of them; with Caller::stays_out
    /// all are the pool's own (a run() caller then joins them as one more).
    explicit WorkerPool(int threads, Caller caller = Caller::takes_part);
    /// Waits for a start()ed loop in flight, then stops the threads.
    ~WorkerPool();
    WorkerPool(const WorkerPool&) = delete;
    WorkerPool& operator=(const WorkerPool&) = delete;

    /// Calls body(i) for every i in [0, count), concurrently for distinct i. Returns
    /// when all have returned; rethrows the first exception a body threw (the other
    /// indexes still run).
    void run(std::size_t count, const Body& body);

    /// Calls body(i) for every i in [0, count) on the pool's own threads and returns at
    /// once. When every call has returned, `done(error)` runs on the pool thread that
    /// finished last (inline, on the caller, when count is 0); `error` is the first
    /// exception a body threw (the other indexes still run). The pool copies `body` and
    /// `done`; what they reference must stay valid until `done` has been called.
    /// `done` must not destroy the pool. Throws std::logic_error when the pool has no
    /// thread of its own (Caller::takes_part with 1 thread) or a loop is in flight.
    void start(std::size_t count, Body body, Done done);

    /// True from start() until `done` is about to be called.
    [[nodiscard]] bool in_flight() const;
    /// Blocks until no start()ed loop is in flight.
    void wait_idle();

    /// Threads that run bodies (with Caller::takes_part, the run() caller included).
    [[nodiscard]] int threads() const {
        return static_cast<int>(helpers_.size()) + (caller_ == Caller::takes_part ? 1 : 0);
    }

    /// The thread count `threads` stands for (0: the machine's cores, at least 1).
    [[nodiscard]] static int resolve(int threads);

private:
    void helper_loop();
    void work(const Body* body, std::size_t count);

    Caller caller_;
    std::vector<std::thread> helpers_;
    mutable std::mutex mutex_;
    std::condition_variable wake_;
    std::condition_variable done_;
    std::uint64_t generation_ = 0; ///< bumped by every run()/start(); guarded by mutex_
    std::size_t busy_helpers_ = 0; ///< helpers inside the current loop; guarded by mutex_
    bool stopping_ = false;        ///< guarded by mutex_
    const Body* body_ = nullptr;   ///< the current loop's body; guarded by mutex_
    std::size_t count_ = 0;        ///< guarded by mutex_
    Body started_body_;            ///< start()'s copy of its body; guarded by mutex_
    Done started_done_;            ///< guarded by mutex_
    bool started_ = false;         ///< a start()ed loop is in flight; guarded by mutex_
    std::atomic<std::size_t> next_{0};
    std::exception_ptr error_; ///< guarded by mutex_
};

} // namespace dsoc::server
