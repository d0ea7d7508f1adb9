#pragma once
// Settings of the DSOC interest manager, with defaults, units and limits.

#include <cstdint>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace dsoc::visibility {

/// How a newly hidden entity's TBV duration and box are chosen.
enum class TbvStrategy : std::uint8_t {
    explicit_duration, ///< fixed duration, box from the motion limits (conservative)
    adaptive,          ///< duration from the entity's speed between min and max (conservative)
    fuzzy,             ///< box predicted from movement history (NOT conservative; evaluation only)
};

[[nodiscard]] const char* to_string(TbvStrategy s) noexcept;
/// Parses "explicit", "adaptive" or "fuzzy"; false on anything else.
[[nodiscard]] bool parse_tbv_strategy(const std::string& name, TbvStrategy& out) noexcept;

struct DSOCConfig {
    /// Simulation rate; converts ticks to seconds. [Units: Hz] [Limit: 1..240]
    int tick_rate = 30;

    // TBV creation (guide: "TBV Creation")
    TbvStrategy strategy = TbvStrategy::adaptive;
    /// Duration of an explicit TBV. [Units: ticks] [Limit: >= 1]
    int default_tbv_duration = 30;
    /// Safety margin on a TBV's growth. [Units: factor] [Limit: >= 1.0]
    float tbv_expansion_factor = 1.2f;
    /// TBVs one entity may hold across all clients; past it a client re-tests that
    /// entity every tick instead (costs CPU, never correctness). Judged on the count at
    /// the start of the tick (deterministic whatever the threads), so one tick may add
    /// up to one TBV per client beyond it. [Limit: >= 1]
    int max_tbvs_per_object = 256;
    /// TBV groups one client may hold; past it the earliest-expiring group is evicted
    /// and its entities become HIDDEN_EXPIRED (re-tested). [Limit: >= 1]
    int max_tbvs_per_client = 4096;

    // Adaptive expiration (guide: "Implicit Expiration")
    /// Below this speed an entity counts as stationary. Per tick, unlike MotionLimits
    /// (per second). [Units: world units / tick] [Limit: >= 0]
    float velocity_threshold = 0.1f;
    /// [Units: ticks] [Limit: 1..max_adaptive_duration]
    int min_adaptive_duration = 4;
    /// [Units: ticks] [Limit: >= min_adaptive_duration]
    int max_adaptive_duration = 30;

    // Fuzzy TBVs
    /// Share of predicted positions a fuzzy TBV keeps. [Limit: 0.5..0.999]
    float fuzzy_confidence = 0.95f;

    // Grouping (guide: "TBV Merging")
    /// TBVs created in the same tick whose centres are closer than this merge into one
    /// group, when the group's box is still hidden. 0 disables. [Units: world units] [Limit: >= 0]
    float tbv_merge_distance = 64.0f;

    // Viewer side (latency safety)
    /// A client's occlusion buffer covers its reachable eye region grown by this, and
    /// is rebuilt only when the reachable region leaves it. [Units: world units] [Limit: >= 0]
    float region_reuse_margin = 16.0f;

    // Network level of detail, from the conservative distance between the client's
    // eye region and the entity (or its TBV).
    /// Closer than this: update every tick at full precision. [Units: world units]
    /// [Limit: >= 0]
    float lod_near_distance = 1024.0f;
    /// Beyond lod_near: every 2nd tick; beyond this: every 4th. [Units: world units]
    /// [Limit: >= lod_near_distance]
    float lod_far_distance = 2048.0f;

    /// Entities whose box centres fall in the same cell of this size (at least 3 of
    /// them) are first tested together, per client: when the union of their boxes is
    /// hidden, so is each of them, with one test instead of one each, and (without a
    /// prepared stage) they share one TBV group made with one test. 0 = off; also off
    /// when the culler says they do not pay (RegionVisibility::pair_shortcuts_pay(): a
    /// baked table first). [Units: world units] [Limit: 0 or >= 16]
    float entity_cluster_size = 512.0f;

    /// true: a hidden entity gets a Temporal Bounding Volume (the box it can reach in
    /// the next ticks, `strategy`) proven hidden and is not tested again until it
    /// expires or turns visible. false (the default): every hidden entity is tested
    /// every tick, which costs less with today's culler on every map measured, for
    /// sets within 0.2% of the pairs (docs/dsoc.md, "When TBVs pay"). Never any when
    /// the culler says they do not pay (RegionVisibility::pair_shortcuts_pay(): a
    /// baked table first). [Units: flag]
    bool tbvs_enabled = false;
    /// false: rebuild every client's culler every tick (no region reuse). [Units: flag]
    bool reuse_buffers = true;
    /// true: entities' current boxes are tested against a culler built every tick for
    /// exactly this tick's reachable region (what they must be hidden from), while TBVs
    /// are proven against the reused, larger buffer region (what they must stay hidden
    /// from while it is reused): tighter sets for one more culler build per client-tick
    /// (with the PVS and shaft stages, a few µs). false: everything against the buffer
    /// region. [Units: flag]
    bool exact_region_tests = true;
    /// Temporal coherence for hidden entities: the culler may remember per (client,
    /// entity) what proved the box hidden (the shaft stage: the occluder) and try it
    /// first next time. Same guarantee; cheaper re-tests. [Units: flag]
    bool blocker_hints = true;
    /// Temporal coherence: an entity visible last tick gets the culler's full test only
    /// every this many ticks (staggered) and its quick test otherwise; 1 = full test
    /// every tick. Both tests are conservative. [Units: ticks] [Limit: 1..64]
    int full_test_interval = 4;

    /// Run ValidateDSOCState after every update() and throw std::logic_error naming
    /// the first broken invariant (the server's and the eval's policies run it before
    /// each tick). On by default in debug builds (NDEBUG not defined); the tests turn it
    /// on. Costs O(clients x entities) per tick.
#ifdef NDEBUG
    bool validate_state = false;
#else
    bool validate_state = true;
#endif
};

/// Guide's implicit expiration: `max_adaptive_duration` below velocity_threshold, else
/// min + (max - min) * (1 - speed / max_speed), clamped. Speeds in world units / tick.
[[nodiscard]] int adaptive_duration(float speed_per_tick, float max_speed_per_tick,
                                    const DSOCConfig& config);

/// Every problem with the settings, each naming the field and why; empty when usable.
[[nodiscard]] std::vector<std::string> validate(const DSOCConfig& config);

/// The one list of DSOCConfig's fields: calls `visit(name, member)` for every field of
/// `config` (a DSOCConfig, const or not), in the order above, with its name as spelled
/// in the struct. `member` is a reference to an int, float, bool or TbvStrategy.
/// set_field() and the server's [dsoc] table (TOML reader, --print-config) read it; a
/// test fails when a field is missing.
template <class Config, class Visitor>
requires std::is_same_v<std::remove_cvref_t<Config>, DSOCConfig>
void visit_fields(Config&& config, Visitor&& visit) {
    visit("tick_rate", config.tick_rate);
    visit("strategy", config.strategy);
    visit("default_tbv_duration", config.default_tbv_duration);
    visit("tbv_expansion_factor", config.tbv_expansion_factor);
    visit("max_tbvs_per_object", config.max_tbvs_per_object);
    visit("max_tbvs_per_client", config.max_tbvs_per_client);
    visit("velocity_threshold", config.velocity_threshold);
    visit("min_adaptive_duration", config.min_adaptive_duration);
    visit("max_adaptive_duration", config.max_adaptive_duration);
    visit("fuzzy_confidence", config.fuzzy_confidence);
    visit("tbv_merge_distance", config.tbv_merge_distance);
    visit("region_reuse_margin", config.region_reuse_margin);
    visit("lod_near_distance", config.lod_near_distance);
    visit("lod_far_distance", config.lod_far_distance);
    visit("entity_cluster_size", config.entity_cluster_size);
    visit("tbvs_enabled", config.tbvs_enabled);
    visit("reuse_buffers", config.reuse_buffers);
    visit("exact_region_tests", config.exact_region_tests);
    visit("blocker_hints", config.blocker_hints);
    visit("full_test_interval", config.full_test_interval);
    visit("validate_state", config.validate_state);
}

/// Sets the field named `key` (as visit_fields() names it; strategy takes "explicit",
/// "adaptive" or "fuzzy"; flags take true/false/1/0) from text, for tools and config
/// files. Returns "" on success, else what is wrong (unknown field, unparsable value).
/// Does not validate(): call it after the last change.
[[nodiscard]] std::string set_field(DSOCConfig& config, std::string_view key,
                                    std::string_view value);

} // namespace dsoc::visibility
