#include "dsoc/maps/pk3.hpp"

#include <zip.h>

#include <algorithm>
#include <cctype>
#include <memory>

namespace dsoc::maps {
namespace {

struct ZipCloser {
    void operator()(zip_t* archive) const { zip_discard(archive); }
};
/// For error paths only (a failure is already being reported); the success path
/// closes with zip_fclose() itself and checks its status.
struct ZipFileCloser {
    void operator()(zip_file_t* file) const { zip_fclose(file); }
};
using ZipPtr = std::unique_ptr<zip_t, ZipCloser>;

Result<ZipPtr> open_archive(const std::filesystem::path& pk3) {
    int code = 0;
    zip_t* archive = zip_open(pk3.c_str(), ZIP_RDONLY | ZIP_CHECKCONS, &code);
    if (archive == nullptr) {
        zip_error_t error;
        zip_error_init_with_code(&error, code);
        std::string what = std::string("cannot open archive: ") + zip_error_strerror(&error);
        zip_error_fini(&error);
        return LoadError{pk3.string(), "", std::move(what)};
    }
    return ZipPtr(archive);
}

/// What a libzip error code means for an entry being read, in words.
std::string failure_text(int zip_code, const char* libzip_text) {
    switch (zip_code) {
    case ZIP_ER_CRC:
        return "CRC-32 mismatch: the entry's data does not match its checksum (damaged "
               "archive)";
    case ZIP_ER_COMPRESSED_DATA:
    case ZIP_ER_ZLIB:
        return std::string("compressed data is invalid (damaged archive): ") + libzip_text;
    case ZIP_ER_INCONS:
        return std::string("inconsistent entry (damaged archive): ") + libzip_text;
    case ZIP_ER_EOF:
        return "the archive ends inside the entry (truncated archive)";
    default:
        return std::string("cannot read entry: ") + libzip_text;
    }
}

std::string read_failure(zip_file_t* file) {
    zip_error_t* error = zip_file_get_error(file);
    return failure_text(zip_error_code_zip(error), zip_error_strerror(error));
}

std::string lower(std::string_view text) {
    std::string out(text);
    std::transform(out.begin(), out.end(), out.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return out;
}

/// Entry `index` (named `name`) of the open archive `zip`, read whole as read_pk3_entry()
/// promises.
Result<std::vector<std::byte>> read_entry(zip_t* zip, const std::filesystem::path& pk3,
                                          const std::string& name, zip_int64_t index) {
    zip_stat_t stat;
    zip_stat_init(&stat);
    if (zip_stat_index(zip, static_cast<zip_uint64_t>(index), 0, &stat) != 0 ||
        (stat.valid & ZIP_STAT_SIZE) == 0) {
        return LoadError{pk3.string(), name,
                         std::string("cannot stat entry: ") + zip_strerror(zip)};
    }
    if (stat.size > kMaxPk3EntryBytes) {
        return LoadError{pk3.string(), name,
                         "entry is " + std::to_string(stat.size) + " bytes, over the limit of " +
                             std::to_string(kMaxPk3EntryBytes)};
    }
    std::unique_ptr<zip_file_t, ZipFileCloser> file(
        zip_fopen_index(zip, static_cast<zip_uint64_t>(index), 0));
    if (!file) {
        return LoadError{pk3.string(), name,
                         std::string("cannot open entry: ") + zip_strerror(zip)};
    }
    std::vector<std::byte> bytes(static_cast<std::size_t>(stat.size));
    std::size_t done = 0;
    while (done < bytes.size()) {
        const zip_int64_t got = zip_fread(file.get(), bytes.data() + done, bytes.size() - done);
        if (got < 0) {
            return LoadError{pk3.string(), name, read_failure(file.get())};
        }
        if (got == 0) {
            return LoadError{pk3.string(), name,
                             "size mismatch: the entry ends after " + std::to_string(done) +
                                 " of the " + std::to_string(bytes.size()) +
                                 " bytes its directory declares (damaged archive)"};
        }
        done += static_cast<std::size_t>(got);
    }
    // Read to the end: libzip checks the CRC-32 only when a read reaches the end of
    // the entry, and an entry that goes on past its declared size is damaged too.
    std::byte extra{};
    const zip_int64_t tail = zip_fread(file.get(), &extra, 1);
    if (tail < 0) {
        return LoadError{pk3.string(), name, read_failure(file.get())};
    }
    if (tail > 0) {
        return LoadError{pk3.string(), name,
                         "size mismatch: the entry holds more than the " +
                             std::to_string(bytes.size()) +
                             " bytes its directory declares (damaged archive)"};
    }
    const int closed = zip_fclose(file.release());
    if (closed != 0) {
        zip_error_t error;
        zip_error_init_with_code(&error, closed);
        std::string what = failure_text(closed, zip_error_strerror(&error));
        zip_error_fini(&error);
        return LoadError{pk3.string(), name, std::move(what)};
    }
    return bytes;
}

/// The entries directly in `folder` whose names end in `extension` (both matched
/// case-insensitively): each one's full name in the archive and its index, sorted by name.
std::vector<std::pair<std::string, zip_int64_t>> entries_in(zip_t* zip, std::string_view folder,
                                                            std::string_view extension) {
    const zip_int64_t count = zip_get_num_entries(zip, 0);
    const std::string prefix = lower(folder);
    const std::string suffix = lower(extension);
    std::vector<std::pair<std::string, zip_int64_t>> found;
    for (zip_int64_t i = 0; i < count; ++i) {
        const char* raw = zip_get_name(zip, static_cast<zip_uint64_t>(i), 0);
        if (raw == nullptr) {
            continue;
        }
        const std::string name = lower(raw);
        if (name.size() > prefix.size() + suffix.size() && name.starts_with(prefix) &&
            name.ends_with(suffix) && name.find('/', prefix.size()) == std::string::npos) {
            found.emplace_back(raw, i);
        }
    }
    std::sort(found.begin(), found.end());
    return found;
}

} // namespace

Result<std::vector<std::byte>> read_pk3_entry(const std::filesystem::path& pk3,
                                              std::string_view entry) {
    auto archive = open_archive(pk3);
    if (!archive) {
        return archive.error();
    }
    zip_t* zip = archive.value().get();
    const std::string name(entry);
    const zip_int64_t index = zip_name_locate(zip, name.c_str(), ZIP_FL_NOCASE);
    if (index < 0) {
        return LoadError{pk3.string(), name, "no such entry in the archive"};
    }
    return read_entry(zip, pk3, name, index);
}

Result<std::vector<Pk3EntryRead>> read_pk3_entries_in(const std::filesystem::path& pk3,
                                                      std::string_view folder,
                                                      std::string_view extension) {
    auto archive = open_archive(pk3);
    if (!archive) {
        return archive.error();
    }
    zip_t* zip = archive.value().get();
    std::vector<Pk3EntryRead> out;
    for (const auto& [name, index] : entries_in(zip, folder, extension)) {
        out.push_back({name, read_entry(zip, pk3, name, index)});
    }
    return out;
}

Result<std::vector<std::string>> list_pk3_entries_in(const std::filesystem::path& pk3,
                                                     std::string_view folder,
                                                     std::string_view extension) {
    auto archive = open_archive(pk3);
    if (!archive) {
        return archive.error();
    }
    std::vector<std::string> names;
    for (const auto& [name, index] : entries_in(archive.value().get(), folder, extension)) {
        names.push_back(name.substr(folder.size(), name.size() - folder.size() - extension.size()));
    }
    return names;
}

Result<std::vector<std::string>> list_pk3_maps(const std::filesystem::path& pk3) {
    return list_pk3_entries_in(pk3, "maps/", ".bsp");
}

} // namespace dsoc::maps
