#pragma once
// What one client knows, and how a new interest set becomes a snapshot of
// enter / update / leave.

#include "dsoc/protocol/messages.hpp"
#include "dsoc/server/game_world.hpp"

#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

namespace dsoc::server {

class ReplicationState {
public:
    /// Fills `snapshot` (cleared first) for `tick`: entities in `interest` (ids in
    /// increasing order, each present in `world`) that the client did not know enter
    /// with full state; known ones whose state changed since last sent get an update;
    /// known ones not in `interest` leave. Afterwards the client knows exactly `interest`.
    void build_snapshot(const GameWorld& world, std::span<const std::uint32_t> interest,
                        std::uint64_t tick, protocol::pb::Snapshot& snapshot);

    [[nodiscard]] std::size_t known_count() const { return known_.size(); }
    [[nodiscard]] const std::vector<std::uint32_t>& known() const { return known_; }

private:
    struct SentState {
        glm::vec3 position;
        float yaw_deg;
        float pitch_deg;
    };

    std::vector<std::uint32_t> known_; // increasing
    std::vector<std::uint32_t> next_known_;
    std::unordered_map<std::uint32_t, SentState> sent_;
};

} // namespace dsoc::server
