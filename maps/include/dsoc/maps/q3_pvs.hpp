#pragma once
// The map compiler's potentially visible set (PVS) of a Quake 3 BSP: which leaf and
// cluster a point is in, and whether one cluster may see another. Read-only queries on
// a parsed Q3Bsp; safe to call from many threads.
//
// Meaning: cluster_visible() == false means the compiler's row of `from` does not hold
// `to`, read as it is in the file. That is what the compiler claims, not a proof: its
// rows need not agree both ways (kaos), and its vis takes see-through brushes for
// walls, so only maps::Pvs (pvs.hpp), which mends both, is conservative. When there is
// no answer (no vis data, as in oa_ctf2, or a point in solid / outside the map, cluster
// -1) it says visible.

#include "dsoc/maps/q3_bsp.hpp"

#include <glm/vec3.hpp>

namespace dsoc::maps::q3 {

/// Index of the leaf containing `point`, or -1 when the map has no leafs. Walks the
/// node tree (at most nodes.size() steps: parse_q3_bsp rejects cycles).
[[nodiscard]] int find_leaf(const Q3Bsp& bsp, glm::vec3 point);

/// Cluster of the leaf containing `point`; -1 in solid, outside the map or without leafs.
[[nodiscard]] int cluster_at(const Q3Bsp& bsp, glm::vec3 point);

/// True unless the compiler's row of `from` leaves out `to` (see above).
[[nodiscard]] bool cluster_visible(const Q3Bsp& bsp, int from, int to);

/// True when the map has vis data (num_clusters > 0).
[[nodiscard]] inline bool has_visibility(const Q3Bsp& bsp) {
    return bsp.visibility.num_clusters > 0;
}

} // namespace dsoc::maps::q3
