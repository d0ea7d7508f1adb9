#pragma once
// What makes a picture read on its own: a title band above it and a legend band below
// it (colour swatches with their meaning, and a scale bar in world units), drawn with
// the built-in font (font.hpp). Each function returns a new, taller image of the same
// width; the picture itself is copied unchanged.

#include "dsoc/inspect/image.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace dsoc::inspect {

struct LegendEntry {
    enum class Swatch : std::uint8_t {
        fill,     ///< a filled square of `colour`
        outline,  ///< a square outline of `colour`
        gradient, ///< a bar shading from `colour` (left) to `colour_to` (right)
    };
    Swatch swatch = Swatch::fill;
    Rgb colour;
    Rgb colour_to;
    std::string label;
};

struct ScaleBar {
    /// The picture's scale. [Units: world units / pixel] [Limit: > 0]
    float units_per_pixel = 1.0f;
    /// The bar is at most this long, and as long as a 1, 2 or 5 x 10^k world units
    /// allows. [Units: pixels]
    int max_pixels = 160;
};

/// The scale bar's length: the largest 1, 2 or 5 x 10^k world units (k any integer)
/// whose bar is at most `max_pixels` long. [Units: world units]
[[nodiscard]] float scale_bar_units(float units_per_pixel, int max_pixels);

struct CaptionStyle {
    Rgb background{16, 18, 24};
    Rgb text{225, 228, 235};
    /// Space around and between the bands' contents. [Units: pixels]
    int padding = 6;
    /// Swatch side. [Units: pixels]
    int swatch = 11;
};

/// `picture` under a band holding `lines`, the first in bold, each wrapped at spaces to
/// the picture's width (a word longer than the width is cut).
[[nodiscard]] Image with_title(const Image& picture, const std::vector<std::string>& lines,
                               const CaptionStyle& style = {});

/// `picture` over a band holding `entries` in as many equal columns as the width fits,
/// filled column by column in the order given; in a single column, labels wider than
/// the picture wrap at spaces. Then the scale bar when given: a bar of
/// scale_bar_units(...) / units_per_pixel pixels (rounded) with end ticks, labelled
/// with its length in world units.
[[nodiscard]] Image with_legend(const Image& picture, const std::vector<LegendEntry>& entries,
                                const std::optional<ScaleBar>& scale = std::nullopt,
                                const CaptionStyle& style = {});

/// `picture` with `labels[i]` centred above the i-th of `count` equal cells laid side by
/// side from x = first_x, each `cell_width` wide and `gap` apart (a strip of faces).
[[nodiscard]] Image with_column_labels(const Image& picture, const std::vector<std::string>& labels,
                                       int first_x, int cell_width, int gap,
                                       const CaptionStyle& style = {});

/// `text` on a box of style.background with 2 pixels around it, the box's top-left
/// corner at (x, y), drawn onto `image` (a label inside a picture, e.g. a frame's tick).
void draw_label(Image& image, int x, int y, std::string_view text, const CaptionStyle& style = {});

} // namespace dsoc::inspect
