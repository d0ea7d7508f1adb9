// Fuzzes the replication trace reader (dsoc/trace/trace_reader.hpp): any bytes must be
// read as a trace or give an error naming the line, never a crash, a sanitizer report
// or a hang, and what it accepts must keep the format's promises
// (docs/replication-trace.md):
// - a reader that stops has finished (the end line, its tick count right) or says why;
// - every header patch is a width x height grid of finite points, both sides odd 3..31;
// - ticks increase; boxes, eyes and points are finite;
// - what was read, written again by TraceWriter and read back, is the same.

#include "dsoc/trace/trace_reader.hpp"
#include "dsoc/trace/trace_writer.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>
#include <vector>

namespace {

void require(bool ok) {
    if (!ok) {
        std::abort();
    }
}

bool finite(glm::vec3 v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// This process's scratch file (the reader reads files), one per fuzzing process.
std::string scratch(const char* what) {
    const char* dir = std::getenv("TMPDIR");
    return std::string(dir != nullptr ? dir : "/tmp") + "/dsoc-fuzz-trace-" +
           std::to_string(getpid()) + what;
}

constexpr int kMostTicks = 64; // bounds the work per input

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string input = scratch(".jsonl");
    {
        std::FILE* f = std::fopen(input.c_str(), "wb");
        require(f != nullptr);
        require(std::fwrite(data, 1, size, f) == size);
        std::fclose(f);
    }
    dsoc::trace::TraceReader reader;
    if (!reader.open(input)) {
        require(!reader.error().empty());
        return 0;
    }
    const dsoc::trace::TraceHeader& header = reader.header();
    require(header.tick_rate > 0 && header.lookahead_ticks >= 0);
    for (const auto& patch : header.patches) {
        require(patch.width >= 3 && patch.width <= 31 && patch.width % 2 == 1);
        require(patch.height >= 3 && patch.height <= 31 && patch.height % 2 == 1);
        require(patch.points.size() == static_cast<std::size_t>(patch.width * patch.height));
        for (const glm::vec3 p : patch.points) {
            require(finite(p));
        }
    }
    std::vector<dsoc::trace::TraceTick> ticks;
    dsoc::trace::TraceTick tick;
    while (static_cast<int>(ticks.size()) < kMostTicks && reader.next(tick)) {
        require(ticks.empty() || tick.t > ticks.back().t);
        for (const auto& e : tick.entities) {
            require(finite(e.box.min) && finite(e.box.max));
        }
        for (const auto& c : tick.clients) {
            require(finite(c.eye));
            require(!c.arrival || finite(*c.arrival));
        }
        ticks.push_back(tick);
    }
    if (static_cast<int>(ticks.size()) < kMostTicks) {
        require(reader.finished() != !reader.error().empty());
    }

    // Written again and read back: the same header and ticks.
    const std::string output = scratch(".out.jsonl");
    std::string error;
    {
        dsoc::trace::TraceWriter writer;
        require(writer.open(output, header, error));
        for (const auto& t : ticks) {
            require(writer.write_tick(t));
        }
        require(writer.close());
    }
    dsoc::trace::TraceReader again;
    require(again.open(output));
    require(again.header().map == header.map && again.header().policy == header.policy);
    require(again.header().tick_rate == header.tick_rate &&
            again.header().lookahead_ticks == header.lookahead_ticks);
    require(again.header().occluders.size() == header.occluders.size());
    for (std::size_t i = 0; i < header.occluders.size(); ++i) {
        const auto& a = again.header().occluders[i];
        const auto& b = header.occluders[i];
        require(a.id == b.id && a.planes.size() == b.planes.size());
        for (std::size_t k = 0; k < a.planes.size(); ++k) {
            require(a.planes[k].normal == b.planes[k].normal &&
                    a.planes[k].distance == b.planes[k].distance);
        }
    }
    require(again.header().patches.size() == header.patches.size());
    for (std::size_t i = 0; i < header.patches.size(); ++i) {
        const auto& a = again.header().patches[i];
        const auto& b = header.patches[i];
        require(a.width == b.width && a.height == b.height && a.points == b.points);
    }
    for (const auto& t : ticks) {
        require(again.next(tick));
        require(tick.t == t.t && tick.entities.size() == t.entities.size() &&
                tick.clients.size() == t.clients.size());
        for (std::size_t k = 0; k < t.entities.size(); ++k) {
            require(tick.entities[k].id == t.entities[k].id &&
                    tick.entities[k].box.min == t.entities[k].box.min &&
                    tick.entities[k].box.max == t.entities[k].box.max);
        }
        for (std::size_t k = 0; k < t.clients.size(); ++k) {
            const auto& a = tick.clients[k];
            const auto& b = t.clients[k];
            require(a.id == b.id && a.entity == b.entity && a.eye == b.eye &&
                    a.arrival == b.arrival && a.replicated == b.replicated &&
                    a.always == b.always && a.never == b.never && a.heard == b.heard);
        }
    }
    require(!again.next(tick) && again.finished());
    return 0;
}
