#include "dsoc/server/client_tick.hpp"

#include "dsoc/protocol/codec.hpp"
#include "dsoc/protocol/quantization.hpp"
#include "dsoc/server/udp_connection.hpp"

#include <algorithm>
#include <cmath>

namespace dsoc::server {

static_assert(interest::kHeardTier == protocol::kHeardTier, "one heard tier on both sides");

void add_own_entity(std::vector<interest::Interest>& interest, std::uint32_t entity_id) {
    const auto own =
        std::lower_bound(interest.begin(), interest.end(), entity_id,
                         [](const interest::Interest& a, std::uint32_t id) { return a.id < id; });
    if (own == interest.end() || own->id != entity_id) {
        interest.insert(own, interest::Interest{entity_id, 0});
    } else {
        own->tier = 0;
    }
}

namespace {

void run_one(const interest::GameWorld& world, interest::InterestPolicy& policy, std::uint64_t tick,
             const ClientTick& job, CullingBudget* budget) {
    std::vector<interest::Interest>& interest = *job.interest;
    if (budget != nullptr && budget->enabled &&
        std::chrono::steady_clock::now() > budget->deadline) {
        policy.select_cheapest(world, job.viewer, interest);
        budget->cheapest.fetch_add(1, std::memory_order_relaxed);
    } else {
        policy.select(world, job.viewer, interest);
    }
    const std::size_t heard =
        job.hearing != nullptr ? job.hearing->add_heard(job.viewer, policy, interest) : 0;
    if (job.heard != nullptr) {
        *job.heard = static_cast<std::uint32_t>(heard);
    }
    add_own_entity(interest, job.viewer.entity_id);
    if (!job.network_lod) {
        for (interest::Interest& i : interest) {
            i.tier = i.tier == interest::kHeardTier ? i.tier : 0; // hearing stays coarse
        }
    }
    if (job.build && job.replication->acked()) {
        protocol::UpdateColumns* columns = job.frame != nullptr ? job.columns : nullptr;
        job.replication->build_acked_snapshot(world, interest, job.viewer.eye, tick, job.acked_tick,
                                              job.audit, *job.envelope->mutable_snapshot(),
                                              job.poses, columns);
        if (job.frame != nullptr) {
            snapshot_frame(tick, *job.envelope, columns, *job.frame);
        }
    } else if (job.build) {
        protocol::UpdateColumns* columns = job.frame != nullptr ? job.columns : nullptr;
        job.replication->build_snapshot(world, interest, tick, job.audit,
                                        *job.envelope->mutable_snapshot(), job.poses, columns);
        if (job.frame != nullptr) {
            job.frame->clear();
            if (columns != nullptr) {
                protocol::encode_snapshot_frame(*job.envelope, *columns, *job.frame);
            } else {
                protocol::encode_frame(*job.envelope, *job.frame);
            }
        }
    }
}

/// The job that takes turn `i` of `n` at `tick`: the order starts at a point that moves
/// by the golden ratio of the job count every tick, so no client is always served last.
std::size_t job_at_turn(std::size_t i, std::size_t n, std::uint64_t tick) {
    const auto start = static_cast<std::size_t>(
        std::fmod(static_cast<double>(tick) * 0.6180339887498949, 1.0) * static_cast<double>(n));
    return (i + start) % n;
}

} // namespace

void run_client_ticks(const interest::GameWorld& world, interest::InterestPolicy& policy,
                      std::uint64_t tick, std::span<const ClientTick> jobs, WorkerPool& pool,
                      CullingBudget* budget) {
    pool.run(jobs.size(), [&](std::size_t i) {
        run_one(world, policy, tick, jobs[job_at_turn(i, jobs.size(), tick)], budget);
    });
}

void start_client_ticks(const interest::GameWorld& world, interest::InterestPolicy& policy,
                        std::uint64_t tick, std::span<const ClientTick> jobs, WorkerPool& pool,
                        std::function<void(std::exception_ptr)> done, CullingBudget* budget) {
    pool.start(
        jobs.size(),
        [&world, &policy, tick, jobs, budget](std::size_t i) {
            run_one(world, policy, tick, jobs[job_at_turn(i, jobs.size(), tick)], budget);
        },
        std::move(done));
}

} // namespace dsoc::server
