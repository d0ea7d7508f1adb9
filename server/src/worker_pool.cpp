#include "dsoc/server/worker_pool.hpp"

#include <pthread.h>

#include <algorithm>
#include <stdexcept>

namespace dsoc::server {

int WorkerPool::resolve(int threads) {
    if (threads > 0) {
        return threads;
    }
    return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

WorkerPool::WorkerPool(int threads, Caller caller) : caller_(caller) {
    const int n = resolve(threads) - (caller == Caller::takes_part ? 1 : 0);
    helpers_.reserve(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
        helpers_.emplace_back([this] { helper_loop(); });
        ::pthread_setname_np(helpers_.back().native_handle(), kThreadName); // best effort
    }
}

WorkerPool::~WorkerPool() {
    {
        std::unique_lock lock(mutex_);
        done_.wait(lock, [&] { return !started_; });
        stopping_ = true;
    }
    wake_.notify_all();
    for (auto& t : helpers_) {
        t.join(); // a helper still calling a loop's `done` finishes it first
    }
}

void WorkerPool::work(const Body* body, std::size_t count) {
    if (count == 0) { // woke between loops: next_ belongs to the next one
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
        const Body* body = nullptr;
        std::size_t count = 0;
        {
            std::unique_lock lock(mutex_);
            wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
            if (stopping_) {
                return;
            }
            seen = generation_;
            body = body_;   // copied under the lock: a helper waking after its loop ended
            count = count_; // finds count 0 and does nothing
            ++busy_helpers_;
        }
        work(body, count);
        Done finished;
        std::exception_ptr error;
        {
            const std::lock_guard lock(mutex_);
            --busy_helpers_;
            // The last helper out of a start()ed loop whose indexes are all handed out:
            // every body has returned (a helper leaves work() only when none is left,
            // and those still inside a body are counted busy).
            if (started_ && busy_helpers_ == 0 && next_.load() >= count_) {
                finished = std::move(started_done_);
                error = error_;
                started_done_ = nullptr;
                started_body_ = nullptr;
                body_ = nullptr;
                count_ = 0;
                started_ = false;
            }
        }
        done_.notify_all();
        if (finished) {
            finished(error);
        }
    }
}

void WorkerPool::run(std::size_t count, const Body& body) {
    if (in_flight()) {
        throw std::logic_error("WorkerPool::run while a start()ed loop is in flight");
    }
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

void WorkerPool::start(std::size_t count, Body body, Done done) {
    if (helpers_.empty()) {
        throw std::logic_error("WorkerPool::start needs a pool with threads of its own "
                               "(Caller::stays_out, or more than one thread)");
    }
    {
        const std::lock_guard lock(mutex_);
        if (started_) {
            throw std::logic_error("WorkerPool::start while a loop is in flight");
        }
        if (count > 0) {
            started_body_ = std::move(body);
            started_done_ = std::move(done);
            started_ = true;
            body_ = &started_body_;
            count_ = count;
            next_.store(0);
            error_ = nullptr;
            ++generation_;
        }
    }
    if (count == 0) {
        done(nullptr);
        return;
    }
    wake_.notify_all();
}

bool WorkerPool::in_flight() const {
    const std::lock_guard lock(mutex_);
    return started_;
}

void WorkerPool::wait_idle() {
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return !started_; });
}

} // namespace dsoc::server
