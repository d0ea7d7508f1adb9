#pragma once
// The z-pyramid layout both occlusion buffers share (OcclusionBuffer around one eye,
// RegionOcclusionBuffer around a region): six cube faces, each of resolution^2
// level-0 depth texels with its max-pyramid (Greene, Kass, Miller: "Hierarchical
// Z-Buffer Visibility", SIGGRAPH 1993). Level k is (resolution >> k) texels square,
// row-major, and each texel holds the max of the four texels below it. What a depth
// means, and how occluders are written, is each buffer's own.

#include <cstddef>
#include <string>
#include <vector>

namespace dsoc::visibility {

/// Face f (0..5: +x, -x, +y, -y, +z, -z) looks along sign * axis; right and up are
/// the other two axes, increasing with the world coordinate.
struct CubeFace {
    int axis, right, up;
    float sign;
};
inline constexpr CubeFace kCubeFaces[6] = {{0, 1, 2, 1.0f},  {0, 1, 2, -1.0f}, {1, 0, 2, 1.0f},
                                           {1, 0, 2, -1.0f}, {2, 0, 1, 1.0f},  {2, 0, 1, -1.0f}};

/// Inclusive rectangle of level-0 texels.
struct TexelRect {
    int x0, y0, x1, y1;
};

class CubeZPyramid {
public:
    /// `resolution` texels along a face's side (a power of two); every texel +inf.
    explicit CubeZPyramid(int resolution = 1);

    /// The problems with a buffer's pyramid settings (face_resolution a power of two
    /// in 8..1024, max_occluders >= 0, max_occluder_distance > 0), added to `problems`.
    static void check_settings(int face_resolution, int max_occluders, float max_occluder_distance,
                               std::vector<std::string>& problems);

    [[nodiscard]] int resolution() const { return resolution_; }
    [[nodiscard]] int levels() const { return levels_; }
    [[nodiscard]] float* level_data(int face, int level) {
        return depth_.data() + static_cast<std::size_t>(face) * face_stride_ +
               level_offset_[static_cast<std::size_t>(level)];
    }
    [[nodiscard]] const float* level_data(int face, int level) const {
        return depth_.data() + static_cast<std::size_t>(face) * face_stride_ +
               level_offset_[static_cast<std::size_t>(level)];
    }
    /// Texel (x, y) of `face` at `level` (0 = finest).
    [[nodiscard]] float depth(int face, int level, int x, int y) const {
        const int size = resolution_ >> level;
        return level_data(face, level)[static_cast<std::size_t>(y) * size + x];
    }

    /// Level 0 of every face back to +inf (nothing known), before a build's writes.
    void clear_level0();
    /// Levels 1.. of every face from level 0, after a build's writes.
    void build_levels();
    /// True when every level-0 texel of `r` holds a depth below `z` (or equal to it,
    /// with `or_equal`): a linear scan, for builds, before the levels exist.
    [[nodiscard]] bool level0_hides(int face, const TexelRect& r, float z, bool or_equal) const;
    /// True when every level-0 texel of `r` holds a depth nearer than `z`, through the
    /// levels: starts where the rectangle spans at most 2x2 texels and descends only
    /// where a coarse texel cannot decide (Greene's `Isoccluded`).
    [[nodiscard]] bool rect_occluded(int face, const TexelRect& r, float z) const;

private:
    [[nodiscard]] bool texel_occluded(int face, int level, int tx, int ty, const TexelRect& r,
                                      float z) const;

    int resolution_ = 0;
    int levels_ = 0;
    std::vector<std::size_t> level_offset_;
    std::size_t face_stride_ = 0;
    std::vector<float> depth_;
};

} // namespace dsoc::visibility
