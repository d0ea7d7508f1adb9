#pragma once
// Text in the inspector's pictures: a fixed 6 x 13 pixel bitmap font (misc-fixed, the
// X Window System's public-domain fonts; font_glyphs.cpp), regular or bold, drawn at an
// integer scale. ASCII 32..126; any other byte draws as '?'. No font file or library
// is read at run time, so the pictures are the same on every machine.

#include "dsoc/inspect/image.hpp"

#include <cstdint>
#include <string_view>

namespace dsoc::inspect {

/// Glyph cell size at scale 1. [Units: pixels]
inline constexpr int kGlyphWidth = 6;
inline constexpr int kGlyphHeight = 13;

enum class FontWeight : std::uint8_t { regular, bold };

struct TextStyle {
    Rgb colour{225, 228, 235};
    FontWeight weight = FontWeight::regular;
    /// Each font pixel becomes scale x scale pixels. [Limit: >= 1]
    int scale = 1;
};

/// Width of `text` on one line at `scale`: kGlyphWidth * scale per byte. [Units: pixels]
[[nodiscard]] int text_width(std::string_view text, int scale = 1);
/// Height of one line at `scale`. [Units: pixels]
[[nodiscard]] int text_height(int scale = 1);

/// Draws `text` on one line with its cell's top-left corner at (x, y). Only the
/// glyphs' set pixels are written: the image shows through elsewhere. Clipped to the
/// image. Returns the x just right of the text.
int draw_text(Image& image, int x, int y, std::string_view text, const TextStyle& style = {});

namespace detail {
inline constexpr int kFirstGlyph = 32; ///< ' '
inline constexpr int kGlyphCount = 95; ///< ' ' .. '~'
/// One glyph: kGlyphHeight rows, top first, leftmost pixel in bit 7.
using GlyphRows = std::uint8_t[kGlyphHeight];
extern const GlyphRows kFixed6x13[kGlyphCount];
extern const GlyphRows kFixed6x13Bold[kGlyphCount];
} // namespace detail

} // namespace dsoc::inspect
