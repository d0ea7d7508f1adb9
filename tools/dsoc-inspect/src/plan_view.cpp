#include "dsoc/inspect/plan_view.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace dsoc::inspect {

namespace {

float cross(glm::vec2 o, glm::vec2 a, glm::vec2 b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

/// Andrew's monotone chain: counter-clockwise hull without collinear points.
std::vector<glm::vec2> convex_hull(std::vector<glm::vec2> p) {
    std::sort(p.begin(), p.end(),
              [](glm::vec2 a, glm::vec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    p.erase(std::unique(p.begin(), p.end()), p.end());
    if (p.size() < 3) {
        return p;
    }
    std::vector<glm::vec2> hull(2 * p.size());
    std::size_t k = 0;
    for (const glm::vec2 q : p) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], q) <= 0.0f) {
            --k;
        }
        hull[k++] = q;
    }
    for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], p[i]) <= 0.0f) {
            --k;
        }
        hull[k++] = p[i];
    }
    hull.resize(k - 1);
    return hull;
}

Rgb darker(Rgb c) {
    return {static_cast<std::uint8_t>(c.r * 3 / 4), static_cast<std::uint8_t>(c.g * 3 / 4),
            static_cast<std::uint8_t>(c.b * 3 / 4)};
}

} // namespace

Rgb PlanPalette::of(EntityState s) const {
    switch (s) {
    case EntityState::replicated_visible:
        return replicated_visible;
    case EntityState::replicated_lookahead:
        return replicated_lookahead;
    case EntityState::replicated_held:
        return replicated_held;
    case EntityState::replicated_rule:
        return replicated_rule;
    case EntityState::replicated_heard:
        return replicated_heard;
    case EntityState::hidden_tbv:
        return hidden_tbv;
    case EntityState::hidden_expired:
        return hidden_expired;
    case EntityState::not_replicated:
        return not_replicated;
    }
    return not_replicated;
}

std::vector<Footprint> footprints(const std::vector<visibility::ConvexPolyhedron>& occluders) {
    std::vector<Footprint> out;
    out.reserve(occluders.size());
    std::vector<glm::vec2> points;
    for (const auto& o : occluders) {
        if (o.is_empty()) {
            continue;
        }
        points.clear();
        for (const glm::vec3& v : o.vertices()) {
            points.emplace_back(v.x, v.y);
        }
        Footprint f;
        f.hull = convex_hull(points);
        f.bottom = o.bounds().min.z;
        f.top = o.bounds().max.z;
        if (f.hull.size() >= 3) {
            out.push_back(std::move(f));
        }
    }
    return out;
}

PlanFrame::PlanFrame(const visibility::Aabb& bounds, const PlanStyle& style)
    : bounds_(bounds), scale_(1.0f / style.units_per_pixel), margin_(std::max(style.margin, 0)) {
    if (bounds.is_empty()) {
        throw std::invalid_argument("plan: the world bounds are empty (a map without brushes?)");
    }
    if (!(style.units_per_pixel > 0.0f) || !std::isfinite(style.units_per_pixel)) {
        throw std::invalid_argument("plan: units per pixel must be a finite number > 0, got " +
                                    std::to_string(style.units_per_pixel));
    }
    const double w = std::ceil(static_cast<double>(bounds.max.x - bounds.min.x) * scale_);
    const double h = std::ceil(static_cast<double>(bounds.max.y - bounds.min.y) * scale_);
    if (w + 2.0 * margin_ > Image::kMaxSide || h + 2.0 * margin_ > Image::kMaxSide) {
        throw std::invalid_argument("plan: " + std::to_string(static_cast<long long>(w)) + " x " +
                                    std::to_string(static_cast<long long>(h)) + " pixels exceeds " +
                                    std::to_string(Image::kMaxSide) +
                                    " per side; use a larger units per pixel");
    }
    width_ = std::max(1, static_cast<int>(w) + 2 * margin_);
    height_ = std::max(1, static_cast<int>(h) + 2 * margin_);
}

glm::vec2 PlanFrame::to_pixel(float x, float y) const {
    return {static_cast<float>(margin_) + (x - bounds_.min.x) * scale_,
            static_cast<float>(margin_) + (bounds_.max.y - y) * scale_};
}

int PlanFrame::pixel_x(float x) const {
    return static_cast<int>(std::floor(to_pixel(x, 0.0f).x));
}

int PlanFrame::pixel_y(float y) const {
    return static_cast<int>(std::floor(to_pixel(0.0f, y).y));
}

Image render_plan(const std::vector<Footprint>& occluders, const visibility::Aabb& bounds,
                  const ClientView& view, const PlanStyle& style, const PlanPalette& palette) {
    const PlanFrame frame(bounds, style);
    Image image(frame.width(), frame.height(), palette.background);

    // Occluders: lower tops first, so what is seen from above ends on top.
    std::vector<const Footprint*> order;
    order.reserve(occluders.size());
    for (const Footprint& f : occluders) {
        if (std::isnan(style.cut_above) || f.bottom <= style.cut_above) {
            order.push_back(&f);
        }
    }
    std::stable_sort(order.begin(), order.end(),
                     [](const Footprint* a, const Footprint* b) { return a->top < b->top; });
    const float z_span = std::max(bounds.max.z - bounds.min.z, 1.0f);
    std::vector<glm::vec2> pixels;
    for (const Footprint* f : order) {
        const float t = std::clamp((f->top - bounds.min.z) / z_span, 0.0f, 1.0f);
        const auto shade = static_cast<std::uint8_t>(
            std::lround(palette.low_shade + t * (palette.high_shade - palette.low_shade)));
        pixels.clear();
        for (const glm::vec2 p : f->hull) {
            pixels.push_back(frame.to_pixel(p.x, p.y));
        }
        image.fill_convex(pixels, Rgb{shade, shade, shade});
        // A darker rim keeps neighbouring brushes of equal height apart.
        const Rgb rim = darker(Rgb{shade, shade, shade});
        for (std::size_t i = 0; i < pixels.size(); ++i) {
            const glm::vec2 a = pixels[i];
            const glm::vec2 b = pixels[(i + 1) % pixels.size()];
            image.draw_line(static_cast<int>(a.x), static_cast<int>(a.y), static_cast<int>(b.x),
                            static_cast<int>(b.y), rim);
        }
    }

    const auto outline = [&](const visibility::Aabb& box, Rgb c) {
        image.draw_rect(frame.pixel_x(box.min.x), frame.pixel_y(box.max.y),
                        frame.pixel_x(box.max.x), frame.pixel_y(box.min.y), c);
    };
    const auto fill_box = [&](const visibility::Aabb& box, Rgb c) {
        const glm::vec3 centre = box.center();
        int x0 = frame.pixel_x(box.min.x);
        int x1 = frame.pixel_x(box.max.x);
        int y0 = frame.pixel_y(box.max.y);
        int y1 = frame.pixel_y(box.min.y);
        const int min_side = std::max(style.min_entity_pixels, 1);
        if (x1 - x0 + 1 < min_side) {
            x0 = frame.pixel_x(centre.x) - (min_side - 1) / 2;
            x1 = x0 + min_side - 1;
        }
        if (y1 - y0 + 1 < min_side) {
            y0 = frame.pixel_y(centre.y) - (min_side - 1) / 2;
            y1 = y0 + min_side - 1;
        }
        image.fill_rect(x0, y0, x1, y1, c);
    };

    if (!view.eye_region.is_empty()) {
        outline(view.eye_region, palette.eye_region);
    }
    for (const EntityView& e : view.entities) {
        if (e.state == EntityState::hidden_tbv && !e.tbv.is_empty()) {
            outline(e.tbv, palette.tbv_outline);
        }
    }
    // Hidden first, then replicated: what the client receives is never covered.
    static constexpr EntityState kDrawOrder[] = {
        EntityState::not_replicated,       EntityState::hidden_expired,
        EntityState::hidden_tbv,           EntityState::replicated_heard,
        EntityState::replicated_held,      EntityState::replicated_rule,
        EntityState::replicated_lookahead, EntityState::replicated_visible};
    for (const EntityState s : kDrawOrder) {
        for (const EntityView& e : view.entities) {
            if (e.state == s) {
                fill_box(e.box, palette.of(s));
            }
        }
    }
    if (view.viewer_entity) {
        fill_box(view.viewer_box, palette.viewer);
    }
    // The eye: a cross five pixels wide either way.
    const int ex = frame.pixel_x(view.eye.x);
    const int ey = frame.pixel_y(view.eye.y);
    image.draw_line(ex - 5, ey, ex + 5, ey, palette.viewer);
    image.draw_line(ex, ey - 5, ex, ey + 5, palette.viewer);
    return image;
}

} // namespace dsoc::inspect
