#pragma once
// What an interest policy reads of the world each tick: the entities, in increasing id
// order, each with its box, velocity, pending respawn, team and the range of its sound. GameWorld
// (the server's and dsoc-inspect's world) is one; dsoc-eval's recorded frames are another, so that
// the evaluation runs the very policies the server runs.

#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/relevance.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>

namespace dsoc::interest {

/// One entity as a policy sees it.
struct EntityView {
    std::uint32_t id = 0;
    visibility::Aabb box;     ///< its collision box in world space
    glm::vec3 velocity{0.0f}; ///< [Units: world units / s]
    /// Where its eye will be once a respawn the world has decided puts it at a spawn
    /// point (sim/respawn.hpp); nothing while it lives.
    std::optional<glm::vec3> arrival_eye;
    /// Its team (visibility::kNoTeam: none): teammates are always replicated.
    visibility::TeamId team = visibility::kNoTeam;
    /// How far the sound it makes this tick is heard (0: silent): every client whose eye
    /// is within this distance of its box hears it (interest/hearing.hpp).
    /// [Units: world units]
    float sound_range = 0.0f;
};

class WorldView {
public:
    virtual ~WorldView() = default;
    /// How many entities there are this tick.
    [[nodiscard]] virtual std::size_t entity_count() const = 0;
    /// The `index`-th entity, 0 <= index < entity_count(); ids increase with the index.
    [[nodiscard]] virtual EntityView entity(std::size_t index) const = 0;

protected:
    WorldView() = default;
    WorldView(const WorldView&) = default;
    WorldView& operator=(const WorldView&) = default;
};

} // namespace dsoc::interest
