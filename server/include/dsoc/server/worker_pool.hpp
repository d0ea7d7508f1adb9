#pragma once
// A fixed set of threads for the server's per-client tick work (interest evaluation
// and snapshot building). One fork-join loop at a time: run(count, body) hands the
// indexes 0..count-1 out one at a time to the helper threads and the calling thread,
// and returns when every call has returned. The caller takes part, so a pool of N
// threads starts N-1 helpers; N = 1 runs everything on the caller, in index order.
//
// Which thread runs which index is not deterministic; a body whose effect depends
// only on its index (and on state no other index writes) gives the same results
// whatever the thread count.
//
// Threading: run() must not be called concurrently or from inside a body.

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
    /// `threads` >= 1, the caller included. 0 means std::thread::hardware_concurrency().
    explicit WorkerPool(int threads);
    ~WorkerPool();
    WorkerPool(const WorkerPool&) = delete;
    WorkerPool& operator=(const WorkerPool&) = delete;

    /// Calls body(i) for every i in [0, count), concurrently for distinct i. Returns
    /// when all have returned; rethrows the first exception a body threw (the other
    /// indexes still run).
    void run(std::size_t count, const std::function<void(std::size_t)>& body);

    /// Threads that run bodies, the caller included.
    [[nodiscard]] int threads() const { return static_cast<int>(helpers_.size()) + 1; }

    /// The thread count `threads` stands for (0: the machine's cores, at least 1).
    [[nodiscard]] static int resolve(int threads);

private:
    void helper_loop();
    void work(const std::function<void(std::size_t)>* body, std::size_t count);

    std::vector<std::thread> helpers_;
    std::mutex mutex_;
    std::condition_variable wake_;
    std::condition_variable done_;
    std::uint64_t generation_ = 0; ///< bumped by every run(); guarded by mutex_
    std::size_t busy_helpers_ = 0; ///< helpers inside the current run; guarded by mutex_
    bool stopping_ = false;        ///< guarded by mutex_
    const std::function<void(std::size_t)>* body_ = nullptr; ///< guarded by mutex_
    std::size_t count_ = 0;                                  ///< guarded by mutex_
    std::atomic<std::size_t> next_{0};
    std::exception_ptr error_; ///< guarded by mutex_
};

} // namespace dsoc::server
