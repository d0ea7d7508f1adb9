#pragma once
// A z-pyramid's six cube faces as images: one grey image per face at a chosen
// pyramid level, near occluders bright, far ones dark, and texels where nothing is
// known (depth +inf: nothing proven hidden through them) in kUnknownDepth.
//
// Face order and orientation follow the buffers (occlusion_buffer.hpp,
// region_occlusion_buffer.hpp): 0..5 = +x, -x, +y, -y, +z, -z; texel x along the
// face's first lateral axis (y for the x faces, else x) drawn left to right, texel y
// along the second (z for the x and y faces, else y) drawn bottom to top. These are
// texel maps, not camera views: the -x, +y and -z faces appear mirrored.

#include "dsoc/inspect/caption.hpp"
#include "dsoc/inspect/image.hpp"
#include "dsoc/visibility/region_occlusion_buffer.hpp"
#include "dsoc/visibility/seeds/occlusion_buffer.hpp"

#include <array>
#include <functional>
#include <vector>

namespace dsoc::inspect {

inline constexpr Rgb kUnknownDepth{20, 30, 90};
inline constexpr const char* kFaceNames[6] = {"px", "nx", "py", "ny", "pz", "nz"};
/// The faces as captions name them: axis, then the map direction (+y north, +z up).
inline constexpr const char* kFaceLabels[6] = {"+x east",  "-x west", "+y north",
                                               "-y south", "+z up",   "-z down"};

/// Read access to either z-pyramid (both use the same face layout).
struct DepthPyramid {
    int resolution = 0; ///< level-0 texels per face side
    int levels = 0;
    /// depth(face, level, x, y); x, y < resolution >> level. [Units: world units]
    std::function<float(int, int, int, int)> depth;

    /// The buffer must outlive the returned value.
    [[nodiscard]] static DepthPyramid of(const visibility::OcclusionBuffer& buffer);
    [[nodiscard]] static DepthPyramid of(const visibility::RegionOcclusionBuffer& buffer);
};

struct DepthStyle {
    /// Depth drawn black; nearer is brighter (linear), depth <= 0 is white.
    /// [Units: world units] [Limit: > 0]
    float far_depth = 1024.0f;
    /// Each face image is scaled up (nearest texel) to at least this many pixels per
    /// side. [Units: pixels] [Limit: >= 1]
    int face_pixels = 192;
    /// Pixels between faces in the strip. [Units: pixels]
    int gap = 6;
};

/// The grey value of a finite depth under `style` (what a test can expect).
[[nodiscard]] Rgb depth_colour(float depth, const DepthStyle& style);

/// Face `face` at `level` (0 = finest). Throws std::invalid_argument when face or
/// level is out of range (naming the valid range).
[[nodiscard]] Image render_depth_face(const DepthPyramid& pyramid, int face, int level,
                                      const DepthStyle& style = {});

/// The six faces side by side, +x first, separated by `style.gap` background pixels.
[[nodiscard]] Image render_depth_strip(const DepthPyramid& pyramid, int level,
                                       const DepthStyle& style = {});

/// render_depth_strip with kFaceLabels centred above the faces.
[[nodiscard]] Image render_labeled_depth_strip(const DepthPyramid& pyramid, int level,
                                               const DepthStyle& style = {});

/// What the depth images' colours mean: white (depth 0) to black (style.far_depth, in
/// world units), and kUnknownDepth.
[[nodiscard]] std::vector<LegendEntry> depth_legend(const DepthStyle& style = {});

} // namespace dsoc::inspect
