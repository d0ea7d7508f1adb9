#pragma once
// The legend of a plan (plan_view.hpp): what each colour of kPalette means, as entries
// for with_legend (caption.hpp). Live views list every state a live run can show,
// always in the same order (so that frames of a sequence get the same layout); trace
// views list the five a trace can show (a trace records no TBVs or eye regions).

#include "dsoc/inspect/caption.hpp"
#include "dsoc/inspect/client_view.hpp"
#include "dsoc/inspect/plan_view.hpp"

#include <vector>

namespace dsoc::inspect {

struct PlanLegendOptions {
    /// The view came from a replication trace (not a live run).
    bool from_trace = false;
    /// Each state's label ends with its count in the view, " (N)".
    bool counts = true;
};

/// Occluder shading, the viewer, the eye region (live), then the entity states, sent
/// ones first, and the TBV outline (live).
[[nodiscard]] std::vector<LegendEntry> plan_legend(const ClientView& view,
                                                   const PlanLegendOptions& options = {},
                                                   const PlanPalette& palette = kPalette);

} // namespace dsoc::inspect
