#pragma once
// The trace input of dsoc-inspect: a replication trace
// (docs/replication-trace.md) read with dsoc::trace::TraceReader. A trace
// records eyes, boxes and replication sets, not TBVs or reachable regions, so its
// views hold replicated_visible / replicated_lookahead (split by the occluder culler
// from the eye, over the trace's own occluders) and not_replicated, and an empty
// eye region. replicated_lookahead there means "hidden from the present eye": the
// trace cannot tell lookahead from a held entity.

#include "dsoc/inspect/client_view.hpp"
#include "dsoc/inspect/replicated_classifier.hpp"
#include "dsoc/trace/trace_reader.hpp"
#include "dsoc/visibility/convex_polyhedron.hpp"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace dsoc::inspect {

class TraceSource {
public:
    /// Opens the trace and turns its occluders into polyhedra. False with `error`
    /// set (file, line, what) when the file or an occluder is unusable.
    [[nodiscard]] bool open(const std::string& path, std::string& error);

    [[nodiscard]] const trace::TraceHeader& header() const { return reader_.header(); }
    [[nodiscard]] const std::vector<visibility::ConvexPolyhedron>& occluders() const {
        return occluders_;
    }
    /// Union of the occluders' bounds (the plan's extent; fixed once open() returns).
    [[nodiscard]] const visibility::Aabb& bounds() const { return bounds_; }
    [[nodiscard]] const std::shared_ptr<const visibility::OccluderScene>& scene() const {
        return scene_;
    }

    /// Reads tick lines until one with t >= `min_tick` lists the client `client`
    /// (std::nullopt: the first client listed) and fills `view` from it. False at the
    /// end of the trace (error empty) or on a bad line (error says where and why).
    [[nodiscard]] bool next_view(std::uint64_t min_tick, std::optional<std::uint32_t> client,
                                 ClientView& view, std::string& error);

private:
    trace::TraceReader reader_;
    std::vector<visibility::ConvexPolyhedron> occluders_;
    visibility::Aabb bounds_;
    std::shared_ptr<const visibility::OccluderScene> scene_;
    std::unique_ptr<ReplicatedClassifier> classifier_;
    trace::TraceTick tick_;
};

} // namespace dsoc::inspect
