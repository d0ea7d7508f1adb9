#pragma once
// How an update entry travels (Snapshot.update_head, update_fields, update_values;
// docs/protocol.md), and a snapshot's update columns held as the packed varints they are
// on the wire, written as the encoder goes. A sender that frames its snapshots with
// encode_snapshot_frame() never holds the updates as protobuf repeated fields, so it neither stores
// them twice nor sizes, serializes or clears them again; the frame's bytes are exactly those of
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

/// Bits of an update entry's field mask.
enum UpdateField : std::uint32_t {
    kFieldX = 1u << 0,
    kFieldY = 1u << 1,
    kFieldZ = 1u << 2,
    kFieldYaw = 1u << 3,
    kFieldPitch = 1u << 4,
    kFieldRebase = 1u << 5, ///< tier changed: the new tier, then all five fields absolute
};

/// The mask bits an update_head holds itself; an entry with any other bit (pitch,
/// rebase) has 0 there and its whole mask in update_fields.
inline constexpr int kHeadFieldBitCount = 4;
inline constexpr std::uint32_t kHeadFields = kFieldX | kFieldY | kFieldZ | kFieldYaw;
static_assert(kHeadFields == (1u << kHeadFieldBitCount) - 1);

/// Whether an entry with field mask `fields` has its mask apart, in update_fields.
[[nodiscard]] constexpr bool mask_apart(std::uint32_t fields) {
    return (fields & ~kHeadFields) != 0;
}

/// The update_head of an entry `id_step` after the previous one's id (the first entry:
/// its id) with field mask `fields`.
[[nodiscard]] constexpr std::uint64_t update_head(std::uint64_t id_step, std::uint32_t fields) {
    return id_step << kHeadFieldBitCount | (mask_apart(fields) ? 0 : fields);
}

/// One update entry of a received snapshot, located: its entity, its field mask and
/// where its values start in update_values.
struct UpdateEntry {
    std::uint32_t id = 0;
    std::uint32_t fields = 0;
    int at = 0;
};

class UpdateColumns {
public:
    /// Empties the columns; their memory is kept, unless it has room for more than twice
    /// the entries added since the last clear() (and kSnapshotSlackEntries,
    /// buffer_room.hpp), when it is given back.
    void clear();
    /// Entries the columns have room for before they grow again.
    [[nodiscard]] std::size_t capacity() const { return capacity_; }
    /// Appends one update entry: its id step (from the previous entry's id, the first
    /// entry's: its id), its UpdateField bits (the head, and the mask apart when
    /// mask_apart()) and its values (at most kMaxValuesPerEntry).
    void add(std::uint32_t id_step, std::uint32_t fields, std::span<const std::int32_t> values) {
        assert(values.size() <= kMaxValuesPerEntry);
        if (count_ == capacity_) {
            grow();
        }
        using google::protobuf::io::CodedOutputStream;
        // Through local pointers: a byte stored through a pointer may be any object's, so
        // the compiler would load the columns' members again after every byte written.
        std::uint8_t* const heads = heads_.bytes.data();
        heads_.used =
            static_cast<std::size_t>(CodedOutputStream::WriteVarint64ToArray(
                                         update_head(id_step, fields), heads + heads_.used) -
                                     heads);
        if (mask_apart(fields)) {
            fields_.used = write_varint(fields, fields_);
        }
        std::uint8_t* const value_bytes = values_.bytes.data();
        std::uint8_t* at = value_bytes + values_.used;
        for (const std::int32_t value : values) {
            at = CodedOutputStream::WriteVarint32ToArray(
                google::protobuf::internal::WireFormatLite::ZigZagEncode32(value), at);
        }
        values_.used = static_cast<std::size_t>(at - value_bytes);
        ++count_;
        assert(heads_.used <= heads_.bytes.size() && fields_.used <= fields_.bytes.size() &&
               values_.used <= values_.bytes.size());
    }

    /// Update entries added since clear().
    [[nodiscard]] std::size_t count() const { return count_; }
    /// Bytes of the masks apart, and of the values, written since clear() (without the
    /// packed fields' tags and lengths).
    [[nodiscard]] std::size_t mask_bytes() const { return fields_.used; }
    [[nodiscard]] std::size_t value_bytes() const { return values_.used; }
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
    /// The most bytes a 32-bit varint takes, and a 64-bit one.
    static constexpr std::size_t kMaxVarintBytes = 5;
    static constexpr std::size_t kMaxVarint64Bytes = 10;

    /// Writes `v` at the end of `to` (which has room) and returns the new length.
    static std::size_t write_varint(std::uint32_t v, Varints& to) {
        std::uint8_t* end = google::protobuf::io::CodedOutputStream::WriteVarint32ToArray(
            v, to.bytes.data() + to.used);
        return static_cast<std::size_t>(end - to.bytes.data());
    }
    /// Room for twice as many entries (at least 64) of the largest size.
    void grow();

    Varints heads_;
    Varints fields_;
    Varints values_;
    std::size_t count_ = 0;
    std::size_t capacity_ = 0; ///< entries of the largest size the columns have room for,
                               ///< counted from empty
};

/// Wire bytes of a snapshot's update columns held as repeated fields (field tags and
/// lengths included): what the updates cost, enters, leaves and the tick left out.
/// UpdateColumns::wire_bytes() of the same entries.
[[nodiscard]] std::size_t update_column_bytes(const pb::Snapshot& snapshot);

/// Appends the bytes of `envelope`, whose body is a snapshot with no update entries of
/// its own, with `columns` as that snapshot's update columns: the bytes protobuf
/// serializes for the envelope whose snapshot holds the same entries as repeated
/// fields. `envelope` is unchanged when this returns (its audit poses and baseline tick,
/// the fields numbered after the columns, are taken out while the fields before them are
/// written, then put back). Returns the number of bytes appended.
std::size_t append_snapshot_envelope(pb::Envelope& envelope, const UpdateColumns& columns,
                                     std::vector<std::uint8_t>& out);

/// Appends one frame (framing.hpp) holding append_snapshot_envelope()'s bytes: those
/// encode_frame() appends for the snapshot holding the same entries as repeated fields.
/// Returns the number of bytes appended (header included).
std::size_t encode_snapshot_frame(pb::Envelope& envelope, const UpdateColumns& columns,
                                  std::vector<std::uint8_t>& out);

} // namespace dsoc::protocol
