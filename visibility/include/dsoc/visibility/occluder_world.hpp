#pragma once
// The static world: opaque convex occluders (brushes), with per-occluder data
// precomputed for the rasterizer and the beam builder.

#include "dsoc/visibility/convex_polyhedron.hpp"
#include "dsoc/visibility/geometry.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace dsoc::visibility {

/// How far the box fast paths shrink a solid box (OccluderWorld::solid_box()): float
/// rounding at world coordinates up to 2^15 units stays below it. [Units: world units]
inline constexpr float kBoxShrink = 1.0f / 64.0f;

/// Index of an occluder in an OccluderWorld, in insertion order. Stable for the
/// world's lifetime (occluders are never removed).
using OccluderId = std::uint32_t;

/// An edge of an occluder with the two faces that share it (indexes into the
/// polyhedron's faces()). Used to find silhouettes.
struct OccluderEdge {
    std::uint32_t v0, v1;
    std::uint32_t face_a, face_b;
};

/// Immutable-after-build set of opaque convex occluders. Not thread-safe to modify;
/// all const members may be called concurrently (per-client culling).
class OccluderWorld {
public:
    /// Adds a non-empty polyhedron and returns its id; empty polyhedra are ignored
    /// and return kInvalid. Call before building a BspTree over the world. Throws
    /// std::length_error past kMaxOccluders (the world is left as it was).
    OccluderId add(ConvexPolyhedron polyhedron);
    static constexpr OccluderId kInvalid = 0xffffffffu;
    /// Occluders a world holds at most: the shaft stage's hints keep an id in their low
    /// 29 bits, beside a tag in the top three (ShaftOcclusion::kPortalHint, kWitnessHint).
    static constexpr std::size_t kMaxOccluders = std::size_t{1} << 29;

    [[nodiscard]] std::size_t size() const { return occluders_.size(); }
    [[nodiscard]] const ConvexPolyhedron& occluder(OccluderId id) const { return occluders_[id]; }
    [[nodiscard]] const std::vector<ConvexPolyhedron>& occluders() const { return occluders_; }
    /// The planes that carry a face (redundant/duplicate planes dropped), unit normals.
    [[nodiscard]] std::span<const Plane> face_planes(OccluderId id) const {
        return {face_planes_.data() + plane_offset_[id], plane_offset_[id + 1] - plane_offset_[id]};
    }
    /// The planes that bound the solid for occlusion: face_planes() plus every other
    /// plane of the brush that comes within 1 unit of a vertex (a face too thin to
    /// survive vertex merging, a bevel), exact duplicates dropped. Their intersection
    /// is never larger than the brush, which is what the rasterizer and the
    /// reference use.
    [[nodiscard]] std::span<const Plane> solid_planes(OccluderId id) const {
        return {solid_planes_.data() + solid_offset_[id],
                solid_offset_[id + 1] - solid_offset_[id]};
    }
    /// Every edge once, with both adjacent faces (face indexes match face_planes()).
    [[nodiscard]] std::span<const OccluderEdge> edges(OccluderId id) const {
        return {edges_.data() + edge_offset_[id], edge_offset_[id + 1] - edge_offset_[id]};
    }
    /// True when every face edge has exactly one twin (a closed, manifold surface)
    /// and no non-face plane cuts the vertices by more than 1e-3 (the faces describe
    /// the brush itself). Only such occluders make occlusion beams: a missing edge
    /// would leave a hole in the silhouette, a missing plane a too-large solid.
    [[nodiscard]] bool is_closed(OccluderId id) const { return closed_[id] != 0; }
    /// When the solid is an axis-aligned box (its solid_planes() are six axis planes)
    /// thicker than 2 kBoxShrink on every axis, that box, exactly as the planes bound
    /// it; else an empty box. Tests may use it instead of the planes (the float fast
    /// paths of shaft_occlusion.hpp, which shrink it by kBoxShrink).
    [[nodiscard]] const Aabb& solid_box(OccluderId id) const { return solid_box_[id]; }
    /// Union of all occluder bounds (empty when the world is).
    [[nodiscard]] const Aabb& bounds() const { return bounds_; }

private:
    std::vector<ConvexPolyhedron> occluders_;
    std::vector<Plane> face_planes_;
    std::vector<std::size_t> plane_offset_{0};
    std::vector<Plane> solid_planes_;
    std::vector<std::size_t> solid_offset_{0};
    std::vector<OccluderEdge> edges_;
    std::vector<std::size_t> edge_offset_{0};
    std::vector<std::uint8_t> closed_;
    std::vector<Aabb> solid_box_;
    Aabb bounds_;
};

} // namespace dsoc::visibility
