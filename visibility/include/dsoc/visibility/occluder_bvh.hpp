#pragma once
// A bounding volume hierarchy over an occluder world's bounds: which occluders a
// segment may touch, found without walking every grid cell along it.

#include "dsoc/visibility/geometry.hpp"
#include "dsoc/visibility/occluder_world.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dsoc::visibility {

/// A tree of boxes over the occluders' bounds, four children to a node (one SSE
/// register a coordinate), built once: immutable after construction; queries are
/// const, allocate nothing and are thread-safe.
///
/// What a query offers does not depend on the tree's shape: every occluder whose bounds,
/// grown by the query's margin, clip_segment_to_box() finds the segment touching, and no
/// other (for a segment with a non-finite end or length: every occluder). A node's box is
/// the min and max of what it holds, so it holds each exactly; growing rounds
/// monotonically, and so does that test in the box (its subtractions and products): a
/// segment that touches an occluder's grown bounds touches every grown box above it. Each
/// box, an occluder's bounds in its slot too, is grown and tested as
/// clip_segment_to_box() does (touches()).
class OccluderBvh {
public:
    /// Levels split by the surface area heuristic (uneven parts); below them, at medians.
    static constexpr int kSahLevels = 16;

    /// `world` need not outlive this: the tree keeps copies of the bounds. `sah_levels`
    /// (at most kSahLevels; fewer only to test the median splits) as above. Worlds hold
    /// at most OccluderWorld::kMaxOccluders occluders, so ids and node indices fit
    /// below kItem.
    explicit OccluderBvh(const OccluderWorld& world, int sah_levels = kSahLevels);

    /// Offers `stop` (a callable bool(OccluderId)) each occluder whose bounds, grown by
    /// `margin` on every side (min - margin, max + margin in floats), the segment
    /// `from`-`to` touches, each once, in no promised order; true as soon as `stop`
    /// returns true. A segment with a NaN or infinite end or length offers every
    /// occluder, so that no caller takes the tree's silence for a clear path.
    /// [Units: margin in world units, >= 0]
    template <class Stop>
    bool any_touching_segment(glm::vec3 from, glm::vec3 to, Stop&& stop,
                              float margin = 0.0f) const {
        if (nodes_.empty()) {
            return false;
        }
        const glm::vec3 dir = to - from;
        if (!finite(from) || !finite(dir)) {
            for (OccluderId id = 0; id < occluders_; ++id) {
                if (stop(id)) {
                    return true;
                }
            }
            return false;
        }
        const Ray ray = Ray::of(from, dir, margin);
        // Without a margin (the centre checks, the most frequent) the boxes as they are,
        // without the two additions an axis.
        return margin == 0.0f ? search<false>(ray, stop) : search<true>(ray, stop);
    }

    /// Nodes in the tree (for tests and sizes).
    [[nodiscard]] std::size_t node_count() const { return nodes_.size(); }
    /// Levels of nodes below the root at most (0 for a root alone): at most sah_levels
    /// plus one level per factor of four the occluders then have to lose, which keeps a
    /// query's stack within kStackSize.
    [[nodiscard]] int depth() const { return depth_; }

private:
    /// A child slot: a node's index, or kItem | an occluder id; kEmpty for none (its
    /// box is empty, so no segment touches it).
    static constexpr std::uint32_t kItem = 0x80000000u;
    static constexpr std::uint32_t kEmpty = 0xffffffffu;
    /// Node indices a query holds at once at most: three more per level, at most
    /// kSahLevels + 1 + log2(occluders) / 2 levels (fewer than 2^32 occluders).
    static constexpr int kStackSize = 3 * (kSahLevels + 18) + 1;

    struct alignas(16) Node {
        float min[3][4]; ///< per axis, the four children's
        float max[3][4];
        std::uint32_t child[4];
        unsigned used = 0; ///< bit i set when child[i] is not kEmpty
    };
    /// The segment as touches() reads it: its start and 1 / length per axis (infinite
    /// for an axis it does not move along), and how far every box is grown.
    struct Ray {
        glm::vec3 from{0.0f};
        glm::vec3 inv{0.0f};
        float margin = 0.0f;
        static Ray of(glm::vec3 from, glm::vec3 dir, float margin) {
            return {from, glm::vec3(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z), margin};
        }
    };

    static bool finite(glm::vec3 v) {
        return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    }
    /// Bit i set when child i is used and the segment touches its box grown by
    /// ray.margin, as clip_segment_to_box() answers for that grown box; kGrown false
    /// (ray.margin 0) skips the growing. (Grown by 0, a box answers as itself: x - 0 and
    /// x + 0 are x, or +0 for -0 + 0, which every comparison takes for -0.)
    template <bool kGrown>
    static unsigned touches(const Node& node, const Ray& ray) {
#if defined(__SSE2__)
        // clip_segment_to_box()'s floats, four boxes at a time: the same products, each
        // axis's entry and exit as its swap leaves them (min and max of two numbers), the
        // same max and min over the axes. On an axis the segment does not move along,
        // inv is infinite and a product is infinite, or NaN where the start lies on the
        // box's side: then the axis lets the segment through, as the function's
        // comparisons do there (start neither below min nor above max).
        __m128 enter = _mm_setzero_ps();
        __m128 exit = _mm_set1_ps(1.0f);
        const __m128 low = _mm_set1_ps(-std::numeric_limits<float>::infinity());
        const __m128 high = _mm_set1_ps(std::numeric_limits<float>::infinity());
        const __m128 margin = _mm_set1_ps(ray.margin);
        for (int a = 0; a < 3; ++a) {
            const __m128 from = _mm_set1_ps(ray.from[a]);
            const __m128 inv = _mm_set1_ps(ray.inv[a]);
            __m128 min = _mm_load_ps(node.min[a]);
            __m128 max = _mm_load_ps(node.max[a]);
            if constexpr (kGrown) {
                min = _mm_sub_ps(min, margin);
                max = _mm_add_ps(max, margin);
            }
            const __m128 ta = _mm_mul_ps(_mm_sub_ps(min, from), inv);
            const __m128 tb = _mm_mul_ps(_mm_sub_ps(max, from), inv);
            const __m128 nan = _mm_cmpunord_ps(ta, tb);
            const __m128 lo =
                _mm_or_ps(_mm_andnot_ps(nan, _mm_min_ps(ta, tb)), _mm_and_ps(nan, low));
            const __m128 hi =
                _mm_or_ps(_mm_andnot_ps(nan, _mm_max_ps(ta, tb)), _mm_and_ps(nan, high));
            enter = _mm_max_ps(enter, lo);
            exit = _mm_min_ps(exit, hi);
        }
        return static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(enter, exit))) & node.used;
#else
        unsigned hits = 0;
        for (int i = 0; i < 4; ++i) {
            const glm::vec3 m(ray.margin);
            const Aabb box{glm::vec3(node.min[0][i], node.min[1][i], node.min[2][i]) - m,
                           glm::vec3(node.max[0][i], node.max[1][i], node.max[2][i]) + m};
            float t0 = 0.0f;
            float t1 = 1.0f;
            if (clip_segment_to_box(ray.from, ray.inv, box, t0, t1)) {
                hits |= 1u << i;
            }
        }
        return hits & node.used;
#endif
    }
    /// any_touching_segment() for a finite segment; kGrown: the boxes grown by
    /// ray.margin (else ray.margin is 0 and not read).
    template <bool kGrown, class Stop>
    bool search(const Ray& ray, Stop& stop) const {
        std::uint32_t stack[kStackSize];
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const Node& node = nodes_[stack[--top]];
            for (unsigned hits = touches<kGrown>(node, ray); hits != 0; hits &= hits - 1) {
                const std::uint32_t child = node.child[std::countr_zero(hits)];
                if ((child & kItem) == 0) {
                    stack[top++] = child;
                    continue;
                }
                if (stop(child & ~kItem)) { // its slot's box is its bounds, just tested
                    return true;
                }
            }
        }
        return false;
    }
    /// Builds the node at `depth` over ids[begin, end) (one or more; `bounds` per
    /// occluder id); returns its index.
    std::uint32_t build(const std::vector<Aabb>& bounds, std::vector<OccluderId>& ids,
                        std::size_t begin, std::size_t end, int depth);
    /// The child slot for ids[begin, end): the occluder itself when it is one, else a node.
    std::uint32_t slot(const std::vector<Aabb>& bounds, std::vector<OccluderId>& ids,
                       std::size_t begin, std::size_t end, int depth);

    int sah_levels_;
    int depth_ = 0;
    std::vector<Node> nodes_; ///< the root first
    std::size_t occluders_ = 0;
};

} // namespace dsoc::visibility
