#pragma once
// The map compiler's potentially visible set, kept with a loaded map in compact form
// (the BSP node tree, leaf clusters and cluster-to-cluster bits; no other lumps), with
// the queries an interest policy needs: the clusters a box touches, and whether some
// cluster of one set may see some cluster of a box.
//
// Conservative meaning (as far as the compiler's vis is, once made symmetric and opened
// through the brushes it took for walls but that let sight through: see the
// constructor): if any point of box B can be seen from any point of region R, then some
// cluster of B is in the PVS of some cluster of R. Clusters are those of the non-solid
// leaves a box overlaps; a box that overlaps no such leaf (in solid, or outside the
// map), a map without vis data (oa_ctf2), or a leaf without a cluster all answer "may
// see".
// Threading: immutable after construction; all queries are const and thread-safe.

#include "dsoc/maps/q3_bsp.hpp"
#include "dsoc/visibility/geometry.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dsoc::maps {

class Pvs {
public:
    /// Copies the nodes, planes, leaf clusters and vis bits of `bsp` and makes the bits
    /// symmetric: a pair of clusters one of whose rows holds the other is visible both
    /// ways. Sight goes both ways along a line, but the compiler's rows need not agree
    /// (kaos: cluster 725 sees 646, 646 does not see 725, and a clear line joins an eye in
    /// 646 to a player in 725), and the wrong one hides what is seen. Then it opens them
    /// through `see_through`: the bounds of solid brushes the compiler's vis stopped at as
    /// at walls but that let sight through (q3_shaders.hpp: grates, windows). A line of
    /// sight through such a brush leaves it in a cluster touching it, and goes on as from
    /// there: so every cluster whose row holds a cluster touching the brush gets the rows
    /// of all the clusters touching it, until nothing changes (a line through several
    /// such brushes in a row). Without that, a box seen only through a grate would be
    /// proven hidden. A brush whose clusters the tree walk cannot tell opens every pair.
    explicit Pvs(const q3::Q3Bsp& bsp, const std::vector<visibility::Aabb>& see_through = {});

    /// True when the map has vis data; without it every query answers "may see".
    [[nodiscard]] bool has_visibility() const { return num_clusters_ > 0; }
    [[nodiscard]] int cluster_count() const { return num_clusters_; }

    /// Appends the clusters of the non-solid leaves `box` overlaps (each once) to `out`
    /// (cleared first). Returns false when the box overlaps no clustered leaf.
    bool clusters_of(const visibility::Aabb& box, std::vector<std::int32_t>& out) const;

    /// True only when `box` surely touches no leaf with a cluster (in solid, or outside
    /// the map): false without vis data or when the tree walk gives up.
    [[nodiscard]] bool touches_no_cluster(const visibility::Aabb& box) const;

    /// The union of the PVS rows of `clusters`, as a bitset of cluster_count() bits
    /// (one byte per 8 clusters), into `out`.
    void union_of_rows(const std::vector<std::int32_t>& clusters,
                       std::vector<std::uint8_t>& out) const;

    /// True unless the PVS proves `box` invisible from every cluster whose bit is set in
    /// `visible_clusters` (a union_of_rows() result). `scratch` is reused storage.
    [[nodiscard]] bool may_see(const std::vector<std::uint8_t>& visible_clusters,
                               const visibility::Aabb& box,
                               std::vector<std::int32_t>& scratch) const;

    /// may_see() for a box whose clusters_of() (true) gave `clusters`: true unless none of
    /// them is set in `visible_clusters`.
    [[nodiscard]] bool may_see_clusters(const std::vector<std::uint8_t>& visible_clusters,
                                        const std::vector<std::int32_t>& clusters) const {
        for (const std::int32_t to : clusters) {
            const auto byte = static_cast<std::size_t>(to >> 3); // huge for a negative `to`
            if (to >= num_clusters_ || byte >= visible_clusters.size() ||
                (visible_clusters[byte] & (1u << (to & 7))) != 0) {
                return true;
            }
        }
        return false;
    }

    /// Whether cluster `from` may see cluster `to` (true for -1 or out of range).
    [[nodiscard]] bool cluster_visible(int from, int to) const;

    /// Ordered cluster pairs the see-through brushes opened (false in the symmetric
    /// bits, true here).
    [[nodiscard]] std::uint64_t opened_pairs() const { return opened_pairs_; }
    /// Unordered cluster pairs the compiler's rows disagreed on (one saw the other, not
    /// the reverse), now visible both ways.
    [[nodiscard]] std::uint64_t one_way_pairs() const { return one_way_pairs_; }

private:
    enum class Walk { found, none, unknown };
    /// The clusters of the leaves `box` overlaps into `out`; `unknown` (out empty)
    /// without vis data or when the walk is deeper than its stack.
    Walk walk(const visibility::Aabb& box, std::vector<std::int32_t>& out) const;

    struct Node {
        glm::vec3 normal;
        float dist;
        std::int32_t children[2];
    };
    std::vector<Node> nodes_;
    std::vector<std::int32_t> leaf_cluster_;
    std::int32_t num_clusters_ = 0;
    std::int32_t bytes_per_cluster_ = 0;
    std::vector<std::uint8_t> bits_;
    std::uint64_t opened_pairs_ = 0;
    std::uint64_t one_way_pairs_ = 0;

    void make_symmetric();
    void open_through(const std::vector<visibility::Aabb>& see_through);
};

} // namespace dsoc::maps
