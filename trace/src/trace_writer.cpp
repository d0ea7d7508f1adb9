#include "dsoc/trace/trace_writer.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <iterator>

namespace dsoc::trace {

namespace {

// fmt prints floats in their shortest round-trip form, so a reader gets back the
// exact values the server used.
void append_vec(std::string& out, glm::vec3 v) {
    fmt::format_to(std::back_inserter(out), "[{},{},{}]", v.x, v.y, v.z);
}

/// `,"key":[id,id,...]`
void append_ids(std::string& out, const char* key, const std::vector<std::uint32_t>& ids) {
    fmt::format_to(std::back_inserter(out), R"(,"{}":[)", key);
    for (std::size_t k = 0; k < ids.size(); ++k) {
        fmt::format_to(std::back_inserter(out), "{}{}", k ? "," : "", ids[k]);
    }
    out += "]";
}

} // namespace

TraceWriter::~TraceWriter() {
    close();
}

bool TraceWriter::open(const std::string& path, const TraceHeader& header, std::string& error) {
    close();
    file_ = std::fopen(path.c_str(), "w");
    if (file_ == nullptr) {
        error = "cannot open trace file '" + path + "': " + std::strerror(errno);
        return false;
    }
    ticks_ = 0;
    any_tick_ = false;
    std::string& out = line_;
    out.clear();
    // Strings we write (map, policy) are names: the quote and the backslash escaped,
    // control characters as \u00XX, so that a reader reads back the same string.
    const auto quoted = [](const std::string& s) {
        std::string q = "\"";
        for (const char c : s) {
            if (c == '"' || c == '\\') {
                q += '\\';
            }
            if (static_cast<unsigned char>(c) >= 0x20) {
                q += c;
            } else {
                fmt::format_to(std::back_inserter(q), "\\u{:04x}", static_cast<unsigned>(c));
            }
        }
        return q + "\"";
    };
    fmt::format_to(std::back_inserter(out),
                   R"({{"type":"header","version":{},"map":{},"tick_rate":{},"policy":{},)"
                   R"("lookahead_ticks":{},"occluders":[)",
                   kTraceVersion, quoted(header.map), header.tick_rate, quoted(header.policy),
                   header.lookahead_ticks);
    for (std::size_t i = 0; i < header.occluders.size(); ++i) {
        const auto& o = header.occluders[i];
        fmt::format_to(std::back_inserter(out), R"({}{{"id":{},"planes":[)", i ? "," : "", o.id);
        for (std::size_t k = 0; k < o.planes.size(); ++k) {
            const auto& p = o.planes[k];
            fmt::format_to(std::back_inserter(out), "{}[{},{},{},{}]", k ? "," : "", p.normal.x,
                           p.normal.y, p.normal.z, p.distance);
        }
        out += "]}";
    }
    out += "]";
    if (!header.patches.empty()) {
        out += R"(,"patches":[)";
        for (std::size_t i = 0; i < header.patches.size(); ++i) {
            const auto& patch = header.patches[i];
            fmt::format_to(std::back_inserter(out), R"({}{{"width":{},"height":{},"points":[)",
                           i ? "," : "", patch.width, patch.height);
            for (std::size_t k = 0; k < patch.points.size(); ++k) {
                const glm::vec3 p = patch.points[k];
                fmt::format_to(std::back_inserter(out), "{}[{},{},{}]", k ? "," : "", p.x, p.y,
                               p.z);
            }
            out += "]}";
        }
        out += "]";
    }
    out += "}\n";
    if (!put(out)) {
        error = "cannot write trace file '" + path + "'";
        return false;
    }
    return true;
}

bool TraceWriter::write_tick(const TraceTick& tick) {
    if (file_ == nullptr || (any_tick_ && tick.t <= last_t_)) {
        return false;
    }
    std::string& out = line_;
    out.clear();
    fmt::format_to(std::back_inserter(out), R"({{"type":"tick","t":{},"entities":[)", tick.t);
    for (std::size_t i = 0; i < tick.entities.size(); ++i) {
        const auto& e = tick.entities[i];
        fmt::format_to(std::back_inserter(out), "{}[{},{},{},{},{},{},{}]", i ? "," : "", e.id,
                       e.box.min.x, e.box.min.y, e.box.min.z, e.box.max.x, e.box.max.y,
                       e.box.max.z);
    }
    out += R"(],"clients":[)";
    for (std::size_t i = 0; i < tick.clients.size(); ++i) {
        const auto& c = tick.clients[i];
        fmt::format_to(std::back_inserter(out), R"({}{{"id":{},"entity":)", i ? "," : "", c.id);
        if (c.entity) {
            fmt::format_to(std::back_inserter(out), "{}", *c.entity);
        } else {
            out += "null";
        }
        out += R"(,"eye":)";
        append_vec(out, c.eye);
        if (c.arrival) {
            out += R"(,"arrival":)";
            append_vec(out, *c.arrival);
        }
        append_ids(out, "replicated", c.replicated);
        if (!c.always.empty()) {
            append_ids(out, "always", c.always);
        }
        if (!c.never.empty()) {
            append_ids(out, "never", c.never);
        }
        if (!c.heard.empty()) {
            append_ids(out, "heard", c.heard);
        }
        out += "}";
    }
    out += "]}\n";
    if (!put(out)) {
        return false;
    }
    any_tick_ = true;
    last_t_ = tick.t;
    ++ticks_;
    return true;
}

bool TraceWriter::close() {
    if (file_ == nullptr) {
        return true;
    }
    const bool ok = put(fmt::format(R"({{"type":"end","ticks":{}}})"
                                    "\n",
                                    ticks_));
    const bool closed = std::fclose(file_) == 0;
    file_ = nullptr;
    return ok && closed;
}

bool TraceWriter::put(const std::string& line) {
    return std::fwrite(line.data(), 1, line.size(), file_) == line.size();
}

} // namespace dsoc::trace
