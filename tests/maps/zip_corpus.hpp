#pragma once
// A minimal .pk3 (zip) writer for the archive corruption tests: one entry, stored or
// deflated, laid out at known offsets so that a test can damage exactly one field
// or byte. Writes what zip's specification (APPNOTE 6.3) requires and nothing more:
// local header, data, central directory, end of central directory.

#include <zlib.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace dsoc::maps::test {

/// One entry as it is stored: `data` is what lies in the archive (deflated when
/// method == 8), `crc` and `size` describe the uncompressed bytes.
struct ZipEntry {
    std::string name;
    std::uint16_t method = 0; ///< 0 stored, 8 deflated
    std::vector<std::byte> data;
    std::uint32_t crc = 0;
    std::uint32_t size = 0;
};

/// Where the fields a test damages are, in the bytes of a one-entry archive.
struct ZipLayout {
    std::vector<std::byte> bytes;
    std::size_t local_header = 0;   ///< offset of the local file header
    std::size_t data = 0;           ///< offset of the entry's (compressed) data
    std::size_t central_header = 0; ///< offset of its central directory header
    std::size_t end_record = 0;     ///< offset of the end of central directory record

    // Field offsets inside the two headers (APPNOTE 4.3.7 and 4.3.12).
    static constexpr std::size_t kLocalCrc = 14;
    static constexpr std::size_t kLocalCompressedSize = 18;
    static constexpr std::size_t kLocalSize = 22;
    static constexpr std::size_t kCentralCrc = 16;
    static constexpr std::size_t kCentralCompressedSize = 20;
    static constexpr std::size_t kCentralSize = 24;

    [[nodiscard]] std::uint32_t read_u32(std::size_t at) const {
        std::uint32_t v = 0;
        std::memcpy(&v, bytes.data() + at, 4);
        return v;
    }
    void write_u32(std::size_t at, std::uint32_t v) { std::memcpy(bytes.data() + at, &v, 4); }
    /// Sets one 32-bit field in both headers (so that they still agree).
    void set_both(std::size_t local_field, std::size_t central_field, std::uint32_t v) {
        write_u32(local_header + local_field, v);
        write_u32(central_header + central_field, v);
    }
};

inline std::uint32_t crc32_of(const std::vector<std::byte>& bytes) {
    return static_cast<std::uint32_t>(
        ::crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
}

/// Raw deflate (no zlib header), as zip's method 8 stores it.
inline std::vector<std::byte> deflate_raw(const std::vector<std::byte>& in) {
    z_stream z{};
    if (deflateInit2(&z, Z_BEST_COMPRESSION, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
        throw std::runtime_error("deflateInit2 failed");
    }
    std::vector<std::byte> out(deflateBound(&z, static_cast<uLong>(in.size())));
    z.next_in = reinterpret_cast<Bytef*>(const_cast<std::byte*>(in.data()));
    z.avail_in = static_cast<uInt>(in.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = static_cast<uInt>(out.size());
    const int status = deflate(&z, Z_FINISH);
    deflateEnd(&z);
    if (status != Z_STREAM_END) {
        throw std::runtime_error("deflate did not finish");
    }
    out.resize(z.total_out);
    return out;
}

/// An entry holding `content`, deflated (method 8) or stored (method 0).
inline ZipEntry make_entry(std::string name, const std::vector<std::byte>& content,
                           std::uint16_t method) {
    ZipEntry e;
    e.name = std::move(name);
    e.method = method;
    e.data = method == 8 ? deflate_raw(content) : content;
    e.crc = crc32_of(content);
    e.size = static_cast<std::uint32_t>(content.size());
    return e;
}

/// A valid archive holding `entry` alone.
inline ZipLayout write_zip(const ZipEntry& entry) {
    ZipLayout z;
    auto put16 = [&](std::uint16_t v) {
        const auto* p = reinterpret_cast<const std::byte*>(&v);
        z.bytes.insert(z.bytes.end(), p, p + 2);
    };
    auto put32 = [&](std::uint32_t v) {
        const auto* p = reinterpret_cast<const std::byte*>(&v);
        z.bytes.insert(z.bytes.end(), p, p + 4);
    };
    auto put_name = [&] {
        const auto* p = reinterpret_cast<const std::byte*>(entry.name.data());
        z.bytes.insert(z.bytes.end(), p, p + entry.name.size());
    };
    const auto compressed = static_cast<std::uint32_t>(entry.data.size());
    const auto name_size = static_cast<std::uint16_t>(entry.name.size());
    // Local file header, then the data.
    z.local_header = z.bytes.size();
    put32(0x04034b50);
    put16(20); // version needed: 2.0 (deflate)
    put16(0);  // flags
    put16(entry.method);
    put16(0);    // time
    put16(0x21); // date: 1980-01-01
    put32(entry.crc);
    put32(compressed);
    put32(entry.size);
    put16(name_size);
    put16(0); // extra field length
    put_name();
    z.data = z.bytes.size();
    z.bytes.insert(z.bytes.end(), entry.data.begin(), entry.data.end());
    // Central directory: one header.
    z.central_header = z.bytes.size();
    put32(0x02014b50);
    put16(20); // made by
    put16(20); // needed
    put16(0);
    put16(entry.method);
    put16(0);
    put16(0x21);
    put32(entry.crc);
    put32(compressed);
    put32(entry.size);
    put16(name_size);
    put16(0); // extra
    put16(0); // comment
    put16(0); // disk
    put16(0); // internal attributes
    put32(0); // external attributes
    put32(static_cast<std::uint32_t>(z.local_header));
    put_name();
    // End of central directory.
    z.end_record = z.bytes.size();
    put32(0x06054b50);
    put16(0);
    put16(0);
    put16(1);
    put16(1);
    put32(static_cast<std::uint32_t>(z.end_record - z.central_header));
    put32(static_cast<std::uint32_t>(z.central_header));
    put16(0);
    return z;
}

inline void write_file(const std::filesystem::path& path, const std::vector<std::byte>& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    if (!out) {
        throw std::runtime_error("cannot write " + path.string());
    }
}

} // namespace dsoc::maps::test
