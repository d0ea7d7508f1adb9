#pragma once
// One of the evaluation's frames as the interest layer's policies read a world
// (interest::WorldView): entity i is frames' entity i, with its box, velocity and
// pending respawn, team and sound.

#include "dsoc/eval/world_sim.hpp"
#include "dsoc/interest/world_view.hpp"

namespace dsoc::eval {

class FrameView final : public interest::WorldView {
public:
    /// `frame` must outlive the view.
    explicit FrameView(const WorldFrame& frame) : frame_(&frame) {}
    [[nodiscard]] std::size_t entity_count() const override { return frame_->entities.size(); }
    [[nodiscard]] interest::EntityView entity(std::size_t index) const override {
        const EntityFrame& e = frame_->entities[index];
        return {static_cast<std::uint32_t>(index),
                e.box,
                e.velocity,
                e.arrival_eye,
                e.team,
                e.sound_range};
    }

private:
    const WorldFrame* frame_;
};

} // namespace dsoc::eval
