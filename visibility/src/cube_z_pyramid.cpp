#include "dsoc/visibility/cube_z_pyramid.hpp"

#include <algorithm>
#include <limits>

namespace dsoc::visibility {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

bool is_power_of_two(int v) {
    return v > 0 && (v & (v - 1)) == 0;
}

} // namespace

CubeZPyramid::CubeZPyramid(int resolution) : resolution_(resolution) {
    std::size_t offset = 0;
    for (int size = resolution_; size >= 1; size /= 2) {
        level_offset_.push_back(offset);
        offset += static_cast<std::size_t>(size) * static_cast<std::size_t>(size);
        ++levels_;
    }
    face_stride_ = offset;
    depth_.assign(6 * face_stride_, kInf);
}

void CubeZPyramid::check_settings(int face_resolution, int max_occluders,
                                  float max_occluder_distance, std::vector<std::string>& problems) {
    if (!is_power_of_two(face_resolution) || face_resolution < 8 || face_resolution > 1024) {
        problems.push_back("face_resolution must be a power of two in 8..1024, is " +
                           std::to_string(face_resolution));
    }
    if (max_occluders < 0) {
        problems.push_back("max_occluders must be >= 0, is " + std::to_string(max_occluders));
    }
    if (!(max_occluder_distance > 0.0f)) {
        problems.push_back("max_occluder_distance must be > 0");
    }
}

void CubeZPyramid::clear_level0() {
    for (int f = 0; f < 6; ++f) {
        float* level0 = level_data(f, 0);
        std::fill(level0, level0 + static_cast<std::size_t>(resolution_) * resolution_, kInf);
    }
}

void CubeZPyramid::build_levels() {
    for (int f = 0; f < 6; ++f) {
        for (int level = 1; level < levels_; ++level) {
            const int size = resolution_ >> level;
            const float* src = level_data(f, level - 1);
            float* dst = level_data(f, level);
            const int src_size = size * 2;
            for (int y = 0; y < size; ++y) {
                const float* r0 = src + static_cast<std::size_t>(2 * y) * src_size;
                const float* r1 = r0 + src_size;
                for (int x = 0; x < size; ++x) {
                    dst[static_cast<std::size_t>(y) * size + x] = std::max(
                        std::max(r0[2 * x], r0[2 * x + 1]), std::max(r1[2 * x], r1[2 * x + 1]));
                }
            }
        }
    }
}

bool CubeZPyramid::level0_hides(int face, const TexelRect& r, float z, bool or_equal) const {
    const float* level0 = level_data(face, 0);
    for (int y = r.y0; y <= r.y1; ++y) {
        const float* row = level0 + static_cast<std::size_t>(y) * resolution_;
        for (int x = r.x0; x <= r.x1; ++x) {
            if (!(z > row[x] || (or_equal && z == row[x]))) {
                return false;
            }
        }
    }
    return true;
}

bool CubeZPyramid::texel_occluded(int face, int level, int tx, int ty, const TexelRect& r,
                                  float z) const {
    const int size = resolution_ >> level;
    if (level_data(face, level)[ty * size + tx] < z) {
        return true;
    }
    if (level == 0) {
        return false;
    }
    const int shift = level - 1; // children of this texel that overlap the rectangle
    for (int cy = 2 * ty; cy <= 2 * ty + 1; ++cy) {
        if ((cy << shift) > r.y1 || (((cy + 1) << shift) - 1) < r.y0) {
            continue;
        }
        for (int cx = 2 * tx; cx <= 2 * tx + 1; ++cx) {
            if ((cx << shift) > r.x1 || (((cx + 1) << shift) - 1) < r.x0) {
                continue;
            }
            if (!texel_occluded(face, level - 1, cx, cy, r, z)) {
                return false;
            }
        }
    }
    return true;
}

bool CubeZPyramid::rect_occluded(int face, const TexelRect& r, float z) const {
    int level = 0;
    while (level + 1 < levels_ &&
           (((r.x1 >> level) - (r.x0 >> level)) > 1 || ((r.y1 >> level) - (r.y0 >> level)) > 1)) {
        ++level;
    }
    for (int ty = r.y0 >> level; ty <= (r.y1 >> level); ++ty) {
        for (int tx = r.x0 >> level; tx <= (r.x1 >> level); ++tx) {
            if (!texel_occluded(face, level, tx, ty, r, z)) {
                return false;
            }
        }
    }
    return true;
}

} // namespace dsoc::visibility
