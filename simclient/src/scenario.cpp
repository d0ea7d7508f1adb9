#include "dsoc/simclient/scenario.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace dsoc::simclient {

DatagramFaults DatagramFaults::worst_with(const DatagramFaults& o) const {
    return {std::max(loss, o.loss), std::max(duplicate, o.duplicate), std::max(reorder, o.reorder)};
}

std::string_view to_string(Behaviour behaviour) {
    switch (behaviour) {
    case Behaviour::wanderer:
        return "wanderer";
    case Behaviour::camper:
        return "camper";
    case Behaviour::respawner:
        return "respawner";
    case Behaviour::spectator:
        return "spectator";
    }
    return "?";
}

bool behaviour_from_string(std::string_view name, Behaviour& out) {
    for (const Behaviour b :
         {Behaviour::wanderer, Behaviour::camper, Behaviour::respawner, Behaviour::spectator}) {
        if (to_string(b) == name) {
            out = b;
            return true;
        }
    }
    return false;
}

double Scenario::length_s() const {
    double total = 0.0;
    for (const Stage& s : stages) {
        total += s.duration_s;
    }
    return total;
}

int Scenario::peak_target() const {
    int peak = 0;
    for (const Stage& s : stages) {
        peak = std::max(peak, s.target);
    }
    return peak;
}

Scenario implicit_scenario(int clients, double duration_s, double ramp_up_s) {
    Scenario s;
    s.stages = {{ramp_up_s, clients}, {std::max(0.0, duration_s - ramp_up_s), clients}};
    s.groups = {ClientGroup{}};
    return s;
}

int target_at(const std::vector<Stage>& stages, double t_s) {
    double start = 0.0;
    int previous = 0;
    for (const Stage& s : stages) {
        const double end = start + s.duration_s;
        if (t_s < end) {
            const double f = s.duration_s > 0.0 ? (t_s - start) / s.duration_s : 1.0;
            const double value = previous + (s.target - previous) * std::clamp(f, 0.0, 1.0);
            return static_cast<int>(std::ceil(value - 1e-9));
        }
        start = end;
        previous = s.target;
    }
    return 0;
}

std::vector<int> split_by_weight(int total, const std::vector<ClientGroup>& groups) {
    std::vector<int> shares(groups.size(), 0);
    double weight_sum = 0.0;
    for (const auto& g : groups) {
        weight_sum += g.weight;
    }
    if (groups.empty() || weight_sum <= 0.0) {
        return shares;
    }
    std::vector<std::pair<double, std::size_t>> remainders;
    int given = 0;
    for (std::size_t i = 0; i < groups.size(); ++i) {
        const double exact = total * groups[i].weight / weight_sum;
        shares[i] = static_cast<int>(std::floor(exact));
        given += shares[i];
        remainders.emplace_back(exact - shares[i], i);
    }
    std::stable_sort(remainders.begin(), remainders.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    for (std::size_t k = 0; given < total; ++k, ++given) {
        ++shares[remainders[k % remainders.size()].second];
    }
    return shares;
}

std::string validate(const Scenario& scenario) {
    if (scenario.stages.empty()) {
        return "stages: at least one stage is needed";
    }
    for (std::size_t i = 0; i < scenario.stages.size(); ++i) {
        const Stage& s = scenario.stages[i];
        const std::string which = "stage " + std::to_string(i + 1);
        if (!(s.duration_s >= 0.0) || !std::isfinite(s.duration_s)) {
            return which + ": duration must be >= 0 s";
        }
        if (s.target < 0 || s.target > 100000) {
            return which + ": target must be 0..100000, got " + std::to_string(s.target);
        }
    }
    if (!(scenario.length_s() > 0.0)) {
        return "stages: the durations must add up to more than 0 s";
    }
    if (scenario.groups.empty()) {
        return "groups: at least one group is needed";
    }
    std::set<std::string> names;
    for (const ClientGroup& g : scenario.groups) {
        const std::string which = "group '" + g.name + "'";
        if (!names.insert(g.name).second) {
            return which + ": the name is used twice";
        }
        if (!(g.weight > 0.0) || !std::isfinite(g.weight)) {
            return which + ": weight must be > 0";
        }
        if (!(g.churn_per_s >= 0.0) || !std::isfinite(g.churn_per_s)) {
            return which + ": churn must be >= 0 per second";
        }
        if (!(g.respawn_every_s > 0.0)) {
            return which + ": respawn_every must be > 0 s";
        }
        if (!(g.network.latency_ms >= 0.0 && g.network.latency_ms <= 10000.0) ||
            !(g.network.jitter_ms >= 0.0 && g.network.jitter_ms <= 10000.0)) {
            return which + ": latency and jitter must be 0..10 s";
        }
        const DatagramFaults& f = g.network.faults;
        for (const double p : {f.loss, f.duplicate, f.reorder}) {
            if (!(p >= 0.0 && p <= 0.9)) {
                return which + ": loss, duplicate and reorder must be 0..0.9";
            }
        }
    }
    if (!(scenario.connect_timeout_s > 0.0)) {
        return "connect_timeout must be > 0 s";
    }
    return {};
}

} // namespace dsoc::simclient
