#include "dsoc/protocol/update_columns.hpp"

#include "dsoc/protocol/buffer_room.hpp"

#include "dsoc/protocol/framing.hpp"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/wire_format_lite.h>

#include <algorithm>
#include <cassert>
#include <cstring>
#include <optional>

namespace dsoc::protocol {

namespace {

using google::protobuf::internal::WireFormatLite;
using google::protobuf::io::CodedOutputStream;

std::uint32_t length_delimited_tag(int field_number) {
    return WireFormatLite::MakeTag(field_number, WireFormatLite::WIRETYPE_LENGTH_DELIMITED);
}

/// Bytes of a packed field holding `payload` bytes: protobuf writes none when empty.
std::size_t packed_field_bytes(int field_number, std::size_t payload) {
    if (payload == 0) {
        return 0;
    }
    return CodedOutputStream::VarintSize32(length_delimited_tag(field_number)) +
           CodedOutputStream::VarintSize32(static_cast<std::uint32_t>(payload)) + payload;
}

std::uint8_t* write_packed_field(int field_number, std::span<const std::uint8_t> payload,
                                 std::uint8_t* out) {
    if (payload.empty()) {
        return out;
    }
    out = CodedOutputStream::WriteVarint32ToArray(length_delimited_tag(field_number), out);
    out = CodedOutputStream::WriteVarint32ToArray(static_cast<std::uint32_t>(payload.size()), out);
    std::memcpy(out, payload.data(), payload.size());
    return out + payload.size();
}

} // namespace

void UpdateColumns::clear() {
    if (room_oversized(capacity_, count_, kSnapshotSlackEntries)) {
        // buffer_room.hpp: room for more than twice the last snapshot's entries is given
        // back; grow() makes room again from what the next snapshot adds.
        capacity_ = 0;
        for (Varints* column : {&heads_, &fields_, &values_}) {
            std::vector<std::uint8_t>().swap(column->bytes);
        }
    }
    heads_.used = 0;
    fields_.used = 0;
    values_.used = 0;
    count_ = 0;
}

void UpdateColumns::grow() {
    // Room for `capacity_` entries of the largest size from the start: whatever was
    // written takes no more than that, so the rest has room for the entries left.
    capacity_ = std::max<std::size_t>(64, 2 * capacity_);
    heads_.bytes.resize(capacity_ * kMaxVarint64Bytes);
    fields_.bytes.resize(capacity_ * kMaxVarintBytes);
    values_.bytes.resize(capacity_ * kMaxValuesPerEntry * kMaxVarintBytes);
}

std::size_t UpdateColumns::wire_bytes() const {
    return packed_field_bytes(pb::Snapshot::kUpdateHeadFieldNumber, heads_.used) +
           packed_field_bytes(pb::Snapshot::kUpdateFieldsFieldNumber, fields_.used) +
           packed_field_bytes(pb::Snapshot::kUpdateValuesFieldNumber, values_.used);
}

std::uint8_t* UpdateColumns::write(std::uint8_t* out) const {
    out = write_packed_field(pb::Snapshot::kUpdateHeadFieldNumber,
                             {heads_.bytes.data(), heads_.used}, out);
    out = write_packed_field(pb::Snapshot::kUpdateFieldsFieldNumber,
                             {fields_.bytes.data(), fields_.used}, out);
    return write_packed_field(pb::Snapshot::kUpdateValuesFieldNumber,
                              {values_.bytes.data(), values_.used}, out);
}

std::size_t update_column_bytes(const pb::Snapshot& s) {
    std::size_t heads = 0;
    for (const std::uint64_t v : s.update_head()) {
        heads += CodedOutputStream::VarintSize64(v);
    }
    std::size_t fields = 0;
    for (const std::uint32_t v : s.update_fields()) {
        fields += CodedOutputStream::VarintSize32(v);
    }
    std::size_t values = 0;
    for (const std::int32_t v : s.update_values()) {
        values += CodedOutputStream::VarintSize32(WireFormatLite::ZigZagEncode32(v));
    }
    return packed_field_bytes(pb::Snapshot::kUpdateHeadFieldNumber, heads) +
           packed_field_bytes(pb::Snapshot::kUpdateFieldsFieldNumber, fields) +
           packed_field_bytes(pb::Snapshot::kUpdateValuesFieldNumber, values);
}

std::size_t append_snapshot_envelope(pb::Envelope& envelope, const UpdateColumns& columns,
                                     std::vector<std::uint8_t>& out) {
    assert(envelope.has_snapshot());
    pb::Snapshot& snapshot = *envelope.mutable_snapshot();
    assert(snapshot.update_head_size() == 0 && snapshot.update_fields_size() == 0 &&
           snapshot.update_values_size() == 0);
    static_assert(pb::Snapshot::kAuditFieldNumber > pb::Snapshot::kUpdateValuesFieldNumber &&
                      pb::Snapshot::kBaselineTickFieldNumber > pb::Snapshot::kAuditFieldNumber,
                  "the audit poses, then the baseline tick, follow the update columns");
    // Protobuf writes fields in number order: the audit poses (8) and the baseline tick
    // (9) come after the columns (5-7), so they are held aside while the fields before
    // them are written: the poses in `tail` (only on the ticks a client audits), the
    // tick written by hand.
    std::optional<pb::Snapshot> tail;
    if (snapshot.audit_size() > 0) {
        tail.emplace().mutable_audit()->Swap(snapshot.mutable_audit());
    }
    const bool has_baseline = snapshot.has_baseline_tick();
    const std::uint64_t baseline = snapshot.baseline_tick();
    snapshot.clear_baseline_tick();
    using google::protobuf::internal::WireFormatLite;
    const std::size_t baseline_bytes =
        has_baseline ? WireFormatLite::TagSize(pb::Snapshot::kBaselineTickFieldNumber,
                                               WireFormatLite::TYPE_UINT64) +
                           CodedOutputStream::VarintSize64(baseline)
                     : 0;
    const std::size_t head_bytes = snapshot.ByteSizeLong();
    const std::size_t tail_bytes = tail ? tail->ByteSizeLong() : 0;
    const std::size_t body = head_bytes + columns.wire_bytes() + tail_bytes + baseline_bytes;
    const std::uint32_t tag = length_delimited_tag(pb::Envelope::kSnapshotFieldNumber);
    const std::size_t payload = CodedOutputStream::VarintSize32(tag) +
                                CodedOutputStream::VarintSize32(static_cast<std::uint32_t>(body)) +
                                body;
    const std::size_t start = out.size();
    out.resize(start + payload);
    std::uint8_t* p = out.data() + start;
    p = CodedOutputStream::WriteVarint32ToArray(tag, p);
    p = CodedOutputStream::WriteVarint32ToArray(static_cast<std::uint32_t>(body), p);
    p = snapshot.SerializeWithCachedSizesToArray(p);
    p = columns.write(p);
    if (tail) {
        p = tail->SerializeWithCachedSizesToArray(p);
        snapshot.mutable_audit()->Swap(tail->mutable_audit());
    }
    if (has_baseline) {
        p = WireFormatLite::WriteUInt64ToArray(pb::Snapshot::kBaselineTickFieldNumber, baseline, p);
        snapshot.set_baseline_tick(baseline);
    }
    assert(p == out.data() + out.size());
    (void)p;
    return payload;
}

std::size_t encode_snapshot_frame(pb::Envelope& envelope, const UpdateColumns& columns,
                                  std::vector<std::uint8_t>& out) {
    const std::size_t start = out.size();
    out.resize(start + kFrameHeaderBytes);
    const std::size_t payload = append_snapshot_envelope(envelope, columns, out);
    write_frame_header(out.data() + start, static_cast<std::uint32_t>(payload));
    return kFrameHeaderBytes + payload;
}

} // namespace dsoc::protocol
