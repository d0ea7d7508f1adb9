#pragma once
// Reading a whole (small) file: a settings file, a scenario, a key.

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

namespace dsoc::common {

/// Reads all bytes of file `path` into `text`. Returns "" on success; otherwise why the
/// file cannot be opened (the system's message, e.g. "No such file or directory"),
/// and `text` is unchanged.
[[nodiscard]] inline std::string read_file(const std::string& path, std::string& text) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        return std::strerror(errno);
    }
    std::ostringstream content;
    content << in.rdbuf();
    text = std::move(content).str();
    return "";
}

} // namespace dsoc::common
