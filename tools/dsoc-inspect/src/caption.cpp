#include "dsoc/inspect/caption.hpp"

#include "dsoc/inspect/font.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace dsoc::inspect {

namespace {

/// `text` split into lines of at most `max_chars` bytes at spaces.
std::vector<std::string> wrap(const std::string& text, int max_chars) {
    const auto limit = static_cast<std::size_t>(std::max(max_chars, 1));
    std::vector<std::string> lines;
    std::istringstream words(text);
    std::string word;
    std::string line;
    while (words >> word) {
        if (!line.empty() && line.size() + 1 + word.size() > limit) {
            lines.push_back(line);
            line.clear();
        }
        line += (line.empty() ? "" : " ") + word;
        if (line.size() > limit) {
            line.resize(limit);
        }
    }
    if (!line.empty() || lines.empty()) {
        lines.push_back(line);
    }
    return lines;
}

void draw_swatch(Image& image, int x, int y, const LegendEntry& entry, int side) {
    switch (entry.swatch) {
    case LegendEntry::Swatch::fill:
        image.fill_rect(x, y, x + side - 1, y + side - 1, entry.colour);
        break;
    case LegendEntry::Swatch::outline:
        image.draw_rect(x, y, x + side - 1, y + side - 1, entry.colour);
        break;
    case LegendEntry::Swatch::gradient: {
        const int width = 3 * side;
        for (int i = 0; i < width; ++i) {
            const float t = width > 1 ? static_cast<float>(i) / static_cast<float>(width - 1) : 0.f;
            const auto mix = [t](std::uint8_t a, std::uint8_t b) {
                return static_cast<std::uint8_t>(std::lround(a + t * (b - a)));
            };
            const Rgb c{mix(entry.colour.r, entry.colour_to.r),
                        mix(entry.colour.g, entry.colour_to.g),
                        mix(entry.colour.b, entry.colour_to.b)};
            image.fill_rect(x + i, y, x + i, y + side - 1, c);
        }
        break;
    }
    }
}

int swatch_width(const LegendEntry& entry, int side) {
    return entry.swatch == LegendEntry::Swatch::gradient ? 3 * side : side;
}

/// A new image: `picture` with `above` rows of background over it and `below` under it.
Image extended(const Image& picture, int above, int below, Rgb background) {
    Image out(picture.width(), picture.height() + above + below, background);
    out.blit(picture, 0, above);
    return out;
}

} // namespace

float scale_bar_units(float units_per_pixel, int max_pixels) {
    const double longest = static_cast<double>(units_per_pixel) * std::max(max_pixels, 1);
    double decade = std::pow(10.0, std::floor(std::log10(longest)));
    for (;;) {
        for (const double m : {5.0, 2.0, 1.0}) {
            if (m * decade <= longest * (1.0 + 1e-9)) {
                return static_cast<float>(m * decade);
            }
        }
        decade /= 10.0;
    }
}

Image with_title(const Image& picture, const std::vector<std::string>& lines,
                 const CaptionStyle& style) {
    const int pad = std::max(style.padding, 0);
    const int max_chars = (picture.width() - 2 * pad) / kGlyphWidth;
    std::vector<std::pair<std::string, FontWeight>> wrapped;
    for (std::size_t i = 0; i < lines.size(); ++i) {
        for (std::string& l : wrap(lines[i], max_chars)) {
            wrapped.emplace_back(std::move(l), i == 0 ? FontWeight::bold : FontWeight::regular);
        }
    }
    const int band =
        wrapped.empty() ? 0 : pad * 2 + static_cast<int>(wrapped.size()) * text_height();
    Image out = extended(picture, band, 0, style.background);
    int y = pad;
    for (const auto& [text, weight] : wrapped) {
        draw_text(out, pad, y, text, {style.text, weight, 1});
        y += text_height();
    }
    return out;
}

Image with_legend(const Image& picture, const std::vector<LegendEntry>& entries,
                  const std::optional<ScaleBar>& scale, const CaptionStyle& style) {
    const int pad = std::max(style.padding, 0);
    const int side = std::max(style.swatch, 1);
    const int line_height = std::max(text_height(), side) + 3;
    int cell = 1;
    int widest_swatch = side;
    for (const LegendEntry& e : entries) {
        cell = std::max(cell, swatch_width(e, side) + 5 + text_width(e.label) + 2 * pad);
        widest_swatch = std::max(widest_swatch, swatch_width(e, side));
    }
    const int columns = std::max(1, (picture.width() - pad) / cell);
    // One column narrower than a label: labels wrap onto more lines.
    const int label_chars = (picture.width() - 2 * pad - widest_swatch - 5) / kGlyphWidth;
    std::vector<std::vector<std::string>> labels;
    for (const LegendEntry& e : entries) {
        labels.push_back(columns == 1 ? wrap(e.label, label_chars)
                                      : std::vector<std::string>{e.label});
    }
    // Column by column, top to bottom: entries given together stay together.
    const int count = static_cast<int>(entries.size());
    const int rows = (count + columns - 1) / columns;
    int lines = 0;
    for (int c = 0; c < columns; ++c) {
        int column_lines = 0;
        for (int i = c * rows; i < std::min(count, (c + 1) * rows); ++i) {
            column_lines += static_cast<int>(labels[static_cast<std::size_t>(i)].size());
        }
        lines = std::max(lines, column_lines);
    }
    const int band = pad + lines * line_height + (scale ? line_height + pad : 0) + pad;
    Image out = extended(picture, 0, band, style.background);
    const int top = picture.height() + pad;
    int y = top;
    for (int i = 0; i < count; ++i) {
        if (i % rows == 0) {
            y = top;
        }
        const auto& entry = entries[static_cast<std::size_t>(i)];
        const int x = pad + i / rows * cell;
        draw_swatch(out, x, y + (text_height() - side) / 2, entry, side);
        for (const std::string& line : labels[static_cast<std::size_t>(i)]) {
            draw_text(out, x + swatch_width(entry, side) + 5, y, line, {style.text});
            y += line_height;
        }
    }
    if (scale) {
        const float units = scale_bar_units(scale->units_per_pixel, scale->max_pixels);
        const int length =
            std::max(1, static_cast<int>(std::lround(units / scale->units_per_pixel)));
        const int bar_y = top + lines * line_height + pad + text_height() / 2;
        const int x0 = pad;
        const int x1 = x0 + length - 1;
        out.fill_rect(x0, bar_y - 1, x1, bar_y, style.text);
        out.fill_rect(x0, bar_y - 5, x0, bar_y + 4, style.text);
        out.fill_rect(x1, bar_y - 5, x1, bar_y + 4, style.text);
        std::ostringstream label;
        label << units << " world units";
        draw_text(out, x1 + 8, bar_y - text_height() / 2, label.str(), {style.text});
    }
    return out;
}

Image with_column_labels(const Image& picture, const std::vector<std::string>& labels, int first_x,
                         int cell_width, int gap, const CaptionStyle& style) {
    const int band = text_height() + 2 * std::max(style.padding / 2, 1);
    Image out = extended(picture, band, 0, style.background);
    for (std::size_t i = 0; i < labels.size(); ++i) {
        const int left = first_x + static_cast<int>(i) * (cell_width + gap);
        const int x = left + (cell_width - text_width(labels[i])) / 2;
        draw_text(out, std::max(x, left), (band - text_height()) / 2, labels[i],
                  {style.text, FontWeight::bold, 1});
    }
    return out;
}

void draw_label(Image& image, int x, int y, std::string_view text, const CaptionStyle& style) {
    image.fill_rect(x, y, x + text_width(text) + 3, y + text_height() + 3, style.background);
    draw_text(image, x + 2, y + 2, text, {style.text});
}

} // namespace dsoc::inspect
