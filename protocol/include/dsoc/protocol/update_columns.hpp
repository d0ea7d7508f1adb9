#pragma once
// A snapshot's three update columns (Snapshot.update_id, update_fields, update_values;
// docs/protocol.md) held as the packed varints they are on the wire, written as the
// encoder goes. A sender that frames its snapshots with encode_snapshot_frame() never
// holds the updates as protobuf repeated fields, so it neither stores them twice nor
// sizes, serializes or clears them again; the frame's bytes are exactly those of
// encode_frame() on the snapshot holding them as repeated fields.
//
// Threading: one per connection (or per thread); not thread-safe.

#include "dsoc/protocol/messages.hpp"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/wire_format_lite.h>

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace dsoc::protocol {

class UpdateColumns {
public:
    /// Empties the columns; their memory is kept.
    void clear();
    /// Appends one update entry: its id (as a delta from the previous entry's, the
    /// first absolute), its UpdateField bits and its values (at most
    /// kMaxValuesPerEntry).
    void add(std::uint32_t id_delta, std::uint32_t fields, std::span<const std::int32_t> values) {
        assert(values.size() <= kMaxValuesPerEntry);
        if (count_ == capacity_) {
            grow();
        }
        ids_.used = write_varint(id_delta, ids_);
        fields_.used = write_varint(fields, fields_);
        for (const std::int32_t value : values) {
            values_.used = write_varint(
                google::protobuf::internal::WireFormatLite::ZigZagEncode32(value), values_);
        }
        ++count_;
        assert(ids_.used <= ids_.bytes.size() && fields_.used <= fields_.bytes.size() &&
               values_.used <= values_.bytes.size());
    }

    /// Update entries added since clear().
    [[nodiscard]] std::size_t count() const { return count_; }
    /// Wire bytes of the three packed fields, tags and lengths included (an empty
    /// column costs nothing): update_column_bytes() of the same snapshot.
    [[nodiscard]] std::size_t wire_bytes() const;
    /// Writes the three fields (5, 6, 7, as protobuf orders them) at `out`, which has
    /// room for wire_bytes(); returns the end of what was written.
    std::uint8_t* write(std::uint8_t* out) const;

    /// The most values one update entry carries (a rebase: the tier and five fields).
    static constexpr std::size_t kMaxValuesPerEntry = 6;

private:
    /// Varints back to back; `bytes.size()` is capacity (grown, never shrunk, so that an
    /// append costs no zero-fill), `used` the written length.
    struct Varints {
        std::vector<std::uint8_t> bytes;
        std::size_t used = 0;
    };
    /// The most bytes a 32-bit varint takes.
    static constexpr std::size_t kMaxVarintBytes = 5;

    /// Writes `v` at the end of `to` (which has room) and returns the new length.
    static std::size_t write_varint(std::uint32_t v, Varints& to) {
        std::uint8_t* end = google::protobuf::io::CodedOutputStream::WriteVarint32ToArray(
            v, to.bytes.data() + to.used);
        return static_cast<std::size_t>(end - to.bytes.data());
    }
    /// Room for twice as many entries (at least 64) of the largest size.
    void grow();

    Varints ids_;
    Varints fields_;
    Varints values_;
    std::size_t count_ = 0;
    std::size_t capacity_ = 0; ///< entries of the largest size the columns have room for,
                               ///< counted from empty
};

/// Wire bytes of a snapshot's update columns held as repeated fields (field tags and
/// lengths included; an acknowledged-delta snapshot's update_head among them): what the
/// updates cost, enters, leaves and the tick left out. UpdateColumns::wire_bytes() of
/// the same entries.
[[nodiscard]] std::size_t update_column_bytes(const pb::Snapshot& snapshot);

/// Appends one frame (framing.hpp) holding `envelope`, whose body is a snapshot with
/// no update entries of its own, with `columns` as that snapshot's update columns;
/// the bytes are those encode_frame() appends for the snapshot holding the same
/// entries as repeated fields. `envelope` is unchanged when this returns (its audit
/// poses are moved aside while the fields before them are written). Returns the
/// number of bytes appended (header included).
std::size_t encode_snapshot_frame(pb::Envelope& envelope, const UpdateColumns& columns,
                                  std::vector<std::uint8_t>& out);

} // namespace dsoc::protocol
