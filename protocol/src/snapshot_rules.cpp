#include "snapshot_rules.hpp"

namespace dsoc::protocol {

std::optional<SnapshotProblem> read_update_entries(const pb::Snapshot& s,
                                                   std::vector<UpdateEntry>& entries) {
    entries.clear();
    const int count = s.update_head_size();
    int v = 0;
    int masks_apart = 0;
    std::uint64_t id = 0;
    for (int i = 0; i < count; ++i) {
        const std::uint64_t head = s.update_head(i);
        const std::uint64_t step = head >> kHeadFieldBitCount;
        id = i == 0 ? step : id + step;
        const auto where = [&] {
            return "update entry " + std::to_string(i) + " (" +
                   entity_name(static_cast<std::uint32_t>(id)) + ")";
        };
        if ((i > 0 && step == 0) || id > 0xffffffffu) {
            return SnapshotProblem{"malformed_update", where() + ": ids must increase"};
        }
        auto fields = static_cast<std::uint32_t>(head & kHeadFields);
        if (fields == 0) {
            if (masks_apart == s.update_fields_size()) {
                return SnapshotProblem{"malformed_update", where() + ": update_fields ends early"};
            }
            fields = s.update_fields(masks_apart++);
            if (!mask_apart(fields)) { // one way to write each mask
                return SnapshotProblem{"malformed_update", where() + ": mask " +
                                                               std::to_string(fields) +
                                                               " belongs in update_head"};
            }
        }
        if (!valid_update_fields(fields)) {
            return SnapshotProblem{"malformed_update",
                                   where() + ": bad field mask " + std::to_string(fields)};
        }
        if (s.update_values_size() - v < update_value_count(fields)) {
            return SnapshotProblem{"malformed_update", where() + ": update_values ends early"};
        }
        entries.push_back({static_cast<std::uint32_t>(id), fields, v});
        v += update_value_count(fields);
    }
    if (masks_apart != s.update_fields_size()) {
        return SnapshotProblem{"malformed_update",
                               std::to_string(s.update_fields_size() - masks_apart) +
                                   " update_fields left over"};
    }
    if (v != s.update_values_size()) {
        return SnapshotProblem{"malformed_update", std::to_string(s.update_values_size() - v) +
                                                       " update_values left over"};
    }
    return std::nullopt;
}

} // namespace dsoc::protocol
