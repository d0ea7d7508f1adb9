#pragma once
// The top-down plan: the map's occluders as footprints shaded by their top height,
// one client's eye and reachable eye region, every entity coloured by its state
// (client_view.hpp) and the TBVs as box outlines. North (+y) is up, +x to the right.
//
// The colours are fixed (kPalette) so that a test, a script or a reader can tell
// the states apart by pixel value: occluder shades are grey (r == g == b), and no
// state colour is grey.

#include "dsoc/inspect/client_view.hpp"
#include "dsoc/inspect/image.hpp"
#include "dsoc/visibility/convex_polyhedron.hpp"

#include <glm/vec2.hpp>

#include <limits>
#include <vector>

namespace dsoc::inspect {

struct PlanPalette {
    Rgb background{16, 18, 24};
    Rgb replicated_visible{40, 210, 70};
    Rgb replicated_lookahead{250, 200, 30};
    Rgb replicated_held{200, 120, 255};
    Rgb replicated_rule{255, 120, 170}; ///< teammates: pink
    Rgb replicated_heard{255, 130, 0};  ///< heard only: orange
    // Not sent: cool and dark, so that what the client receives stands out and the
    // usual hidden entity does not read as an error.
    Rgb hidden_tbv{60, 120, 255};
    Rgb hidden_expired{25, 35, 80};
    Rgb not_replicated{70, 45, 100};
    Rgb tbv_outline{40, 80, 200};
    Rgb viewer{255, 255, 255};
    Rgb eye_region{0, 230, 230};
    /// Occluder tops are grey from low_shade (lowest top of the map) to high_shade.
    std::uint8_t low_shade = 48;
    std::uint8_t high_shade = 210;

    [[nodiscard]] Rgb of(EntityState s) const;
};
inline constexpr PlanPalette kPalette{};

/// An occluder seen from above: the convex hull of its vertices on the xy plane.
struct Footprint {
    std::vector<glm::vec2> hull; ///< counter-clockwise, world units
    float bottom = 0.0f;         ///< lowest z of the solid [Units: world units]
    float top = 0.0f;            ///< highest z
};

/// The footprints of every non-empty occluder.
[[nodiscard]] std::vector<Footprint>
footprints(const std::vector<visibility::ConvexPolyhedron>& occluders);

struct PlanStyle {
    /// World units per pixel. [Units: world units / pixel] [Limit: > 0]
    float units_per_pixel = 4.0f;
    /// Border around the world bounds. [Units: pixels] [Limit: >= 0]
    int margin = 8;
    /// Occluders whose bottom is above this height are left out (ceilings and
    /// overhangs would hide the floor plan). [Units: world units] NaN: keep all.
    float cut_above = std::numeric_limits<float>::quiet_NaN();
    /// Entities are drawn at least this many pixels wide. [Units: pixels] [Limit: >= 1]
    int min_entity_pixels = 3;
};

/// World <-> pixel mapping of a plan of `bounds` (x and y used) at `style`.
class PlanFrame {
public:
    /// Throws std::invalid_argument when bounds is empty or the image would exceed
    /// Image::kMaxSide (say so: choose a larger units_per_pixel).
    PlanFrame(const visibility::Aabb& bounds, const PlanStyle& style);
    [[nodiscard]] int width() const { return width_; }
    [[nodiscard]] int height() const { return height_; }
    /// Pixel coordinates (continuous: pixel (i, j) spans [i, i+1) x [j, j+1)).
    [[nodiscard]] glm::vec2 to_pixel(float x, float y) const;
    /// The pixel whose area holds world point (x, y).
    [[nodiscard]] int pixel_x(float x) const;
    [[nodiscard]] int pixel_y(float y) const;

private:
    visibility::Aabb bounds_;
    float scale_; ///< pixels per world unit
    int margin_;
    int width_ = 0;
    int height_ = 0;
};

/// Draws the plan. `bounds` sets the picture's extent (normally the map's bounds)
/// and the height range of the shading. Order, later on top: occluders (lower tops
/// first), eye region, TBV outlines, hidden entities, replicated entities, viewer.
[[nodiscard]] Image render_plan(const std::vector<Footprint>& occluders,
                                const visibility::Aabb& bounds, const ClientView& view,
                                const PlanStyle& style = {}, const PlanPalette& palette = kPalette);

} // namespace dsoc::inspect
