#include "dsoc/eval/scenario.hpp"

#include "dsoc/interest/interest_policy.hpp"

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <fstream>

#ifndef DSOC_EVAL_SCENARIOS
#define DSOC_EVAL_SCENARIOS "bench/scenarios.json"
#endif

namespace dsoc::eval {

std::vector<std::string> validate(const Scenario& s) {
    std::vector<std::string> problems;
    if (s.viewers < 1) {
        problems.push_back("viewers must be >= 1");
    }
    if (s.bots < 0) {
        problems.push_back("bots must be >= 0");
    }
    if (s.teams < 0 || s.teams > 1000) {
        problems.push_back("teams must be in 0..1000");
    }
    if (s.tick_rate < 1 || s.tick_rate > 240) {
        problems.push_back("tick_rate must be in 1..240 Hz");
    }
    if (s.rtt_ms < 0 || s.interpolation_ms < 0) {
        problems.push_back("rtt_ms and interpolation_ms must be >= 0");
    }
    if (!(s.duration_s > 0.0) || s.total_ticks() < 1) {
        problems.push_back("duration_s must be at least one tick");
    }
    if (s.oracle_clients < 0) {
        problems.push_back("oracle_clients must be >= 0");
    }
    if (s.oracle_every < 1) {
        problems.push_back("oracle_every must be >= 1");
    }
    if (!(s.distance_radius > 0.0f)) {
        problems.push_back("distance_radius must be > 0");
    }
    if (s.city_blocks < 0 || s.city_blocks > 256) {
        problems.push_back("city_blocks must be in 0..256");
    }
    return problems;
}

bool load_scenarios(const std::string& path, std::vector<Scenario>& out, std::string& error) {
    std::ifstream in(path);
    if (!in) {
        error = path + ": cannot open";
        return false;
    }
    const nlohmann::json doc = nlohmann::json::parse(in, nullptr, false);
    if (doc.is_discarded() || !doc.is_object() || !doc.contains("scenarios") ||
        !doc["scenarios"].is_array()) {
        error = path + ": not a scenarios file (an object with a \"scenarios\" array)";
        return false;
    }
    out.clear();
    try {
        for (const auto& j : doc["scenarios"]) {
            Scenario s;
            s.name = j.at("name").get<std::string>();
            s.description = j.value("description", "");
            s.map = j.value("map", s.map);
            s.city_blocks = j.value("city_blocks", s.city_blocks);
            s.viewers = j.value("viewers", s.viewers);
            s.bots = j.value("bots", s.bots);
            s.teams = j.value("teams", s.teams);
            s.sounds = j.value("sounds", s.sounds);
            s.tick_rate = j.value("tick_rate", s.tick_rate);
            s.rtt_ms = j.value("rtt_ms", s.rtt_ms);
            s.interpolation_ms = j.value("interpolation_ms", s.interpolation_ms);
            s.duration_s = j.value("duration_s", s.duration_s);
            s.oracle_every = j.value("oracle_every", s.oracle_every);
            s.oracle_clients = j.value("oracle_clients", s.oracle_clients);
            s.policies = j.value("policies", s.policies);
            s.distance_radius = j.value("distance_radius", s.distance_radius);
            s.seed = j.value("seed", s.seed);
            for (const auto& p : validate(s)) {
                error = path + ": scenario " + s.name + ": " + p;
                return false;
            }
            out.push_back(std::move(s));
        }
    } catch (const nlohmann::json::exception& e) {
        error = path + ": " + e.what();
        return false;
    }
    return true;
}

int Scenario::lookahead_ticks() const {
    return interest::lookahead_ticks(rtt_ms + interpolation_ms, tick_rate);
}

std::string default_scenarios_path() {
    if (const char* env = std::getenv("DSOC_SCENARIOS"); env != nullptr && *env != '\0') {
        return env;
    }
    return DSOC_EVAL_SCENARIOS;
}

} // namespace dsoc::eval
