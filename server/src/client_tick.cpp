#include "dsoc/server/client_tick.hpp"

#include "dsoc/protocol/codec.hpp"

#include <algorithm>

namespace dsoc::server {

namespace {

void run_one(const GameWorld& world, InterestPolicy& policy, std::uint64_t tick,
             const ClientTick& job) {
    std::vector<Interest>& interest = *job.interest;
    policy.select(world, job.viewer, interest);
    const auto own =
        std::lower_bound(interest.begin(), interest.end(), job.viewer.entity_id,
                         [](const Interest& a, std::uint32_t id) { return a.id < id; });
    if (own == interest.end() || own->id != job.viewer.entity_id) {
        interest.insert(own, Interest{job.viewer.entity_id, 0});
    } else {
        own->tier = 0; // a client always gets its own entity every tick, finest
    }
    if (!job.network_lod) {
        for (Interest& i : interest) {
            i.tier = 0;
        }
    }
    if (job.build) {
        job.replication->build_snapshot(world, interest, tick, job.audit,
                                        *job.envelope->mutable_snapshot(), job.poses);
        if (job.frame != nullptr) {
            job.frame->clear();
            protocol::encode_frame(*job.envelope, *job.frame);
        }
    }
}

} // namespace

void run_client_ticks(const GameWorld& world, InterestPolicy& policy, std::uint64_t tick,
                      std::span<const ClientTick> jobs, WorkerPool& pool) {
    pool.run(jobs.size(), [&](std::size_t i) { run_one(world, policy, tick, jobs[i]); });
}

void start_client_ticks(const GameWorld& world, InterestPolicy& policy, std::uint64_t tick,
                        std::span<const ClientTick> jobs, WorkerPool& pool,
                        std::function<void(std::exception_ptr)> done) {
    pool.start(
        jobs.size(),
        [&world, &policy, tick, jobs](std::size_t i) { run_one(world, policy, tick, jobs[i]); },
        std::move(done));
}

} // namespace dsoc::server
