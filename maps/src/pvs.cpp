#include "dsoc/maps/pvs.hpp"

#include <algorithm>
#include <bit>

namespace dsoc::maps {

Pvs::Pvs(const q3::Q3Bsp& bsp, const std::vector<visibility::Aabb>& see_through)
    : num_clusters_(bsp.visibility.num_clusters),
      bytes_per_cluster_(bsp.visibility.bytes_per_cluster), bits_(bsp.visibility.bits) {
    nodes_.reserve(bsp.nodes.size());
    for (const q3::Node& n : bsp.nodes) {
        const q3::Plane& p = bsp.planes[static_cast<std::size_t>(n.plane)];
        nodes_.push_back({p.normal, p.dist, {n.children[0], n.children[1]}});
    }
    leaf_cluster_.reserve(bsp.leafs.size());
    for (const q3::Leaf& l : bsp.leafs) {
        leaf_cluster_.push_back(l.cluster);
    }
    make_symmetric();
    open_through(see_through);
}

namespace {

/// The 8 x 8 bit matrix `m` (byte k is row k; bit j of it, column j) transposed
/// (Hacker's Delight, "transpose8", on a 64-bit word).
constexpr std::uint64_t transpose8x8(std::uint64_t m) {
    std::uint64_t t = (m ^ (m >> 7)) & 0x00AA00AA00AA00AAull;
    m = m ^ t ^ (t << 7);
    t = (m ^ (m >> 14)) & 0x0000CCCC0000CCCCull;
    m = m ^ t ^ (t << 14);
    t = (m ^ (m >> 28)) & 0x00000000F0F0F0F0ull;
    return m ^ t ^ (t << 28);
}
static_assert(transpose8x8(0x02) == 0x0100, "(row 0, column 1) goes to (row 1, column 0)");
static_assert(transpose8x8(0x8000000000000000ull) == 0x8000000000000000ull);

} // namespace

void Pvs::make_symmetric() {
    if (!has_visibility()) {
        return;
    }
    // In blocks of 8 x 8 clusters: block (i, j) is byte j of rows 8i..8i+7, and its
    // mirror block (j, i), transposed, holds the same pairs the other way round. Each
    // row is read a byte at a time along it, where a bit at a time down the columns
    // missed the cache once a pair on maps of thousands of clusters.
    const auto n = static_cast<std::size_t>(num_clusters_);
    const auto row_bytes = static_cast<std::size_t>(bytes_per_cluster_);
    const std::size_t blocks = (n + 7) / 8;
    const auto load = [&](std::size_t i, std::size_t j) {
        std::uint64_t m = 0;
        for (std::size_t k = 0; k < 8 && 8 * i + k < n; ++k) {
            m |= std::uint64_t{bits_[(8 * i + k) * row_bytes + j]} << (8 * k);
        }
        return m;
    };
    const auto store = [&](std::size_t i, std::size_t j, std::uint64_t m) {
        for (std::size_t k = 0; k < 8 && 8 * i + k < n; ++k) {
            bits_[(8 * i + k) * row_bytes + j] = static_cast<std::uint8_t>(m >> (8 * k));
        }
    };
    // The bits of block column j that are clusters (not the last byte's padding), in
    // every row of a block.
    const auto clusters_in = [&](std::size_t j) {
        const std::size_t columns = std::min<std::size_t>(8, n - 8 * j);
        const std::uint64_t byte = (std::uint64_t{1} << columns) - 1;
        return byte * 0x0101010101010101ull;
    };
    for (std::size_t i = 0; i < blocks; ++i) {
        for (std::size_t j = i; j < blocks; ++j) {
            const std::uint64_t here = load(i, j);
            const std::uint64_t there = load(j, i); // here itself on the diagonal
            const std::uint64_t mask = clusters_in(j);
            const std::uint64_t there_mask = clusters_in(i);
            const std::uint64_t mine = here & mask;
            const std::uint64_t theirs = transpose8x8(there & there_mask);
            const std::uint64_t both = mine | theirs;
            // Off the diagonal each pair is once in (i, j); on it, twice.
            const auto disagree = static_cast<std::uint64_t>(std::popcount(mine ^ theirs));
            one_way_pairs_ += i == j ? disagree / 2 : disagree;
            store(i, j, (here & ~mask) | both);
            if (i != j) {
                store(j, i, (there & ~there_mask) | transpose8x8(both));
            }
        }
    }
}

void Pvs::open_through(const std::vector<visibility::Aabb>& see_through) {
    if (!has_visibility() || see_through.empty()) {
        return;
    }
    const auto row_bytes = static_cast<std::size_t>(bytes_per_cluster_);
    const auto set_bits = [&] {
        std::uint64_t count = 0;
        for (const std::uint8_t byte : bits_) {
            count += static_cast<std::uint64_t>(std::popcount(byte));
        }
        return count;
    };
    const std::uint64_t before = set_bits();
    // The clusters touching each brush: the leaves around it, one unit out (its own
    // interior is solid leaves, which have none).
    constexpr float kTouch = 1.0f;
    std::vector<std::vector<std::int32_t>> gates;
    for (const visibility::Aabb& brush : see_through) {
        std::vector<std::int32_t> clusters;
        const visibility::Aabb around{brush.min - glm::vec3(kTouch), brush.max + glm::vec3(kTouch)};
        const Walk walked = walk(around, clusters);
        if (walked == Walk::unknown) {
            std::fill(bits_.begin(), bits_.end(), std::uint8_t{0xff}); // cannot tell: all
            opened_pairs_ = set_bits() - before;
            return;
        }
        if (walked == Walk::found) {
            gates.push_back(std::move(clusters));
        }
    }
    std::vector<std::uint8_t> beyond;
    for (bool changed = true; changed;) {
        changed = false;
        for (const std::vector<std::int32_t>& gate : gates) {
            union_of_rows(gate, beyond); // what the clusters around the brush see
            for (std::int32_t from = 0; from < num_clusters_; ++from) {
                std::uint8_t* row = bits_.data() + static_cast<std::size_t>(from) * row_bytes;
                const bool sees_gate = std::any_of(gate.begin(), gate.end(), [&](std::int32_t g) {
                    return g >= num_clusters_ || (row[g >> 3] & (1u << (g & 7))) != 0;
                });
                if (!sees_gate) {
                    continue;
                }
                for (std::size_t i = 0; i < row_bytes; ++i) {
                    const auto opened = static_cast<std::uint8_t>(row[i] | beyond[i]);
                    changed = changed || opened != row[i];
                    row[i] = opened;
                }
            }
        }
    }
    opened_pairs_ = set_bits() - before;
}

bool Pvs::clusters_of(const visibility::Aabb& box, std::vector<std::int32_t>& out) const {
    return walk(box, out) == Walk::found;
}

bool Pvs::touches_no_cluster(const visibility::Aabb& box) const {
    thread_local std::vector<std::int32_t> clusters;
    return walk(box, clusters) == Walk::none;
}

Pvs::Walk Pvs::walk(const visibility::Aabb& box, std::vector<std::int32_t>& out) const {
    out.clear();
    if (leaf_cluster_.empty()) {
        return Walk::unknown;
    }
    // Walk the node tree with the box: both children where the plane cuts it. The
    // stack bound is the tree depth; parse_q3_bsp guarantees children follow parents.
    std::int32_t stack[1024];
    int top = 0;
    stack[top++] = nodes_.empty() ? -1 : 0;
    const glm::vec3 c = box.center();
    const glm::vec3 h = box.half_extents();
    while (top > 0) {
        const std::int32_t index = stack[--top];
        if (index < 0) {
            const std::size_t leaf = static_cast<std::size_t>(-(index + 1));
            if (leaf < leaf_cluster_.size() && leaf_cluster_[leaf] >= 0) {
                out.push_back(leaf_cluster_[leaf]);
            }
            continue;
        }
        const Node& n = nodes_[static_cast<std::size_t>(index)];
        const float d = n.normal.x * c.x + n.normal.y * c.y + n.normal.z * c.z - n.dist;
        const float r =
            std::abs(n.normal.x) * h.x + std::abs(n.normal.y) * h.y + std::abs(n.normal.z) * h.z;
        if (top + 2 > 1024) {
            out.clear(); // pathological depth: answer "may see"
            return Walk::unknown;
        }
        if (d >= -r) {
            stack[top++] = n.children[0];
        }
        if (d < r) {
            stack[top++] = n.children[1];
        }
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out.empty() ? Walk::none : Walk::found;
}

void Pvs::union_of_rows(const std::vector<std::int32_t>& clusters,
                        std::vector<std::uint8_t>& out) const {
    out.assign(static_cast<std::size_t>(std::max(bytes_per_cluster_, 0)), 0);
    for (const std::int32_t from : clusters) {
        if (from < 0 || from >= num_clusters_) {
            std::fill(out.begin(), out.end(), std::uint8_t{0xff}); // no answer: all
            return;
        }
        const std::size_t row = static_cast<std::size_t>(from) * out.size();
        for (std::size_t i = 0; i < out.size(); ++i) {
            out[i] |= bits_[row + i];
        }
    }
}

bool Pvs::may_see(const std::vector<std::uint8_t>& visible_clusters, const visibility::Aabb& box,
                  std::vector<std::int32_t>& scratch) const {
    if (!has_visibility() || !clusters_of(box, scratch)) {
        return true;
    }
    return may_see_clusters(visible_clusters, scratch);
}

bool Pvs::cluster_visible(int from, int to) const {
    if (num_clusters_ <= 0 || from < 0 || to < 0 || from >= num_clusters_ || to >= num_clusters_) {
        return true;
    }
    const std::size_t row =
        static_cast<std::size_t>(from) * static_cast<std::size_t>(bytes_per_cluster_);
    return (bits_[row + static_cast<std::size_t>(to >> 3)] & (1u << (to & 7))) != 0;
}

} // namespace dsoc::maps
