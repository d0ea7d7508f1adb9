#include "dsoc/trace/trace_reader.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <utility>

namespace dsoc::trace {

namespace {

using nlohmann::json;

bool get_u32(const json& j, std::uint32_t& out) {
    if (!j.is_number_unsigned() && !(j.is_number_integer() && j.get<std::int64_t>() >= 0)) {
        return false;
    }
    const auto v = j.get<std::uint64_t>();
    if (v > std::numeric_limits<std::uint32_t>::max()) {
        return false;
    }
    out = static_cast<std::uint32_t>(v);
    return true;
}

bool get_float(const json& j, float& out) {
    if (!j.is_number()) {
        return false;
    }
    out = j.get<float>();
    return std::isfinite(out);
}

bool get_vec3(const json& j, glm::vec3& out) {
    return j.is_array() && j.size() == 3 && get_float(j[0], out.x) && get_float(j[1], out.y) &&
           get_float(j[2], out.z);
}

} // namespace

bool TraceReader::fail(const std::string& what) {
    error_ = path_ + ":" + std::to_string(line_number_) + ": " + what;
    return false;
}

bool TraceReader::open(const std::string& path) {
    path_ = path;
    in_.open(path);
    if (!in_) {
        line_number_ = 0;
        return fail("cannot open the trace file");
    }
    std::string line;
    if (!std::getline(in_, line)) {
        line_number_ = 1;
        return fail("empty file: expected the header line");
    }
    line_number_ = 1;
    const json j = json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.is_object()) {
        return fail("header: not a JSON object");
    }
    // Not j.value("type", ""), which throws when the type is not a string.
    if (!j.contains("type") || !j["type"].is_string() || j["type"] != "header") {
        return fail("first line must have \"type\":\"header\"");
    }
    if (!j.contains("version") || j["version"] != kTraceVersion) {
        return fail("header: version must be 1");
    }
    if (!j.contains("map") || !j["map"].is_string() || !j.contains("tick_rate") ||
        !j["tick_rate"].is_number_integer() || !j.contains("policy") || !j["policy"].is_string() ||
        !j.contains("lookahead_ticks") || !j["lookahead_ticks"].is_number_integer() ||
        !j.contains("occluders") || !j["occluders"].is_array()) {
        return fail("header: needs map (string), tick_rate (int), policy (string), "
                    "lookahead_ticks (int) and occluders (array)");
    }
    header_.map = j["map"].get<std::string>();
    header_.tick_rate = j["tick_rate"].get<int>();
    header_.policy = j["policy"].get<std::string>();
    header_.lookahead_ticks = j["lookahead_ticks"].get<int>();
    if (header_.tick_rate <= 0 || header_.lookahead_ticks < 0) {
        return fail("header: tick_rate must be > 0 and lookahead_ticks >= 0");
    }
    header_.occluders.clear();
    for (const auto& o : j["occluders"]) {
        TraceOccluder occ;
        if (!o.is_object() || !o.contains("id") || !get_u32(o["id"], occ.id) ||
            !o.contains("planes") || !o["planes"].is_array()) {
            return fail("header: occluder " + std::to_string(header_.occluders.size()) +
                        " needs id and planes");
        }
        for (const auto& p : o["planes"]) {
            visibility::Plane plane;
            if (!p.is_array() || p.size() != 4 || !get_float(p[0], plane.normal.x) ||
                !get_float(p[1], plane.normal.y) || !get_float(p[2], plane.normal.z) ||
                !get_float(p[3], plane.distance)) {
                return fail("header: occluder " + std::to_string(occ.id) +
                            ": a plane must be [nx,ny,nz,d] of finite numbers");
            }
            occ.planes.push_back(plane);
        }
        header_.occluders.push_back(std::move(occ));
    }
    header_.patches.clear();
    if (j.contains("patches")) {
        if (!j["patches"].is_array()) {
            return fail("header: patches must be an array");
        }
        for (const auto& p : j["patches"]) {
            const std::string which = "header: patch " + std::to_string(header_.patches.size());
            TracePatch patch;
            const auto side_ok = [](const json& n) {
                return n.is_number_integer() && n.get<long long>() >= 3 &&
                       n.get<long long>() <= 31 && n.get<long long>() % 2 == 1;
            };
            if (!p.is_object() || !p.contains("width") || !side_ok(p["width"]) ||
                !p.contains("height") || !side_ok(p["height"]) || !p.contains("points") ||
                !p["points"].is_array()) {
                return fail(which + " needs width and height (odd, 3 to 31) and points");
            }
            patch.width = p["width"].get<int>();
            patch.height = p["height"].get<int>();
            if (p["points"].size() != static_cast<std::size_t>(patch.width * patch.height)) {
                return fail(which + ": " + std::to_string(p["points"].size()) + " points for " +
                            std::to_string(patch.width) + " x " + std::to_string(patch.height));
            }
            for (const auto& point : p["points"]) {
                glm::vec3 v;
                if (!get_vec3(point, v)) {
                    return fail(which + ": a point must be [x,y,z] of finite numbers");
                }
                patch.points.push_back(v);
            }
            header_.patches.push_back(std::move(patch));
        }
    }
    return true;
}

bool TraceReader::next(TraceTick& tick) {
    std::string line;
    if (finished_ || !error_.empty()) {
        return false;
    }
    if (!std::getline(in_, line)) {
        return fail("missing the end line");
    }
    ++line_number_;
    const json j = json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("type") || !j["type"].is_string()) {
        return fail("not a JSON object with a type");
    }
    const std::string type = j["type"].get<std::string>();
    if (type == "end") {
        if (!j.contains("ticks") || !j["ticks"].is_number_unsigned() ||
            j["ticks"].get<std::uint64_t>() != ticks_) {
            return fail("end: ticks must equal the " + std::to_string(ticks_) + " tick lines read");
        }
        finished_ = true;
        return false;
    }
    if (type != "tick") {
        return fail("unknown line type '" + type + "'");
    }
    if (!j.contains("t") || !j["t"].is_number_unsigned() || !j.contains("entities") ||
        !j["entities"].is_array() || !j.contains("clients") || !j["clients"].is_array()) {
        return fail("tick: needs t (unsigned), entities and clients (arrays)");
    }
    tick.t = j["t"].get<std::uint64_t>();
    if (any_tick_ && tick.t <= last_t_) {
        return fail("tick t=" + std::to_string(tick.t) + " does not increase");
    }
    tick.entities.clear();
    for (const auto& e : j["entities"]) {
        TraceEntity te;
        if (!e.is_array() || e.size() != 7 || !get_u32(e[0], te.id) ||
            !get_float(e[1], te.box.min.x) || !get_float(e[2], te.box.min.y) ||
            !get_float(e[3], te.box.min.z) || !get_float(e[4], te.box.max.x) ||
            !get_float(e[5], te.box.max.y) || !get_float(e[6], te.box.max.z)) {
            return fail("tick: an entity must be [id,minx,miny,minz,maxx,maxy,maxz]");
        }
        tick.entities.push_back(te);
    }
    tick.clients.clear();
    for (const auto& c : j["clients"]) {
        TraceClient tc;
        if (!c.is_object() || !c.contains("id") || !get_u32(c["id"], tc.id) || !c.contains("eye") ||
            !get_vec3(c["eye"], tc.eye) || !c.contains("replicated") ||
            !c["replicated"].is_array()) {
            return fail("tick: a client needs id, eye [x,y,z] and replicated");
        }
        if (c.contains("entity") && !c["entity"].is_null()) {
            std::uint32_t entity = 0;
            if (!get_u32(c["entity"], entity)) {
                return fail("tick: client " + std::to_string(tc.id) + ": bad entity");
            }
            tc.entity = entity;
        }
        if (c.contains("arrival") && !c["arrival"].is_null()) {
            glm::vec3 arrival{0.0f};
            if (!get_vec3(c["arrival"], arrival)) {
                return fail("tick: client " + std::to_string(tc.id) + ": arrival must be [x,y,z]");
            }
            tc.arrival = arrival;
        }
        const auto read_ids = [&](const char* key, std::vector<std::uint32_t>& ids) {
            if (!c.contains(key) || c[key].is_null()) {
                return true; // only `replicated` is required (checked above)
            }
            if (!c[key].is_array()) {
                return false;
            }
            for (const auto& r : c[key]) {
                std::uint32_t id = 0;
                if (!get_u32(r, id)) {
                    return false;
                }
                ids.push_back(id);
            }
            return true;
        };
        const std::pair<const char*, std::vector<std::uint32_t>*> lists[] = {
            {"replicated", &tc.replicated},
            {"always", &tc.always},
            {"never", &tc.never},
            {"heard", &tc.heard}};
        for (const auto& [key, ids] : lists) {
            if (!read_ids(key, *ids)) {
                return fail("tick: client " + std::to_string(tc.id) + ": bad " + key + " id");
            }
        }
        tick.clients.push_back(std::move(tc));
    }
    any_tick_ = true;
    last_t_ = tick.t;
    ++ticks_;
    return true;
}

} // namespace dsoc::trace
