#pragma once
// A uniform grid of occluder ids: which occluders may touch a box or a segment.

#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/occluder_world.hpp"

#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

namespace dsoc::visibility {

/// A uniform grid over an occluder world's bounds listing the occluders that
/// overlap each cell, to find the occluders that may cut a shaft. Immutable after
/// construction; queries are const and thread-safe given a caller-owned scratch.
class OccluderGrid {
public:
    /// The finest cell edge the scene's grid uses (docs/RESULTS.md: how it was chosen
    /// for the bake and the exact stages). [Units: world units]
    static constexpr float kDefaultCellSize = 128.0f;
    /// Entries all cells' lists may hold (4 bytes each); a world that would need more
    /// gets coarser cells. [Units: occluder ids]
    static constexpr std::uint64_t kMaxListEntries = std::uint64_t{1} << 23;

    /// `cell_size` in world units (> 0): the finest cell edge; doubled until the lists
    /// hold at most kMaxListEntries. What a query promises to find does not depend on
    /// it, only the order it finds them in and the time it takes.
    explicit OccluderGrid(const OccluderWorld& world, float cell_size = kDefaultCellSize);

    /// The cell edge in use (after any doubling). [Units: world units]
    [[nodiscard]] float cell_size() const { return cell_size_; }

    /// Scratch for one querying thread (a visit stamp per occluder).
    struct Scratch {
        std::vector<std::uint32_t> stamp;
        std::uint32_t epoch = 0;
        std::vector<OccluderId> found;
    };

    /// Occluders whose bounds overlap `box`, each once, into scratch.found.
    void query(const Aabb& box, Scratch& scratch) const;

    /// The occluders listed in the cell that holds `p` (clamped to the grid): every
    /// occluder whose bounds contain `p` is among them. Empty for an empty world.
    [[nodiscard]] std::span<const OccluderId> items_at(glm::vec3 p) const;

    /// Occluders in the cells the segment `from`-`to` passes through (a 3D DDA walk),
    /// each once, into scratch.found: every occluder that intersects the segment is
    /// among them (up to float rounding at cell borders, which can only drop one).
    void query_segment(glm::vec3 from, glm::vec3 to, Scratch& scratch) const;

    /// The occluders query_segment() finds, each offered once to `stop` (a callable
    /// bool(OccluderId)) cell by cell from `from` towards `to`, so nearer ones mostly
    /// first; true as soon as `stop` returns true (the rest of the walk is skipped),
    /// false when every one was offered. scratch.found is not touched.
    template <class Stop>
    bool any_along_segment(glm::vec3 from, glm::vec3 to, Scratch& scratch, Stop&& stop) const {
        return walk_segment(
            from, to, scratch,
            [](void* s, OccluderId id) {
                return (*static_cast<std::remove_reference_t<Stop>*>(s))(id);
            },
            &stop);
    }

private:
    using Visit = bool (*)(void* context, OccluderId id);
    /// The walk behind query_segment() and any_along_segment(): `visit` gets each
    /// occluder once; true from it ends the walk (and is returned).
    bool walk_segment(glm::vec3 from, glm::vec3 to, Scratch& scratch, Visit visit,
                      void* context) const;

    const OccluderWorld* world_;
    Aabb bounds_;
    float cell_size_;
    int dims_[3] = {1, 1, 1};
    std::vector<std::uint32_t> cell_start_; ///< CSR offsets, one more than cells
    std::vector<OccluderId> cell_items_;
};

} // namespace dsoc::visibility
