#pragma once
// An 8-bit RGB raster for the inspector's pictures, with the few drawing primitives
// they need (filled rectangles, lines, convex polygons, blits). Pixel (0, 0) is the
// top-left corner; x grows to the right, y downwards. Every drawing call clips to the
// image, so callers may pass coordinates outside it.

#include <glm/vec2.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace dsoc::inspect {

struct Rgb {
    std::uint8_t r = 0;
    std::uint8_t g = 0;
    std::uint8_t b = 0;
    bool operator==(const Rgb&) const = default;
};

class Image {
public:
    /// Largest width or height accepted. [Units: pixels]
    static constexpr int kMaxSide = 16384;

    Image() = default;
    /// A `width` x `height` image filled with `fill`. Sides outside 1..kMaxSide throw
    /// std::invalid_argument naming the size.
    Image(int width, int height, Rgb fill = {});

    [[nodiscard]] int width() const { return width_; }
    [[nodiscard]] int height() const { return height_; }
    [[nodiscard]] bool empty() const { return pixels_.empty(); }
    [[nodiscard]] bool contains(int x, int y) const {
        return x >= 0 && y >= 0 && x < width_ && y < height_;
    }
    /// The pixel at (x, y); requires contains(x, y).
    [[nodiscard]] Rgb at(int x, int y) const {
        return pixels_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                       static_cast<std::size_t>(x)];
    }
    /// Row-major pixels, width() * height() of them.
    [[nodiscard]] const std::vector<Rgb>& pixels() const { return pixels_; }

    /// Sets one pixel; ignored outside the image.
    void set(int x, int y, Rgb c);
    /// Fills the rectangle with corners (x0, y0) and (x1, y1), both inclusive, in any order.
    void fill_rect(int x0, int y0, int x1, int y1, Rgb c);
    /// The outline of that rectangle, one pixel wide.
    void draw_rect(int x0, int y0, int x1, int y1, Rgb c);
    /// A one-pixel line from (x0, y0) to (x1, y1), both ends included (Bresenham).
    void draw_line(int x0, int y0, int x1, int y1, Rgb c);
    /// Fills every pixel whose centre lies inside (or on) the convex polygon `points`
    /// (pixel coordinates, either winding). Fewer than 3 points fill nothing.
    void fill_convex(std::span<const glm::vec2> points, Rgb c);
    /// Copies `source` with its top-left corner at (x, y), clipped.
    void blit(const Image& source, int x, int y);
    /// The `width` x `height` window of `source` whose top-left corner is (x, y); parts
    /// outside `source` are `fill`. Sides must be 1..kMaxSide.
    [[nodiscard]] static Image cropped(const Image& source, int x, int y, int width, int height,
                                       Rgb fill = {});
    /// `images` (all the same size) in a grid of `columns`, row by row, `gap` pixels
    /// of `fill` around and between them. Needs at least one image and columns >= 1.
    [[nodiscard]] static Image grid(const std::vector<Image>& images, int columns, int gap,
                                    Rgb fill = {});
    /// `source` scaled by an integer factor (nearest neighbour); factor >= 1.
    [[nodiscard]] static Image scaled(const Image& source, int factor);

private:
    int width_ = 0;
    int height_ = 0;
    std::vector<Rgb> pixels_;
};

} // namespace dsoc::inspect
