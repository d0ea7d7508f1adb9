// The per-client half of a tick on 1 and on N threads: every snapshot byte for byte
// the same, for the culling policy (InterestManager::update_client in parallel) and
// a plain one, with and without the server's shared per-tick quantization and frame
// encoding on the pool, run in the caller (WorkerPool::run) or, as the server runs
// it, on the pool's own threads while the caller waits elsewhere (start()); and the
// WorkerPool itself.

#include "dsoc/protocol/compact_snapshot.hpp"
#include "dsoc/server/client_tick.hpp"
#include "dsoc/server/interest_setup.hpp"
#include "support/test_maps.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <future>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace dsoc::server {
namespace {

struct TestClient {
    std::uint32_t client_id = 0;
    std::uint32_t entity_id = 0;
    ReplicationState replication;
    std::vector<interest::Interest> interest;
    protocol::pb::Envelope envelope;
    std::vector<std::uint8_t> frame;
    protocol::SnapshotDecoder decoder;
};

/// Every snapshot of every client over `ticks` ticks, serialized, in client order.
/// Players join at staggered ticks and steer by a seeded random intent; one leaves.
/// `as_server`: as the server runs it - poses quantized once per tick (SharedPoses),
/// each snapshot encoded into its frame, all on the pool's own threads
/// (start_client_ticks, Caller::stays_out); the payload of that frame is returned.
std::vector<std::string> run_server_ticks(const std::string& policy, int threads, int ticks,
                                          bool as_server, std::uint64_t& enters,
                                          std::uint64_t& updates) {
    ServerConfig config;
    config.bots = 120;
    config.policy = *interest::parse_choice<interest::PolicyKind>(policy);
    config.baked_stage = false; // the exact stages (no bake in this test)
    config.threads = threads;
    config.seed = 9;
    interest::GameWorld world(world_settings(config), testing::rooms_map());
    auto interest_policy = make_policy(config, world);
    WorkerPool pool(threads,
                    as_server ? WorkerPool::Caller::stays_out : WorkerPool::Caller::takes_part);
    std::vector<std::unique_ptr<TestClient>> clients;
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::vector<std::string> out;
    enters = 0;
    updates = 0;
    for (int t = 1; t <= ticks; ++t) {
        const auto tick = static_cast<std::uint64_t>(t);
        if (t <= 24 && t % 2 == 1) { // 12 players join over the first ticks
            auto c = std::make_unique<TestClient>();
            c->client_id = static_cast<std::uint32_t>(clients.size() + 1);
            c->entity_id = world.spawn_player();
            c->replication = ReplicationState(quantization(config));
            c->decoder.set_settings(quantization(config));
            interest_policy->add_viewer(c->client_id, c->entity_id);
            clients.push_back(std::move(c));
        }
        if (t == ticks / 2) { // one leaves mid-run
            interest_policy->remove_viewer(clients[3]->client_id);
            world.remove(clients[3]->entity_id);
            clients.erase(clients.begin() + 3);
        }
        for (auto& c : clients) {
            world.set_player_input(c->entity_id, glm::vec3(unit(rng), unit(rng), 0.0f),
                                   rng() % 20 == 0, unit(rng) * 180.0f, unit(rng) * 60.0f);
        }
        world.step(1.0f / 30.0f);
        interest_policy->begin_tick(world, tick);
        SharedPoses poses;
        poses.compute(world, quantization(config));
        std::vector<ClientTick> jobs;
        for (auto& c : clients) {
            const interest::Entity* self = world.find(c->entity_id);
            ClientTick job;
            job.viewer = interest::Viewer{c->client_id, c->entity_id, world.eye_of(*self)};
            job.replication = &c->replication;
            job.interest = &c->interest;
            job.envelope = &c->envelope;
            job.build = (t + static_cast<int>(c->client_id)) % 7 != 0; // some dropped ticks
            job.audit = t % 5 == 0;
            if (as_server) {
                job.frame = &c->frame;
                job.poses = &poses;
            }
            jobs.push_back(job);
        }
        if (as_server) {
            std::promise<void> finished;
            start_client_ticks(world, *interest_policy, tick, jobs, pool,
                               [&finished](std::exception_ptr error) {
                                   if (error) {
                                       finished.set_exception(error);
                                   } else {
                                       finished.set_value();
                                   }
                               });
            finished.get_future().get();
        } else {
            run_client_ticks(world, *interest_policy, tick, jobs, pool);
        }
        for (std::size_t i = 0; i < jobs.size(); ++i) {
            if (!jobs[i].build) {
                out.emplace_back("dropped");
                continue;
            }
            const auto& snapshot = clients[i]->envelope.snapshot();
            if (as_server) {
                const auto& frame = clients[i]->frame;
                EXPECT_EQ(frame.size(), 4 + clients[i]->envelope.ByteSizeLong());
                out.emplace_back(frame.begin() + 4, frame.end());
            } else {
                out.push_back(clients[i]->envelope.SerializeAsString());
            }
            enters += static_cast<std::uint64_t>(snapshot.enter_size());
            updates += static_cast<std::uint64_t>(snapshot.update_head_size());
            // What the client decodes is within half a quantum of the server's world.
            const auto problems = clients[i]->decoder.apply(snapshot);
            EXPECT_TRUE(problems.empty())
                << problems.front().kind << ": " << problems.front().detail;
            double worst = 0.0;
            const auto audit = clients[i]->decoder.check_audit(snapshot, worst);
            EXPECT_TRUE(audit.empty()) << audit.front().detail;
        }
    }
    return out;
}

void expect_same_bytes_for_any_thread_count(const std::string& policy) {
    std::uint64_t enters = 0;
    std::uint64_t updates = 0;
    const auto serial = run_server_ticks(policy, 1, 90, false, enters, updates);
    // The run must exercise something: entities entering and moving.
    EXPECT_GT(enters, 100u);
    EXPECT_GT(updates, 2000u);
    for (const int threads : {1, 2, 4, 7}) {
        std::uint64_t e = 0;
        std::uint64_t u = 0;
        // Threads, shared poses, frames and the pool's own threads: none of them may
        // change a byte.
        const auto parallel = run_server_ticks(policy, threads, 90, threads != 4, e, u);
        ASSERT_EQ(parallel.size(), serial.size());
        for (std::size_t i = 0; i < serial.size(); ++i) {
            ASSERT_EQ(parallel[i], serial[i])
                << policy << ", " << threads << " threads: snapshot " << i << " differs";
        }
    }
}

TEST(ParallelTick, DsocSnapshotsAreIdenticalForAnyThreadCount) {
    expect_same_bytes_for_any_thread_count("dsoc");
}

TEST(ParallelTick, DistanceSnapshotsAreIdenticalForAnyThreadCount) {
    expect_same_bytes_for_any_thread_count("distance");
}

TEST(WorkerPool, RunsEveryIndexExactlyOnceAcrossManyRuns) {
    WorkerPool pool(4);
    EXPECT_EQ(pool.threads(), 4);
    for (std::size_t count : {0u, 1u, 3u, 1000u, 17u}) {
        std::vector<std::atomic<int>> hits(count);
        for (int run = 0; run < 20; ++run) {
            pool.run(count, [&](std::size_t i) { hits[i].fetch_add(1); });
        }
        for (std::size_t i = 0; i < count; ++i) {
            ASSERT_EQ(hits[i].load(), 20) << "index " << i << " of " << count;
        }
    }
}

TEST(WorkerPool, RethrowsABodysExceptionAndStaysUsable) {
    WorkerPool pool(3);
    std::atomic<int> ran{0};
    EXPECT_THROW(pool.run(50,
                          [&](std::size_t i) {
                              ran.fetch_add(1);
                              if (i == 13) {
                                  throw std::runtime_error("index 13");
                              }
                          }),
                 std::runtime_error);
    EXPECT_EQ(ran.load(), 50); // the other indexes still ran
    std::atomic<int> again{0};
    pool.run(10, [&](std::size_t) { again.fetch_add(1); });
    EXPECT_EQ(again.load(), 10);
    EXPECT_GE(WorkerPool::resolve(0), 1);
}

/// Starts a loop and waits for its `done`; returns the error `done` received.
std::exception_ptr start_and_wait(WorkerPool& pool, std::size_t count,
                                  const WorkerPool::Body& body) {
    std::promise<std::exception_ptr> finished;
    pool.start(count, body, [&](std::exception_ptr error) { finished.set_value(error); });
    return finished.get_future().get();
}

TEST(WorkerPool, StartedLoopsRunEveryIndexOnceBeforeDone) {
    for (const int threads : {1, 3}) {
        WorkerPool pool(threads, WorkerPool::Caller::stays_out);
        EXPECT_EQ(pool.threads(), threads);
        const std::thread::id caller = std::this_thread::get_id();
        for (std::size_t count : {0u, 1u, 5u, 1000u}) {
            std::vector<std::atomic<int>> hits(count);
            for (int run = 0; run < 20; ++run) {
                std::atomic<bool> on_caller{false};
                std::promise<std::size_t> seen_at_done;
                pool.start(
                    count,
                    [&](std::size_t i) {
                        hits[i].fetch_add(1);
                        on_caller = on_caller || std::this_thread::get_id() == caller;
                    },
                    [&](std::exception_ptr error) {
                        EXPECT_FALSE(error);
                        std::size_t total = 0; // every body has returned by now
                        for (const auto& h : hits) {
                            total += static_cast<std::size_t>(h.load());
                        }
                        seen_at_done.set_value(total);
                    });
                EXPECT_EQ(seen_at_done.get_future().get(),
                          count * static_cast<std::size_t>(run + 1));
                pool.wait_idle();
                EXPECT_FALSE(pool.in_flight());
                EXPECT_FALSE(on_caller) << "a body ran on the caller";
            }
        }
    }
}

TEST(WorkerPool, StartedLoopReportsABodysExceptionToDone) {
    WorkerPool pool(2, WorkerPool::Caller::stays_out);
    std::atomic<int> ran{0};
    const auto error = start_and_wait(pool, 40, [&](std::size_t i) {
        ran.fetch_add(1);
        if (i == 7) {
            throw std::runtime_error("index 7");
        }
    });
    ASSERT_TRUE(error);
    EXPECT_THROW(std::rethrow_exception(error), std::runtime_error);
    EXPECT_EQ(ran.load(), 40);
    EXPECT_FALSE(start_and_wait(pool, 3, [](std::size_t) {})); // usable again
}

TEST(WorkerPool, StartIsRefusedWhileALoopIsInFlightOrWithoutOwnThreads) {
    WorkerPool pool(2, WorkerPool::Caller::stays_out);
    std::promise<void> release;
    std::shared_future<void> released = release.get_future().share();
    std::promise<void> finished;
    pool.start(
        2, [&](std::size_t) { released.wait(); },
        [&](std::exception_ptr) { finished.set_value(); });
    EXPECT_TRUE(pool.in_flight());
    EXPECT_THROW(pool.start(
                     1, [](std::size_t) {}, [](std::exception_ptr) {}),
                 std::logic_error);
    EXPECT_THROW(pool.run(1, [](std::size_t) {}), std::logic_error);
    release.set_value();
    finished.get_future().get();

    WorkerPool caller_only(1); // Caller::takes_part with one thread: no thread of its own
    EXPECT_THROW(caller_only.start(
                     1, [](std::size_t) {}, [](std::exception_ptr) {}),
                 std::logic_error);
}

} // namespace
} // namespace dsoc::server
