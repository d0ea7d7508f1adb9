#include "dsoc/inspect/plan_legend.hpp"

#include <string>

namespace dsoc::inspect {

namespace {

const char* label_of(EntityState s, bool from_trace) {
    switch (s) {
    case EntityState::replicated_visible:
        return "sent: not proven hidden from the eye";
    case EntityState::replicated_lookahead:
        return from_trace ? "sent: hidden from the eye (lookahead or held)"
                          : "sent: hidden from the eye, not from all reach";
    case EntityState::replicated_held:
        return "sent: hidden, held until its next test";
    case EntityState::replicated_rule:
        return "sent by a rule: a teammate";
    case EntityState::replicated_heard:
        return "sent heard only: coarse, no angles";
    case EntityState::hidden_tbv:
        return "not sent: hidden, inside its TBV";
    case EntityState::hidden_expired:
        return "not sent: hidden, tested every tick";
    case EntityState::not_replicated:
        return "not sent";
    }
    return "";
}

} // namespace

std::vector<LegendEntry> plan_legend(const ClientView& view, const PlanLegendOptions& options,
                                     const PlanPalette& palette) {
    using Swatch = LegendEntry::Swatch;
    const Rgb low{palette.low_shade, palette.low_shade, palette.low_shade};
    const Rgb high{palette.high_shade, palette.high_shade, palette.high_shade};
    std::vector<LegendEntry> out = {
        {Swatch::gradient, low, high, "occluder: low top to high top"},
        {Swatch::fill, palette.viewer, {}, "viewer (box) and its eye (cross)"},
    };
    if (!options.from_trace) {
        out.push_back({Swatch::outline, palette.eye_region, {}, "eyes reachable within latency"});
    }
    static constexpr EntityState kLive[] = {
        EntityState::replicated_visible, EntityState::replicated_lookahead,
        EntityState::replicated_held,    EntityState::replicated_rule,
        EntityState::replicated_heard,   EntityState::hidden_tbv,
        EntityState::hidden_expired};
    static constexpr EntityState kTrace[] = {
        EntityState::replicated_visible, EntityState::replicated_lookahead,
        EntityState::replicated_rule, EntityState::replicated_heard, EntityState::not_replicated};
    const auto add = [&](EntityState s) {
        std::string label = label_of(s, options.from_trace);
        if (options.counts) {
            label += " (" + std::to_string(view.count(s)) + ")";
        }
        out.push_back({Swatch::fill, palette.of(s), {}, std::move(label)});
    };
    if (options.from_trace) {
        for (const EntityState s : kTrace) {
            add(s);
        }
    } else {
        for (const EntityState s : kLive) {
            add(s);
        }
        out.push_back({Swatch::outline, palette.tbv_outline, {}, "TBV: where a hidden one may be"});
    }
    return out;
}

} // namespace dsoc::inspect
