#include "dsoc/eval/report.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <ostream>
#include <string>

namespace dsoc::eval {

namespace {

struct Derived {
    double updates_per_client_s = 0.0;
    double bytes_per_client_s = 0.0;
    double set_size = 0.0;
    Percentiles cpu;
    double exposure = 0.0;
    double bytes_vs_ideal = 0.0;
    double tbvs_created_per_client_s = 0.0;
    double live_tbvs_per_client = 0.0;
    double tbv_hit_rate = 0.0;
    double tbv_expired_rate = 0.0;
    double builds_per_client_s = 0.0;
};

double ratio(double a, double b) {
    return b > 0.0 ? a / b : 0.0;
}

Derived derive(const EvalResult& r, const PolicyMetrics& m) {
    Derived d;
    const double rate = r.scenario.tick_rate;
    const auto ct = static_cast<double>(m.client_ticks);
    d.updates_per_client_s = ratio(static_cast<double>(m.enters + m.updates), ct) * rate;
    d.bytes_per_client_s = ratio(static_cast<double>(m.bytes), ct) * rate;
    d.set_size = ratio(static_cast<double>(m.replicated_pairs), ct);
    d.cpu = summarize(m.cpu_us);
    d.exposure = ratio(static_cast<double>(m.exposed), static_cast<double>(m.checked_replicated));
    d.bytes_vs_ideal =
        ratio(static_cast<double>(m.measured_bytes), static_cast<double>(r.ideal_bytes));
    if (m.tbv.available) {
        d.tbvs_created_per_client_s = ratio(static_cast<double>(m.tbv.tbvs_created), ct) * rate;
        d.live_tbvs_per_client =
            ratio(static_cast<double>(m.live_tbv_sum), static_cast<double>(m.live_tbv_samples) *
                                                           static_cast<double>(r.scenario.viewers));
        // Hits are counted per group; a TBV that merged into a group made none.
        const std::uint64_t groups =
            m.tbv.tbvs_created - std::min(m.tbv.tbvs_merged, m.tbv.tbvs_created);
        d.tbv_hit_rate = ratio(static_cast<double>(m.tbv.tbv_hits), static_cast<double>(groups));
        d.tbv_expired_rate =
            ratio(static_cast<double>(m.tbv.tbvs_expired), static_cast<double>(m.tbv.tbvs_created));
        d.builds_per_client_s = ratio(static_cast<double>(m.tbv.buffer_builds), ct) * rate;
    }
    return d;
}

std::string fmt(const char* format, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, format, v);
    return buf;
}

double judged_clients(const EvalResult& r) {
    return static_cast<double>(r.oracle_ticks > 0 ? r.oracle_client_ticks / r.oracle_ticks : 0);
}

double ideal_bytes_per_client_s(const EvalResult& r) {
    return ratio(static_cast<double>(r.ideal_bytes),
                 static_cast<double>(r.measured_ticks) * judged_clients(r)) *
           r.scenario.tick_rate;
}
double ideal_updates_per_client_s(const EvalResult& r) {
    return ratio(static_cast<double>(r.ideal_updates),
                 static_cast<double>(r.measured_ticks) * judged_clients(r)) *
           r.scenario.tick_rate;
}

} // namespace

void write_markdown(const EvalResult& r, const std::string& command, std::ostream& out) {
    const Scenario& s = r.scenario;
    out << "## dsoc-eval: " << s.name << "\n\n";
    out << "`" << command << "`\n\n";
    out << "Map " << s.map << " (" << r.map_source << ", " << r.occluders << " occluders, "
        << r.oracle_triangles << " oracle triangles); " << s.viewers << " viewers, " << s.bots
        << " bots (" << r.entities << " entities); " << s.tick_rate << " Hz, " << r.ticks
        << " ticks (" << fmt("%.1f", r.ticks / static_cast<double>(s.tick_rate)) << " s); RTT "
        << s.rtt_ms << " ms + interpolation " << s.interpolation_ms
        << " ms = lookahead K = " << r.lookahead_ticks << " ticks; seed " << s.seed << ".\n";
    out << "Oracle: " << r.sample_grid << "x" << r.sample_grid
        << " samples per front box face + centre, Embree rays; judged " << r.oracle_ticks
        << " ticks = " << r.oracle_client_ticks << " client-ticks (every " << s.oracle_every
        << "th tick and the one before"
        << (r.oracle_client_stride > 1
                ? ", every " + std::to_string(r.oracle_client_stride) + "th client"
                : std::string())
        << "); ideal bytes from " << r.measured_ticks << " ticks. Wall "
        << fmt("%.1f", r.wall_seconds) << " s on " << r.threads << " threads (world "
        << fmt("%.1f", r.world_seconds) << " s, oracle " << fmt("%.1f", r.oracle_seconds)
        << " s).\n\n";

    out << "| policy | set size | updates/client/s | KB/client/s | bytes / ideal | CPU "
           "us/client-tick mean | p99 "
           "| pop-in K=0 | pop-in K="
        << r.lookahead_ticks << " | exposure | wall s |\n";
    out << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (std::size_t i = 0; i < r.policies.size(); ++i) {
        const PolicyMetrics& m = r.policies[i];
        const Derived d = derive(r, m);
        out << "| " << m.name << " | " << fmt("%.1f", d.set_size) << " | "
            << fmt("%.0f", d.updates_per_client_s) << " | "
            << fmt("%.2f", d.bytes_per_client_s / 1000.0) << " | "
            << (r.ideal_bytes > 0 ? fmt("%.2f", d.bytes_vs_ideal) : std::string("-")) << " | "
            << fmt("%.1f", d.cpu.mean) << " | " << fmt("%.1f", d.cpu.p99) << " | "
            << m.popin_present << " | " << m.popin_lookahead << " | "
            << fmt("%.1f%%", 100.0 * d.exposure) << " | "
            << fmt("%.1f", i < r.policy_seconds.size() ? r.policy_seconds[i] : 0.0) << " |\n";
    }
    const double ideal_set = ratio(static_cast<double>(r.ideal_visible_pairs),
                                   static_cast<double>(r.oracle_client_ticks));
    out << "| *oracle ideal* | " << fmt("%.1f", ideal_set) << " | "
        << fmt("%.0f", ideal_updates_per_client_s(r)) << " | "
        << fmt("%.2f", ideal_bytes_per_client_s(r) / 1000.0) << " | 1.00 | - | - | 0 | 0 | 0.0% | "
        << fmt("%.1f", r.oracle_seconds) << " |\n";
    if (r.region_bound) {
        // Updates scale with the set size: the ideal's updates per entity, times this set.
        const double region_set = ratio(static_cast<double>(r.region_visible_pairs),
                                        static_cast<double>(r.oracle_client_ticks));
        out << "| *region bound* | " << fmt("%.1f", region_set) << " | "
            << fmt("%.0f",
                   ideal_set > 0.0 ? ideal_updates_per_client_s(r) * region_set / ideal_set : 0.0)
            << " | - | - | - | - | 0 | 0 | - | - |\n";
    }
    out << "\n";
    if (!r.policies.empty() && r.policies.front().checked_by_rule > 0) {
        // The same pairs for every policy: the judged clients' teammates.
        out << "*Teams*: " << r.policies.front().checked_by_rule
            << " judged pairs are teammates, sent for their team whatever they see and left "
               "out of pop-in and exposure; not sent:";
        for (const auto& m : r.policies) {
            out << " " << m.name << " " << m.missed_by_rule;
        }
        out << ".\n\n";
    }
    if (s.sounds) {
        // Hearing adds to every policy's set: the same sounds, different sight sets.
        out << "*Hearing* (footsteps and shots; heard-only entities go coarse, without angles, "
               "and are judged apart from sight): heard-only entities per client-tick, their "
               "share of entity updates, the bytes they add, the share of judged pairs sent "
               "only for hearing (hearing's exposure) and how many of them were visible (also "
               "counted as pop-in):";
        for (const auto& m : r.policies) {
            const double entries = static_cast<double>(m.enters + m.updates);
            out << " " << m.name << " "
                << fmt("%.1f", ratio(static_cast<double>(m.heard_pairs),
                                     static_cast<double>(m.client_ticks)))
                << ", "
                << fmt("%.1f%%", 100.0 * ratio(static_cast<double>(m.heard_entries), entries))
                << ", +"
                << fmt("%.1f%%", 100.0 * ratio(static_cast<double>(m.bytes) -
                                                   static_cast<double>(m.sight_bytes),
                                               static_cast<double>(m.sight_bytes)))
                << ", "
                << fmt("%.1f%%",
                       100.0 * ratio(static_cast<double>(m.checked_heard),
                                     static_cast<double>(m.checked_replicated + m.checked_heard)))
                << ", " << m.heard_visible << ";";
        }
        out << "\n\n";
    }
    if (r.region_bound) {
        out << "*Region bound*: entities visible from some eye of a " << r.region_lattice << " x "
            << r.region_lattice << " x " << r.region_lattice
            << " lattice over "
               "each client's reachable eye region (the box the culling policies cover), plus "
               "the real eyes: at least what any policy covering that region must send "
               "(updates scaled from the ideal's per-entity rate).\n\n";
    }

    bool any_tbv = false;
    for (const auto& m : r.policies) {
        any_tbv = any_tbv || m.tbv.available;
    }
    if (any_tbv) {
        out << "| policy | buffer builds/client/s | TBVs created/client/s | live TBV groups/client "
               "| group hit rate | expired/created | merged | evictions | teleports |\n";
        out << "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
        for (const auto& m : r.policies) {
            if (!m.tbv.available) {
                continue;
            }
            const Derived d = derive(r, m);
            out << "| " << m.name << " | " << fmt("%.2f", d.builds_per_client_s) << " | "
                << fmt("%.1f", d.tbvs_created_per_client_s) << " | "
                << fmt("%.1f", d.live_tbvs_per_client) << " | "
                << fmt("%.1f%%", 100.0 * d.tbv_hit_rate) << " | "
                << fmt("%.1f%%", 100.0 * d.tbv_expired_rate) << " | " << m.tbv.tbvs_merged << " | "
                << m.tbv.evictions << " | " << m.tbv.teleports << " |\n";
        }
        out << "\n";
    }
    for (const auto& m : r.policies) {
        if (m.examples.empty()) {
            continue;
        }
        out << "Pop-in examples, " << m.name << " (tick, client, entity, kind):";
        for (const auto& e : m.examples) {
            out << " (" << e.tick << ", " << e.client << ", " << e.entity << ", "
                << (e.present_eye ? "present eye" : "lookahead") << ")";
        }
        out << "\n";
    }
    if (!r.trace_path.empty()) {
        out << "\nTrace: " << r.trace_path << " (policy " << r.trace_policy << ", " << r.trace_ticks
            << " ticks).\n";
    }
}

std::string to_json(const EvalResult& r, const std::string& command) {
    using nlohmann::json;
    const Scenario& s = r.scenario;
    json j;
    j["command"] = command;
    j["scenario"] = {{"name", s.name},
                     {"description", s.description},
                     {"map", s.map},
                     {"map_source", r.map_source},
                     {"viewers", s.viewers},
                     {"bots", s.bots},
                     {"teams", s.teams},
                     {"sounds", s.sounds},
                     {"entities", r.entities},
                     {"tick_rate", s.tick_rate},
                     {"rtt_ms", s.rtt_ms},
                     {"interpolation_ms", s.interpolation_ms},
                     {"duration_s", r.ticks / static_cast<double>(s.tick_rate)},
                     {"ticks", r.ticks},
                     {"seed", s.seed},
                     {"lookahead_ticks", r.lookahead_ticks},
                     {"distance_radius", s.distance_radius}};
    j["oracle"] = {{"sample_grid", r.sample_grid},
                   {"every", s.oracle_every},
                   {"client_stride", r.oracle_client_stride},
                   {"ticks", r.oracle_ticks},
                   {"client_ticks", r.oracle_client_ticks},
                   {"measured_ticks", r.measured_ticks},
                   {"occluders", r.occluders},
                   {"triangles", r.oracle_triangles},
                   {"ideal_bytes_per_client_s", ideal_bytes_per_client_s(r)},
                   {"ideal_updates_per_client_s", ideal_updates_per_client_s(r)},
                   {"region_bound_set_size",
                    r.region_bound ? ratio(static_cast<double>(r.region_visible_pairs),
                                           static_cast<double>(r.oracle_client_ticks))
                                   : 0.0},
                   {"ideal_set_size", ratio(static_cast<double>(r.ideal_visible_pairs),
                                            static_cast<double>(r.oracle_client_ticks))},
                   {"seconds", r.oracle_seconds}};
    j["timing"] = {{"wall_seconds", r.wall_seconds},
                   {"world_seconds", r.world_seconds},
                   {"threads", r.threads}};
    json policies = json::array();
    for (std::size_t i = 0; i < r.policies.size(); ++i) {
        const PolicyMetrics& m = r.policies[i];
        const Derived d = derive(r, m);
        json p = {{"name", m.name},
                  {"lookahead_ticks", m.lookahead_ticks},
                  {"client_ticks", m.client_ticks},
                  {"set_size", d.set_size},
                  {"entity_updates_per_client_s", d.updates_per_client_s},
                  {"bytes_per_client_s", d.bytes_per_client_s},
                  {"enters", m.enters},
                  {"updates", m.updates},
                  {"leaves", m.leaves},
                  {"bytes", m.bytes},
                  {"cpu_us_per_client_tick",
                   {{"mean", d.cpu.mean}, {"p99", d.cpu.p99}, {"max", d.cpu.max}}},
                  {"checked_client_ticks", m.checked_client_ticks},
                  {"checked_replicated", m.checked_replicated},
                  {"popin_present", m.popin_present},
                  {"popin_lookahead", m.popin_lookahead},
                  {"exposed", m.exposed},
                  {"checked_by_rule", m.checked_by_rule},
                  {"missed_by_rule", m.missed_by_rule},
                  {"heard_pairs", m.heard_pairs},
                  {"heard_entries", m.heard_entries},
                  {"sight_bytes", m.sight_bytes},
                  {"checked_heard", m.checked_heard},
                  {"heard_visible", m.heard_visible},
                  {"exposure", d.exposure},
                  {"measured_bytes", m.measured_bytes},
                  {"bytes_vs_ideal", d.bytes_vs_ideal},
                  {"wall_seconds", i < r.policy_seconds.size() ? r.policy_seconds[i] : 0.0}};
        if (m.tbv.available) {
            p["tbv"] = {{"buffer_builds", m.tbv.buffer_builds},
                        {"buffer_builds_per_client_s", d.builds_per_client_s},
                        {"box_tests", m.tbv.box_tests},
                        {"tbv_tests", m.tbv.tbv_tests},
                        {"cluster_tests", m.tbv.cluster_tests},
                        {"cluster_hits", m.tbv.cluster_hits},
                        {"cheapest_updates", m.tbv.cheapest_updates},
                        {"created", m.tbv.tbvs_created},
                        {"created_per_client_s", d.tbvs_created_per_client_s},
                        {"merged", m.tbv.tbvs_merged},
                        {"rejected", m.tbv.tbvs_rejected},
                        {"hits", m.tbv.tbv_hits},
                        {"hit_rate", d.tbv_hit_rate},
                        {"expired", m.tbv.tbvs_expired},
                        {"expired_rate", d.tbv_expired_rate},
                        {"evictions", m.tbv.evictions},
                        {"teleports", m.tbv.teleports},
                        {"fuzzy_escapes", m.tbv.fuzzy_escapes},
                        {"live_groups_per_client", d.live_tbvs_per_client}};
        }
        json ex = json::array();
        for (const auto& e : m.examples) {
            ex.push_back({{"tick", e.tick},
                          {"client", e.client},
                          {"entity", e.entity},
                          {"present_eye", e.present_eye}});
        }
        p["popin_examples"] = ex;
        policies.push_back(std::move(p));
    }
    j["policies"] = policies;
    if (!r.trace_path.empty()) {
        j["trace"] = {{"path", r.trace_path}, {"policy", r.trace_policy}, {"ticks", r.trace_ticks}};
    }
    return j.dump(2) + "\n";
}

} // namespace dsoc::eval
