#include "dsoc/simclient/scenario_file.hpp"

#include "dsoc/common/read_file.hpp"

#include <toml++/toml.h>

#include <set>

namespace dsoc::simclient {

namespace {

/// Thrown inside the parser with a message already naming where and what.
struct FileError {
    std::string message;
};

class Reader {
public:
    explicit Reader(std::string_view source) : source_(source) {}

    [[noreturn]] void fail(const toml::node& node, const std::string& key,
                           const std::string& why) const {
        const auto& at = node.source().begin;
        throw FileError{source_ + ":" + std::to_string(at.line) + ":" + std::to_string(at.column) +
                        ": " + key + ": " + why};
    }

    [[noreturn]] void fail_file(const std::string& why) const {
        throw FileError{source_ + ": " + why};
    }

    /// Refuses keys of `table` outside `known`.
    void only(const toml::table& table, const std::string& where,
              std::initializer_list<std::string_view> known) const {
        for (const auto& [key, node] : table) {
            bool ok = false;
            for (const auto k : known) {
                ok = ok || key.str() == k;
            }
            if (!ok) {
                std::string list;
                for (const auto k : known) {
                    list += (list.empty() ? "" : ", ") + std::string(k);
                }
                fail(node, where + std::string(key.str()), "unknown key; known: " + list);
            }
        }
    }

    double duration_s(const toml::node& node, const std::string& key) const {
        if (const auto* i = node.as_integer()) {
            return check_duration(node, key, static_cast<double>(i->get()));
        }
        if (const auto* f = node.as_floating_point()) {
            return check_duration(node, key, f->get());
        }
        if (const auto* s = node.as_string()) {
            double seconds = 0.0;
            std::string why;
            if (!parse_duration_s(s->get(), seconds, why)) {
                fail(node, key, why);
            }
            return seconds;
        }
        fail(node, key, "expected a duration (\"5s\", \"500ms\", \"1m30s\" or seconds)");
    }

    double number(const toml::node& node, const std::string& key) const {
        if (const auto* i = node.as_integer()) {
            return static_cast<double>(i->get());
        }
        if (const auto* f = node.as_floating_point()) {
            return f->get();
        }
        fail(node, key, "expected a number");
    }

    int count(const toml::node& node, const std::string& key) const {
        const auto* i = node.as_integer();
        if (i == nullptr || i->get() < 0 || i->get() > 100000) {
            fail(node, key, "expected a whole number 0..100000");
        }
        return static_cast<int>(i->get());
    }

    std::string string(const toml::node& node, const std::string& key) const {
        const auto* s = node.as_string();
        if (s == nullptr) {
            fail(node, key, "expected a string");
        }
        return s->get();
    }

    const toml::table& table(const toml::node& node, const std::string& key) const {
        const auto* t = node.as_table();
        if (t == nullptr) {
            fail(node, key, "expected a table ({ duration = \"5s\", target = 10 })");
        }
        return *t;
    }

    const toml::array& array(const toml::node& node, const std::string& key) const {
        const auto* a = node.as_array();
        if (a == nullptr) {
            fail(node, key, "expected an array");
        }
        return *a;
    }

private:
    double check_duration(const toml::node& node, const std::string& key, double seconds) const {
        if (!(seconds >= 0.0)) {
            fail(node, key, "must be >= 0 s");
        }
        return seconds;
    }

    std::string source_;
};

Stage read_stage(const Reader& r, const toml::node& node, const std::string& where) {
    const toml::table& t = r.table(node, where);
    r.only(t, where + ".", {"duration", "target"});
    const toml::node* duration = t.get("duration");
    const toml::node* target = t.get("target");
    if (duration == nullptr || target == nullptr) {
        r.fail(node, where,
               "a stage needs duration and target ({ duration = \"5s\", target = 10 })");
    }
    return {r.duration_s(*duration, where + ".duration"), r.count(*target, where + ".target")};
}

ClientGroup read_group(const Reader& r, const toml::node& node, const std::string& where,
                       std::size_t index) {
    const toml::table& t = r.table(node, where);
    r.only(t, where + ".",
           {"name", "behaviour", "weight", "churn_per_s", "respawn_every", "latency", "jitter",
            "loss", "duplicate", "reorder"});
    ClientGroup g;
    g.name = "group-" + std::to_string(index + 1);
    for (const auto& [k, v] : t) {
        const std::string_view name_of_key = k.str();
        const std::string key = where + "." + std::string(name_of_key);
        if (name_of_key == "name") {
            g.name = r.string(v, key);
        } else if (name_of_key == "behaviour") {
            const std::string name = r.string(v, key);
            if (!behaviour_from_string(name, g.behaviour)) {
                r.fail(v, key,
                       "unknown behaviour '" + name +
                           "'; known: wanderer, camper, respawner, spectator");
            }
        } else if (name_of_key == "weight") {
            g.weight = r.number(v, key);
            if (!(g.weight > 0.0)) {
                r.fail(v, key, "must be > 0");
            }
        } else if (name_of_key == "churn_per_s") {
            g.churn_per_s = r.number(v, key);
            if (!(g.churn_per_s >= 0.0)) {
                r.fail(v, key, "must be >= 0");
            }
        } else if (name_of_key == "respawn_every") {
            g.respawn_every_s = r.duration_s(v, key);
            if (!(g.respawn_every_s > 0.0)) {
                r.fail(v, key, "must be > 0 s");
            }
        } else if (name_of_key == "latency") {
            g.network.latency_ms = 1000.0 * r.duration_s(v, key);
        } else if (name_of_key == "jitter") {
            g.network.jitter_ms = 1000.0 * r.duration_s(v, key);
        } else if (name_of_key == "loss" || name_of_key == "duplicate" ||
                   name_of_key == "reorder") {
            const double p = r.number(v, key);
            if (!(p >= 0.0 && p <= 0.9)) {
                r.fail(v, key, "must be a probability 0..0.9 (UDP only)");
            }
            DatagramFaults& f = g.network.faults;
            (name_of_key == "loss"        ? f.loss
             : name_of_key == "duplicate" ? f.duplicate
                                          : f.reorder) = p;
        }
    }
    return g;
}

void read_scenario(const Reader& r, const toml::table& root, Scenario& s) {
    r.only(root, "", {"stages", "groups", "thresholds", "connect_timeout"});
    s = Scenario{};
    if (const toml::node* stages = root.get("stages")) {
        const toml::array& a = r.array(*stages, "stages");
        for (std::size_t i = 0; i < a.size(); ++i) {
            s.stages.push_back(read_stage(r, a[i], "stages[" + std::to_string(i) + "]"));
        }
    }
    if (const toml::node* groups = root.get("groups")) {
        const toml::array& a = r.array(*groups, "groups");
        for (std::size_t i = 0; i < a.size(); ++i) {
            s.groups.push_back(read_group(r, a[i], "groups[" + std::to_string(i) + "]", i));
        }
    }
    if (s.groups.empty()) {
        s.groups.push_back(ClientGroup{}); // wanderers, all of the count
    }
    if (const toml::node* thresholds = root.get("thresholds")) {
        const toml::array& a = r.array(*thresholds, "thresholds");
        for (std::size_t i = 0; i < a.size(); ++i) {
            const std::string key = "thresholds[" + std::to_string(i) + "]";
            Threshold t;
            std::string why;
            if (!parse_threshold(r.string(a[i], key), t, why)) {
                r.fail(a[i], key, why);
            }
            s.thresholds.push_back(std::move(t));
        }
    }
    if (const toml::node* timeout = root.get("connect_timeout")) {
        s.connect_timeout_s = r.duration_s(*timeout, "connect_timeout");
    }
    if (const std::string why = validate(s); !why.empty()) {
        r.fail_file(why);
    }
}

} // namespace

bool parse_scenario(std::string_view text, std::string_view source, Scenario& out,
                    std::string& error) {
    const Reader reader(source);
    try {
        const toml::table root = toml::parse(text, source);
        Scenario s;
        read_scenario(reader, root, s);
        out = std::move(s);
        return true;
    } catch (const toml::parse_error& e) {
        const auto& at = e.source().begin;
        error = std::string(source) + ":" + std::to_string(at.line) + ":" +
                std::to_string(at.column) + ": " + std::string(e.description());
    } catch (const FileError& e) {
        error = e.message;
    }
    return false;
}

bool load_scenario_file(const std::string& path, Scenario& out, std::string& error) {
    std::string text;
    if (const std::string why = common::read_file(path, text); !why.empty()) {
        error = path + ": cannot read scenario file: " + why;
        return false;
    }
    return parse_scenario(text, path, out, error);
}

} // namespace dsoc::simclient
