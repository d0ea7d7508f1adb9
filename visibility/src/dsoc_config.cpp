#include "dsoc/visibility/dsoc_config.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <type_traits>

namespace dsoc::visibility {

const char* to_string(TbvStrategy s) noexcept {
    switch (s) {
    case TbvStrategy::explicit_duration:
        return "explicit";
    case TbvStrategy::adaptive:
        return "adaptive";
    case TbvStrategy::fuzzy:
        return "fuzzy";
    }
    return "unknown";
}

bool parse_tbv_strategy(const std::string& name, TbvStrategy& out) noexcept {
    for (const auto s :
         {TbvStrategy::explicit_duration, TbvStrategy::adaptive, TbvStrategy::fuzzy}) {
        if (name == to_string(s)) {
            out = s;
            return true;
        }
    }
    return false;
}

int adaptive_duration(float speed_per_tick, float max_speed_per_tick, const DSOCConfig& config) {
    if (speed_per_tick < config.velocity_threshold || max_speed_per_tick <= 0.0f) {
        return config.max_adaptive_duration;
    }
    const float slowness = std::clamp(1.0f - speed_per_tick / max_speed_per_tick, 0.0f, 1.0f);
    const float span =
        static_cast<float>(config.max_adaptive_duration - config.min_adaptive_duration);
    return config.min_adaptive_duration + static_cast<int>(std::lround(span * slowness));
}

std::vector<std::string> validate(const DSOCConfig& c) {
    std::vector<std::string> p;
    const auto check = [&](bool ok, const char* field, const char* why) {
        if (!ok) {
            p.push_back(std::string(field) + ": " + why);
        }
    };
    check(c.tick_rate >= 1 && c.tick_rate <= 240, "tick_rate", "must be 1..240 Hz");
    check(c.default_tbv_duration >= 1, "default_tbv_duration", "must be >= 1 tick");
    check(std::isfinite(c.tbv_expansion_factor) && c.tbv_expansion_factor >= 1.0f,
          "tbv_expansion_factor", "must be a finite number >= 1.0");
    check(c.max_tbvs_per_object >= 1, "max_tbvs_per_object", "must be >= 1");
    check(c.max_tbvs_per_client >= 1, "max_tbvs_per_client", "must be >= 1");
    check(std::isfinite(c.velocity_threshold) && c.velocity_threshold >= 0.0f, "velocity_threshold",
          "must be a finite number >= 0");
    check(c.min_adaptive_duration >= 1, "min_adaptive_duration", "must be >= 1 tick");
    check(c.max_adaptive_duration >= c.min_adaptive_duration, "max_adaptive_duration",
          "must be >= min_adaptive_duration");
    check(std::isfinite(c.fuzzy_confidence) && c.fuzzy_confidence >= 0.5f &&
              c.fuzzy_confidence <= 0.999f,
          "fuzzy_confidence", "must be in [0.5, 0.999]");
    check(std::isfinite(c.tbv_merge_distance) && c.tbv_merge_distance >= 0.0f, "tbv_merge_distance",
          "must be a finite number >= 0");
    check(std::isfinite(c.region_reuse_margin) && c.region_reuse_margin >= 0.0f,
          "region_reuse_margin", "must be a finite number >= 0");
    check(std::isfinite(c.entity_cluster_size) &&
              (c.entity_cluster_size == 0.0f || c.entity_cluster_size >= 16.0f),
          "entity_cluster_size", "must be 0 (off) or a finite number >= 16");
    check(c.full_test_interval >= 1 && c.full_test_interval <= 64, "full_test_interval",
          "must be 1..64 ticks");
    check(std::isfinite(c.lod_near_distance) && c.lod_near_distance > 0.0f, "lod_near_distance",
          "must be a finite number > 0");
    check(std::isfinite(c.lod_far_distance) && c.lod_far_distance >= c.lod_near_distance,
          "lod_far_distance", "must be >= lod_near_distance");
    return p;
}

namespace {

template <typename T>
bool parse_number(std::string_view text, T& out) {
    T parsed{};
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, parsed);
    if (ec != std::errc() || ptr != end) {
        return false; // `out` untouched
    }
    out = parsed;
    return true;
}

bool set_field_flag(bool& out, std::string_view text) {
    if (text == "true" || text == "1") {
        out = true;
        return true;
    }
    if (text == "false" || text == "0") {
        out = false;
        return true;
    }
    return false;
}

} // namespace

std::string set_field(DSOCConfig& c, std::string_view key, std::string_view value) {
    std::string why = "unknown DSOCConfig field '" + std::string(key) + "'";
    visit_fields(c, [&](std::string_view name, auto& member) {
        if (name != key) {
            return;
        }
        using T = std::remove_reference_t<decltype(member)>;
        bool ok = false;
        const char* expected = "";
        if constexpr (std::is_same_v<T, TbvStrategy>) {
            ok = parse_tbv_strategy(std::string(value), member);
            expected = " (explicit, adaptive or fuzzy)";
        } else if constexpr (std::is_same_v<T, bool>) {
            ok = set_field_flag(member, value);
            expected = " (true or false)";
        } else {
            ok = parse_number(value, member);
        }
        why = ok ? "" : "bad value '" + std::string(value) + "' for " + std::string(key) + expected;
    });
    return why;
}

} // namespace dsoc::visibility
