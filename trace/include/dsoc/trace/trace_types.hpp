#pragma once
// The contents of a replication trace, version 1 (docs/replication-trace.md).
// Units: world units, z up. Ids: unsigned 32-bit.

#include "dsoc/visibility/geometry.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace dsoc::trace {

inline constexpr int kTraceVersion = 1;

struct TraceOccluder {
    std::uint32_t id = 0;
    /// Half-spaces dot(normal, x) <= distance, unit normals pointing out of the solid.
    std::vector<visibility::Plane> planes;
};

/// A curved surface the game draws opaque (a Quake 3 patch): a width x height grid of
/// control points, read as biquadratic Bezier patches of 3 x 3 points sharing edges.
/// It blocks sight like an occluder, though the culling did not use it.
struct TracePatch {
    int width = 0;                 ///< odd, 3..31
    int height = 0;                ///< odd, 3..31
    std::vector<glm::vec3> points; ///< row by row, width x height
};

struct TraceHeader {
    std::string map;
    int tick_rate = 30;
    std::string policy;
    /// Ticks of the client's own movement the server promises to cover (0: present eye only).
    int lookahead_ticks = 0;
    std::vector<TraceOccluder> occluders;
    std::vector<TracePatch> patches; ///< written only when there are some
};

struct TraceEntity {
    std::uint32_t id = 0;
    visibility::Aabb box;
};

struct TraceClient {
    std::uint32_t id = 0;
    std::optional<std::uint32_t> entity; ///< the entity it controls, if any
    glm::vec3 eye{0.0f};
    std::vector<std::uint32_t> replicated;
    /// Where a respawn the server has decided will put the eye (within the lookahead):
    /// the replicated set covers it too. Absent while the client's entity lives.
    std::optional<glm::vec3> arrival;
    /// Entities sent by a rule whatever sight says (teammates: visibility::Relevance::
    /// always), increasing; and entities withheld by a rule, seen or not (never).
    /// Their reason is the rule, not the culler: a checker leaves `always` out of
    /// exposure and `never` out of pop-in.
    std::vector<std::uint32_t> always;
    std::vector<std::uint32_t> never;
    /// Replicated entities sent only because the client hears them (interest/hearing.hpp):
    /// a coarse position, no angles. Increasing; a subset of `replicated`. A checker
    /// counts them as hearing's exposure, apart from sight's, and one that is visible
    /// as a pop-in (sight needed it precise).
    std::vector<std::uint32_t> heard;
};

struct TraceTick {
    std::uint64_t t = 0;
    std::vector<TraceEntity> entities;
    std::vector<TraceClient> clients;
};

} // namespace dsoc::trace
