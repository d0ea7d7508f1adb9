#include "dsoc/inspect/image.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace dsoc::inspect {

Image::Image(int width, int height, Rgb fill) : width_(width), height_(height) {
    if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide) {
        throw std::invalid_argument("image size " + std::to_string(width) + " x " +
                                    std::to_string(height) + " is outside 1.." +
                                    std::to_string(kMaxSide) + " per side");
    }
    pixels_.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), fill);
}

void Image::set(int x, int y, Rgb c) {
    if (contains(x, y)) {
        pixels_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                static_cast<std::size_t>(x)] = c;
    }
}

void Image::fill_rect(int x0, int y0, int x1, int y1, Rgb c) {
    const int xa = std::max(std::min(x0, x1), 0);
    const int xb = std::min(std::max(x0, x1), width_ - 1);
    const int ya = std::max(std::min(y0, y1), 0);
    const int yb = std::min(std::max(y0, y1), height_ - 1);
    for (int y = ya; y <= yb; ++y) {
        for (int x = xa; x <= xb; ++x) {
            pixels_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                    static_cast<std::size_t>(x)] = c;
        }
    }
}

void Image::draw_rect(int x0, int y0, int x1, int y1, Rgb c) {
    draw_line(x0, y0, x1, y0, c);
    draw_line(x1, y0, x1, y1, c);
    draw_line(x1, y1, x0, y1, c);
    draw_line(x0, y1, x0, y0, c);
}

void Image::draw_line(int x0, int y0, int x1, int y1, Rgb c) {
    // Lines far outside the image are clipped to a generous box first so that a
    // wild coordinate cannot make the loop run for billions of steps.
    const int limit = 4 * kMaxSide;
    x0 = std::clamp(x0, -limit, limit);
    x1 = std::clamp(x1, -limit, limit);
    y0 = std::clamp(y0, -limit, limit);
    y1 = std::clamp(y1, -limit, limit);
    const int dx = std::abs(x1 - x0);
    const int dy = -std::abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1;
    const int sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    for (;;) {
        set(x0, y0, c);
        if (x0 == x1 && y0 == y1) {
            break;
        }
        const int e2 = 2 * err;
        if (e2 >= dy) {
            err += dy;
            x0 += sx;
        }
        if (e2 <= dx) {
            err += dx;
            y0 += sy;
        }
    }
}

void Image::fill_convex(std::span<const glm::vec2> points, Rgb c) {
    if (points.size() < 3) {
        return;
    }
    float min_x = points[0].x, max_x = points[0].x, min_y = points[0].y, max_y = points[0].y;
    double area2 = 0.0; // twice the signed area: its sign is the winding
    for (std::size_t i = 0; i < points.size(); ++i) {
        const glm::vec2 a = points[i];
        const glm::vec2 b = points[(i + 1) % points.size()];
        min_x = std::min(min_x, a.x);
        max_x = std::max(max_x, a.x);
        min_y = std::min(min_y, a.y);
        max_y = std::max(max_y, a.y);
        area2 += static_cast<double>(a.x) * b.y - static_cast<double>(b.x) * a.y;
    }
    if (area2 == 0.0 || !std::isfinite(area2)) {
        return;
    }
    const float winding = area2 > 0.0 ? 1.0f : -1.0f;
    const int xa = std::max(0, static_cast<int>(std::floor(min_x)));
    const int xb = std::min(width_ - 1, static_cast<int>(std::ceil(max_x)));
    const int ya = std::max(0, static_cast<int>(std::floor(min_y)));
    const int yb = std::min(height_ - 1, static_cast<int>(std::ceil(max_y)));
    for (int y = ya; y <= yb; ++y) {
        for (int x = xa; x <= xb; ++x) {
            const glm::vec2 p(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f);
            bool inside = true;
            for (std::size_t i = 0; i < points.size() && inside; ++i) {
                const glm::vec2 a = points[i];
                const glm::vec2 b = points[(i + 1) % points.size()];
                const float cross = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
                inside = cross * winding >= 0.0f;
            }
            if (inside) {
                set(x, y, c);
            }
        }
    }
}

void Image::blit(const Image& source, int x, int y) {
    const int sx0 = std::max(0, -x);
    const int sy0 = std::max(0, -y);
    const int sx1 = std::min(source.width(), width_ - x);
    const int sy1 = std::min(source.height(), height_ - y);
    for (int sy = sy0; sy < sy1; ++sy) {
        for (int sx = sx0; sx < sx1; ++sx) {
            set(x + sx, y + sy, source.at(sx, sy));
        }
    }
}

Image Image::cropped(const Image& source, int x, int y, int width, int height, Rgb fill) {
    Image out(width, height, fill);
    out.blit(source, -x, -y);
    return out;
}

Image Image::grid(const std::vector<Image>& images, int columns, int gap, Rgb fill) {
    if (images.empty() || columns < 1 || gap < 0) {
        throw std::invalid_argument("Image::grid needs images, columns >= 1 and gap >= 0");
    }
    const int w = images.front().width();
    const int h = images.front().height();
    for (const Image& i : images) {
        if (i.width() != w || i.height() != h) {
            throw std::invalid_argument("Image::grid: images differ in size (" +
                                        std::to_string(i.width()) + " x " +
                                        std::to_string(i.height()) + " vs " + std::to_string(w) +
                                        " x " + std::to_string(h) + ")");
        }
    }
    const int count = static_cast<int>(images.size());
    const int cols = std::min(columns, count);
    const int rows = (count + cols - 1) / cols;
    Image out(cols * w + (cols + 1) * gap, rows * h + (rows + 1) * gap, fill);
    for (int k = 0; k < count; ++k) {
        out.blit(images[static_cast<std::size_t>(k)], gap + (k % cols) * (w + gap),
                 gap + (k / cols) * (h + gap));
    }
    return out;
}

Image Image::scaled(const Image& source, int factor) {
    if (factor < 1 || source.empty()) {
        throw std::invalid_argument(
            "Image::scaled needs a non-empty image and a factor >= 1, got " +
            std::to_string(factor));
    }
    Image out(source.width() * factor, source.height() * factor);
    for (int y = 0; y < out.height(); ++y) {
        for (int x = 0; x < out.width(); ++x) {
            out.set(x, y, source.at(x / factor, y / factor));
        }
    }
    return out;
}

} // namespace dsoc::inspect
