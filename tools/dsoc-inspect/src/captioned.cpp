#include "dsoc/inspect/captioned.hpp"

#include "dsoc/inspect/caption.hpp"
#include "dsoc/inspect/plan_legend.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace dsoc::inspect {

namespace {

std::string tick_and_time(const RunInfo& run, std::uint64_t tick) {
    std::ostringstream s;
    s << "tick " << tick;
    if (run.tick_rate > 0) {
        s << " (" << std::fixed << std::setprecision(1) << static_cast<double>(tick) / run.tick_rate
          << " s)";
    }
    return s.str();
}

/// The run, then how the plan is drawn.
std::string plan_note(const RunInfo& run, const PlanStyle& style) {
    std::ostringstream s;
    s << run.note << "; seen from above, north up, " << style.units_per_pixel
      << " world units per pixel";
    if (!std::isnan(style.cut_above)) {
        s << "; occluders whose bottom is above z " << std::lround(style.cut_above) << " left out";
    }
    return s.str();
}

} // namespace

std::string headline(const RunInfo& run, const ClientView& view) {
    return run.map + " | client " + std::to_string(view.client) + " | " +
           tick_and_time(run, view.tick) + " | policy " + run.policy;
}

Image captioned_plan(const Image& plan, const RunInfo& run, const ClientView& view,
                     const PlanStyle& style) {
    const Image titled = with_title(plan, {headline(run, view), plan_note(run, style)});
    return with_legend(titled, plan_legend(view, {run.from_trace, true}),
                       ScaleBar{style.units_per_pixel});
}

Image labeled_frame(Image frame, const RunInfo& run, const ClientView& view) {
    draw_label(frame, 2, 2, tick_and_time(run, view.tick));
    return frame;
}

Image captioned_frames(const Image& frames, const RunInfo& run, const ClientView& first,
                       const ClientView& last, const PlanStyle& style) {
    std::string head = run.map + " | client " + std::to_string(first.client) + " | " +
                       tick_and_time(run, first.tick);
    if (last.tick != first.tick) {
        head += " to " + tick_and_time(run, last.tick);
    }
    head += " | policy " + run.policy;
    const Image titled = with_title(frames, {head, plan_note(run, style)});
    return with_legend(titled, plan_legend(first, {run.from_trace, false}),
                       ScaleBar{style.units_per_pixel});
}

Image captioned_depth(const Image& depth, const RunInfo& run, const ClientView& view,
                      const std::string& what, const DepthStyle& style) {
    const Image titled =
        with_title(depth, {what + " | " + headline(run, view),
                           "texel maps, not camera views: -x, +y and -z appear mirrored"});
    return with_legend(titled, depth_legend(style));
}

} // namespace dsoc::inspect
