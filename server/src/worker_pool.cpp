#include "dsoc/server/worker_pool.hpp"

#include <algorithm>

namespace dsoc::server {

int WorkerPool::resolve(int threads) {
    if (threads > 0) {
        return threads;
    }
    return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

WorkerPool::WorkerPool(int threads) {
    const int n = resolve(threads);
    helpers_.reserve(static_cast<std::size_t>(n - 1));
    for (int i = 1; i < n; ++i) {
        helpers_.emplace_back([this] { helper_loop(); });
    }
}

WorkerPool::~WorkerPool() {
    {
        const std::lock_guard lock(mutex_);
        stopping_ = true;
    }
    wake_.notify_all();
    for (auto& t : helpers_) {
        t.join();
    }
}

void WorkerPool::work(const std::function<void(std::size_t)>* body, std::size_t count) {
    if (count == 0) { // woke between runs: next_ belongs to the next run
        return;
    }
    for (std::size_t i = next_.fetch_add(1); i < count; i = next_.fetch_add(1)) {
        try {
            (*body)(i);
        } catch (...) {
            const std::lock_guard lock(mutex_);
            if (!error_) {
                error_ = std::current_exception();
            }
        }
    }
}

void WorkerPool::helper_loop() {
    std::uint64_t seen = 0;
    for (;;) {
        const std::function<void(std::size_t)>* body = nullptr;
        std::size_t count = 0;
        {
            std::unique_lock lock(mutex_);
            wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
            if (stopping_) {
                return;
            }
            seen = generation_;
            body = body_;   // copied under the lock: a helper waking after its run ended
            count = count_; // finds count 0 and does nothing
            ++busy_helpers_;
        }
        work(body, count);
        {
            const std::lock_guard lock(mutex_);
            --busy_helpers_;
        }
        done_.notify_one();
    }
}

void WorkerPool::run(std::size_t count, const std::function<void(std::size_t)>& body) {
    if (count == 0) {
        return;
    }
    if (helpers_.empty() || count == 1) {
        for (std::size_t i = 0; i < count; ++i) {
            body(i);
        }
        return;
    }
    {
        const std::lock_guard lock(mutex_);
        body_ = &body;
        count_ = count;
        next_.store(0);
        error_ = nullptr;
        ++generation_;
    }
    wake_.notify_all();
    work(&body, count);
    std::exception_ptr error;
    {
        // Every index has been handed out; wait for helpers still inside a body. A
        // helper that wakes late finds no index left and leaves at once.
        std::unique_lock lock(mutex_);
        done_.wait(lock, [&] { return busy_helpers_ == 0; });
        error = error_;
        body_ = nullptr;
        count_ = 0;
    }
    if (error) {
        std::rethrow_exception(error);
    }
}

} // namespace dsoc::server
