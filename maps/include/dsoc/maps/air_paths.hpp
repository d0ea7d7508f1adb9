#pragma once
// Shortest paths through a map's open air: how far a sound would have to travel around
// the walls between two points, against the straight line Quake 3's mixer uses (it
// fades a sound by distance alone: sim/sounds.hpp). A measurement (dsoc-sound-paths),
// not a rule the server runs.
//
// The air is a grid of cubic voxels over the map's bounds. A voxel is solid where it
// meets a brush that stops shots (contents_solid; glass and player clip let sound
// through): closed boxes, so that no path leaks through a wall thinner than a voxel,
// at the price of narrowing every opening by up to a voxel on each side. Paths step
// between the centres of open voxels, to any of the 26 neighbours, and never cut a
// corner (a diagonal step needs every voxel it grazes open), so a path is never
// shorter than the shortest path through the real air by more than the voxels' own
// rounding (about a voxel at each end).

#include "dsoc/maps/map.hpp"

#include <glm/ext/vector_int3.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace dsoc::maps {

struct AirGrid {
    float voxel = 0.0f;       ///< edge of a voxel [Units: world units]
    glm::vec3 origin{0.0f};   ///< the low corner of voxel (0, 0, 0)
    glm::ivec3 size{0, 0, 0}; ///< voxels along x, y, z
    /// 1 where solid, x fastest then y then z.
    std::vector<std::uint8_t> solid;
    /// The brushes that stop sound, for what the voxels cannot say: whether a point
    /// in a solid voxel reaches a neighbouring open one without crossing a wall.
    std::vector<CollisionBrush> walls;

    [[nodiscard]] std::size_t index(glm::ivec3 v) const {
        return (static_cast<std::size_t>(v.z) * static_cast<std::size_t>(size.y) +
                static_cast<std::size_t>(v.y)) *
                   static_cast<std::size_t>(size.x) +
               static_cast<std::size_t>(v.x);
    }
    [[nodiscard]] bool inside(glm::ivec3 v) const {
        return v.x >= 0 && v.y >= 0 && v.z >= 0 && v.x < size.x && v.y < size.y && v.z < size.z;
    }
    [[nodiscard]] glm::ivec3 voxel_of(glm::vec3 p) const;
    [[nodiscard]] glm::vec3 centre_of(glm::ivec3 v) const;
};

/// Most voxels an AirGrid may have (a byte each, and a float each while a path search
/// runs).
inline constexpr std::size_t kMaxAirVoxels = std::size_t{1} << 27;

/// The air of `map` in voxels of `voxel` units; its outermost layer is solid. Throws
/// std::invalid_argument, naming the map and the figures, when `voxel` is not positive or the map's
/// bounds need more than kMaxAirVoxels.
[[nodiscard]] AirGrid air_grid(const Map& map, float voxel);

/// No path within the search's bound.
inline constexpr float kNoAirPath = std::numeric_limits<float>::infinity();

/// Path searches over one grid, which must outlive it. Not thread-safe: one per thread.
class AirPathSearch {
public:
    /// Throws std::invalid_argument when the grid's outermost layer is not all solid
    /// (air_grid()'s always is): the search steps without bounds checks.
    explicit AirPathSearch(const AirGrid& grid);

    /// The length of the shortest path through open voxels from `from` to each of `to`
    /// [Units: world units], kNoAirPath where there is none of at most `max_length`. A
    /// point in a solid voxel (an eye beside a wall) starts or ends at the nearest open
    /// voxel within two voxels of its own that a straight line from it reaches without
    /// meeting a wall (AirGrid::walls), the detour counted; none: no path.
    /// The work is bounded by the voxels within `max_length` of `from`.
    [[nodiscard]] std::vector<float> lengths(glm::vec3 from, std::span<const glm::vec3> to,
                                             float max_length);

private:
    struct LinearStep {
        std::ptrdiff_t offset = 0;              ///< to the neighbour, in the grid's linear index
        float length = 0.0f;                    ///< in voxels
        std::array<std::ptrdiff_t, 6> grazed{}; ///< voxels between, which must be open
        int grazed_count = 0;
    };
    const AirGrid* grid_;
    std::vector<LinearStep> steps_;
    std::vector<float> distance_;       ///< per voxel [Units: voxels], kNoAirPath where not reached
    std::vector<std::uint8_t> settled_; ///< per voxel: its distance is final
    std::vector<std::size_t> touched_;  ///< the voxels the last search reached
    std::array<std::vector<std::size_t>, 3> buckets_; ///< Dial's, kept for their capacity
};

} // namespace dsoc::maps
