#pragma once
// Turns one brush (its side planes) into a collision brush and, when it blocks
// sight, an occluder; counts what was skipped and why. Shared by every loader.
// Private to dsoc::maps.

#include "dsoc/maps/map.hpp"

#include <span>

namespace dsoc::maps::detail {

/// Adds the brush to `map`. `contents` says what it blocks (BrushContents bits);
/// `opaque` whether it may hide things. Returns false (and counts the reason in
/// map.stats.degenerate) when the planes make no usable polyhedron.
bool add_brush(Map& map, std::span<const visibility::Plane> planes, std::uint32_t contents,
               bool opaque);

/// Recomputes map.bounds from the collision brushes and sets the counts that follow
/// from the vectors' sizes.
void finish_map(Map& map);

} // namespace dsoc::maps::detail
