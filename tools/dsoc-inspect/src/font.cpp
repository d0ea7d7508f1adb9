#include "dsoc/inspect/font.hpp"

#include <algorithm>

namespace dsoc::inspect {

int text_width(std::string_view text, int scale) {
    return static_cast<int>(text.size()) * kGlyphWidth * std::max(scale, 1);
}

int text_height(int scale) {
    return kGlyphHeight * std::max(scale, 1);
}

int draw_text(Image& image, int x, int y, std::string_view text, const TextStyle& style) {
    const int scale = std::max(style.scale, 1);
    const auto& glyphs =
        style.weight == FontWeight::bold ? detail::kFixed6x13Bold : detail::kFixed6x13;
    for (const char ch : text) {
        int index = static_cast<unsigned char>(ch) - detail::kFirstGlyph;
        if (index < 0 || index >= detail::kGlyphCount) {
            index = '?' - detail::kFirstGlyph;
        }
        const auto& rows = glyphs[index];
        for (int row = 0; row < kGlyphHeight; ++row) {
            for (int col = 0; col < kGlyphWidth; ++col) {
                if ((rows[row] >> (7 - col)) & 1) {
                    image.fill_rect(x + col * scale, y + row * scale, x + (col + 1) * scale - 1,
                                    y + (row + 1) * scale - 1, style.colour);
                }
            }
        }
        x += kGlyphWidth * scale;
    }
    return x;
}

} // namespace dsoc::inspect
