#pragma once
// Greene's hierarchical z-pyramid query, shared by the point and the region
// occlusion buffers (internal header).
//
// A pyramid has `levels` levels over a `resolution` x `resolution` base; level k is
// (resolution >> k) texels square, row-major, and each texel holds the max depth of
// the four texels below it. `level_texels(k)` returns level k's first texel.

namespace dsoc::visibility::detail {

/// Inclusive rectangle of level-0 texels.
struct TexelRect {
    int x0, y0, x1, y1;
};

/// True when every level-0 texel of `r` under texel (tx, ty) of `level` holds a depth
/// nearer than `z` (descending only where the coarse texel cannot decide).
template <class LevelTexels>
bool texel_occluded(const LevelTexels& level_texels, int resolution, int level, int tx, int ty,
                    const TexelRect& r, float z) {
    const int size = resolution >> level;
    if (level_texels(level)[ty * size + tx] < z) {
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
            if (!texel_occluded(level_texels, resolution, level - 1, cx, cy, r, z)) {
                return false;
            }
        }
    }
    return true;
}

/// True when every level-0 texel of `r` holds a depth nearer than `z`. Starts at the
/// level where the rectangle spans at most 2x2 texels (Greene's `Isoccluded`).
template <class LevelTexels>
bool rect_occluded(const LevelTexels& level_texels, int resolution, int levels, const TexelRect& r,
                   float z) {
    int level = 0;
    while (level + 1 < levels &&
           (((r.x1 >> level) - (r.x0 >> level)) > 1 || ((r.y1 >> level) - (r.y0 >> level)) > 1)) {
        ++level;
    }
    for (int ty = r.y0 >> level; ty <= (r.y1 >> level); ++ty) {
        for (int tx = r.x0 >> level; tx <= (r.x1 >> level); ++tx) {
            if (!texel_occluded(level_texels, resolution, level, tx, ty, r, z)) {
                return false;
            }
        }
    }
    return true;
}

} // namespace dsoc::visibility::detail
