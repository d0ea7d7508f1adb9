#pragma once
// The inspector's pictures as they are written: each renderer's image with a title
// (map, client, tick, policy and the run), a legend of its colours and, for plans, a
// scale bar in world units (caption.hpp). dsoc-inspect writes only these.

#include "dsoc/inspect/client_view.hpp"
#include "dsoc/inspect/depth_view.hpp"
#include "dsoc/inspect/image.hpp"
#include "dsoc/inspect/plan_view.hpp"

#include <string>

namespace dsoc::inspect {

/// The run the pictures come from, as titles name it.
struct RunInfo {
    std::string map;
    std::string policy;
    int tick_rate = 30; ///< [Units: Hz] 0: unknown (no time shown)
    bool from_trace = false;
    /// Where the views come from, e.g. "live: 576 bots, 30 Hz, 150 ms latency allowance".
    std::string note;
};

/// "oa_dm4 | client 1 | tick 150 (5.0 s) | policy dsoc".
[[nodiscard]] std::string headline(const RunInfo& run, const ClientView& view);

/// A plan (render_plan of `view` at `style`) with its title, its legend with the count
/// of each state, and a scale bar.
[[nodiscard]] Image captioned_plan(const Image& plan, const RunInfo& run, const ClientView& view,
                                   const PlanStyle& style);

/// A frame of a sequence with "tick T (S s)" drawn inside its top-left corner: frames of
/// one run keep one size, so they can be tiled or animated.
[[nodiscard]] Image labeled_frame(Image frame, const RunInfo& run, const ClientView& view);

/// Labelled frames (one, or a sheet of them) with a title naming the ticks `first` ..
/// `last`, a legend without counts (the same for every frame) and a scale bar.
[[nodiscard]] Image captioned_frames(const Image& frames, const RunInfo& run,
                                     const ClientView& first, const ClientView& last,
                                     const PlanStyle& style);

/// A depth image (the labelled strip or one face) titled `what` (e.g. "z-pyramid from
/// the present eye, level 2") and the run, with the depth legend.
[[nodiscard]] Image captioned_depth(const Image& depth, const RunInfo& run, const ClientView& view,
                                    const std::string& what, const DepthStyle& style);

} // namespace dsoc::inspect
