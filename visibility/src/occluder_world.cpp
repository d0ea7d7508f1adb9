#include "dsoc/visibility/occluder_world.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace dsoc::visibility {

OccluderId OccluderWorld::add(ConvexPolyhedron polyhedron) {
    if (polyhedron.is_empty()) {
        return kInvalid;
    }
    if (occluders_.size() >= kMaxOccluders) {
        throw std::length_error("OccluderWorld::add: the world already holds " +
                                std::to_string(occluders_.size()) +
                                " occluders, the most its ids can name (kMaxOccluders)");
    }
    const auto id = static_cast<OccluderId>(occluders_.size());
    const auto& faces = polyhedron.faces();
    for (const PolyhedronFace& face : faces) {
        face_planes_.push_back(face.plane);
    }
    plane_offset_.push_back(face_planes_.size());

    // Solid planes: faces first, then near-touching non-face planes.
    const std::size_t solid_begin = solid_planes_.size();
    bool cuts_vertices = false;
    for (const PolyhedronFace& face : faces) {
        solid_planes_.push_back(face.plane);
    }
    for (const Plane& p : polyhedron.planes()) {
        bool duplicate = false;
        for (std::size_t k = solid_begin; k < solid_planes_.size() && !duplicate; ++k) {
            const Plane& q = solid_planes_[k];
            duplicate = q.normal == p.normal && q.distance <= p.distance;
        }
        if (duplicate) {
            continue;
        }
        float nearest = std::numeric_limits<float>::lowest();
        for (const glm::vec3& v : polyhedron.vertices()) {
            nearest = std::max(nearest, p.signed_distance(v));
        }
        if (nearest > -1.0f) {
            solid_planes_.push_back(p);
            // A non-face plane that cuts the (merged) vertices means the faces
            // describe a slightly larger solid than the brush: no beams from it.
            cuts_vertices = cuts_vertices || nearest > 1.0e-3f;
        }
    }
    solid_offset_.push_back(solid_planes_.size());
    // An axis-aligned box: six solid planes, one per axis and direction. The solid is
    // then exactly the box the planes bound.
    Aabb solid;
    int sides = 0;
    for (std::size_t k = solid_begin; k < solid_planes_.size(); ++k) {
        const Plane& p = solid_planes_[k];
        for (int a = 0; a < 3; ++a) {
            if (p.normal[(a + 1) % 3] != 0.0f || p.normal[(a + 2) % 3] != 0.0f) {
                continue;
            }
            if (p.normal[a] == 1.0f) {
                solid.max[a] = p.distance;
                sides |= 1 << (2 * a);
            } else if (p.normal[a] == -1.0f) {
                solid.min[a] = -p.distance;
                sides |= 2 << (2 * a);
            }
        }
    }
    // A box the fast paths' shrink would turn inside out is left to the planes.
    const glm::vec3 thickness = solid.max - solid.min;
    const bool box = solid_planes_.size() - solid_begin == 6 && sides == 0b111111 &&
                     std::min({thickness.x, thickness.y, thickness.z}) > 2.0f * kBoxShrink;
    solid_box_.push_back(box ? solid : Aabb{});

    // Edges: each directed edge (a->b) of a face loop meets its twin (b->a) in the
    // neighbouring face. Sorting by the undirected key pairs them up.
    struct HalfEdge {
        std::uint32_t lo, hi, face;
    };
    std::vector<HalfEdge> half_edges;
    for (std::uint32_t f = 0; f < faces.size(); ++f) {
        const auto& loop = faces[f].vertex_indices;
        for (std::size_t i = 0; i < loop.size(); ++i) {
            const std::uint32_t a = loop[i];
            const std::uint32_t b = loop[(i + 1) % loop.size()];
            half_edges.push_back({std::min(a, b), std::max(a, b), f});
        }
    }
    std::sort(half_edges.begin(), half_edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
        return x.lo != y.lo ? x.lo < y.lo : (x.hi != y.hi ? x.hi < y.hi : x.face < y.face);
    });
    bool closed = half_edges.size() % 2 == 0;
    for (std::size_t i = 0; i < half_edges.size(); ++i) {
        const HalfEdge& x = half_edges[i];
        if (i + 1 < half_edges.size()) {
            const HalfEdge& y = half_edges[i + 1];
            if (x.lo == y.lo && x.hi == y.hi && x.face != y.face) {
                const bool third = i + 2 < half_edges.size() && half_edges[i + 2].lo == x.lo &&
                                   half_edges[i + 2].hi == x.hi;
                closed = closed && !third;
                edges_.push_back({x.lo, x.hi, x.face, y.face});
                ++i;
                continue;
            }
        }
        closed = false;
    }
    closed_.push_back(closed && !cuts_vertices ? 1 : 0);
    edge_offset_.push_back(edges_.size());
    bounds_.extend(polyhedron.bounds());
    occluders_.push_back(std::move(polyhedron));
    return id;
}

} // namespace dsoc::visibility
