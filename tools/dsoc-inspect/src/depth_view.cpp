#include "dsoc/inspect/depth_view.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>

namespace dsoc::inspect {

DepthPyramid DepthPyramid::of(const visibility::OcclusionBuffer& buffer) {
    return {buffer.config().face_resolution, buffer.levels(),
            [&buffer](int f, int l, int x, int y) { return buffer.depth(f, l, x, y); }};
}

DepthPyramid DepthPyramid::of(const visibility::RegionOcclusionBuffer& buffer) {
    return {buffer.config().face_resolution, buffer.levels(),
            [&buffer](int f, int l, int x, int y) { return buffer.depth(f, l, x, y); }};
}

Rgb depth_colour(float depth, const DepthStyle& style) {
    if (!std::isfinite(depth)) {
        return kUnknownDepth;
    }
    const float t = std::clamp(depth / style.far_depth, 0.0f, 1.0f);
    const auto v = static_cast<std::uint8_t>(std::lround(255.0f * (1.0f - t)));
    return {v, v, v};
}

Image render_depth_face(const DepthPyramid& pyramid, int face, int level, const DepthStyle& style) {
    if (face < 0 || face > 5) {
        throw std::invalid_argument("depth image: face " + std::to_string(face) +
                                    " is outside 0..5");
    }
    if (level < 0 || level >= pyramid.levels) {
        throw std::invalid_argument("depth image: level " + std::to_string(level) +
                                    " is outside 0.." + std::to_string(pyramid.levels - 1) +
                                    " (this pyramid has " + std::to_string(pyramid.levels) +
                                    " levels)");
    }
    if (!(style.far_depth > 0.0f)) {
        throw std::invalid_argument("depth image: far depth must be > 0");
    }
    const int size = pyramid.resolution >> level;
    Image texels(size, size);
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            texels.set(x, size - 1 - y, depth_colour(pyramid.depth(face, level, x, y), style));
        }
    }
    const int factor = std::max(1, (std::max(style.face_pixels, 1) + size - 1) / size);
    return Image::scaled(texels, factor);
}

Image render_depth_strip(const DepthPyramid& pyramid, int level, const DepthStyle& style) {
    Image faces[6];
    for (int f = 0; f < 6; ++f) {
        faces[f] = render_depth_face(pyramid, f, level, style);
    }
    const int side = faces[0].width();
    const int gap = std::max(style.gap, 0);
    Image strip(6 * side + 7 * gap, side + 2 * gap, Rgb{0, 0, 0});
    for (int f = 0; f < 6; ++f) {
        strip.blit(faces[f], gap + f * (side + gap), gap);
    }
    return strip;
}

Image render_labeled_depth_strip(const DepthPyramid& pyramid, int level, const DepthStyle& style) {
    const Image strip = render_depth_strip(pyramid, level, style);
    const int gap = std::max(style.gap, 0);
    const int side = (strip.width() - 7 * gap) / 6;
    return with_column_labels(strip, {std::begin(kFaceLabels), std::end(kFaceLabels)}, gap, side,
                              gap);
}

std::vector<LegendEntry> depth_legend(const DepthStyle& style) {
    std::ostringstream far;
    far << "depth: 0 (white) to " << style.far_depth << " world units (black)";
    return {
        {LegendEntry::Swatch::gradient, Rgb{255, 255, 255}, Rgb{0, 0, 0}, far.str()},
        {LegendEntry::Swatch::fill, kUnknownDepth, {}, "nothing known (nothing proven hidden)"}};
}

} // namespace dsoc::inspect
