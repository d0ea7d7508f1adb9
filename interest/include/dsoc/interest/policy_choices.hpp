#pragma once
// The choices of PolicySettings that are names in config files and on command lines:
// which policy, which exact culler stages, whether the exact stages follow the baked
// table. Each has one table of names, used both ways: parsing where settings are read
// (server config file and flags, dsoc-inspect's flags) and printing (--print-config,
// logs, stats JSON, errors). The names are part of the interface: config keys, flags
// and docs use them as written here.

#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace dsoc::interest {

/// Which interest policy make_policy() builds.
enum class PolicyKind {
    dsoc,      ///< occlusion culling with TBVs, latency-safe
    occlusion, ///< the same culler, every entity tested every tick, no TBVs
    pvs,       ///< the map's PVS from the eye's cluster, as the Quake 3 server does
    distance,  ///< entities within a radius of the eye
    broadcast, ///< every entity
};

/// The exact occluder stages of the culling policies.
enum class CullerKind {
    shaft,   ///< the exact single-occluder shaft test (no per-region build)
    pyramid, ///< the from-region z-pyramid alone
    both,    ///< the z-pyramid, then the shaft test
};

/// With the baked stage: whether the PVS and shaft stages follow the table.
enum class ExactStages {
    when_coarse, ///< "auto": only when the bake had to make its cells coarser than asked
    always,      ///< "true"
    never,       ///< "false": the table alone where it covers
};

/// One entry of a choice's name table.
template <class Choice>
struct ChoiceName {
    Choice value;
    std::string_view name;
};

// The name tables, in the order messages list the names.
inline constexpr std::array<ChoiceName<PolicyKind>, 5> kPolicyNames{{
    {PolicyKind::dsoc, "dsoc"},
    {PolicyKind::occlusion, "occlusion"},
    {PolicyKind::pvs, "pvs"},
    {PolicyKind::distance, "distance"},
    {PolicyKind::broadcast, "broadcast"},
}};
inline constexpr std::array<ChoiceName<CullerKind>, 3> kCullerNames{{
    {CullerKind::shaft, "shaft"},
    {CullerKind::pyramid, "pyramid"},
    {CullerKind::both, "both"},
}};
inline constexpr std::array<ChoiceName<ExactStages>, 3> kExactStagesNames{{
    {ExactStages::when_coarse, "auto"},
    {ExactStages::always, "true"},
    {ExactStages::never, "false"},
}};

/// The name table of a choice type (found by argument-dependent lookup).
constexpr std::span<const ChoiceName<PolicyKind>> names_of(PolicyKind) {
    return kPolicyNames;
}
constexpr std::span<const ChoiceName<CullerKind>> names_of(CullerKind) {
    return kCullerNames;
}
constexpr std::span<const ChoiceName<ExactStages>> names_of(ExactStages) {
    return kExactStagesNames;
}

/// A type with a name table above.
template <class T>
concept NamedChoice = requires(T value) {
    names_of(value);
};

/// The name of `value` as config files and flags write it.
template <NamedChoice Choice>
[[nodiscard]] constexpr std::string_view name_of(Choice value) {
    for (const auto& entry : names_of(value)) {
        if (entry.value == value) {
            return entry.name;
        }
    }
    return "?";
}

/// The choice named `text` (exactly, case included); nullopt for any other text.
template <NamedChoice Choice>
[[nodiscard]] constexpr std::optional<Choice> parse_choice(std::string_view text) {
    for (const auto& entry : names_of(Choice{})) {
        if (entry.name == text) {
            return entry.value;
        }
    }
    return std::nullopt;
}

/// The same, for callers that find it by argument-dependent lookup (dsoc::cli's
/// add_choice_option()): sets `out` and returns true when `text` names a choice.
template <NamedChoice Choice>
[[nodiscard]] constexpr bool parse_choice(std::string_view text, Choice& out) {
    const auto choice = parse_choice<Choice>(text);
    if (choice) {
        out = *choice;
    }
    return choice.has_value();
}

/// Every name of `Choice`, comma separated: "shaft, pyramid, both".
template <NamedChoice Choice>
[[nodiscard]] std::string choice_names() {
    std::string out;
    for (const auto& entry : names_of(Choice{})) {
        out += (out.empty() ? "" : ", ") + std::string(entry.name);
    }
    return out;
}

/// Why `text` is not a `Choice`: "must be one of shaft, pyramid, both; got 'x'" (the
/// caller puts the key in front).
template <NamedChoice Choice>
[[nodiscard]] std::string not_a_choice(std::string_view text) {
    return "must be one of " + choice_names<Choice>() + "; got '" + std::string(text) + "'";
}

/// The same, for callers that find it by argument-dependent lookup.
template <NamedChoice Choice>
[[nodiscard]] std::string not_a_choice(std::string_view text, Choice /*type*/) {
    return not_a_choice<Choice>(text);
}

} // namespace dsoc::interest
