#pragma once
// A fresh directory for one test's files, removed (with what is in it) at the end.

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace dsoc::testing {

class TempDir {
public:
    /// `name` below the system's temporary directory; emptied if it exists.
    explicit TempDir(const std::string& name)
        : dir_(std::filesystem::temp_directory_path() / name) {
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(dir_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    /// The path of file `name` in the directory (it need not exist).
    [[nodiscard]] std::string path(const std::string& name) const { return (dir_ / name).string(); }
    /// Writes `text` to file `name` in the directory; returns its path.
    std::string write(const std::string& name, const std::string& text) const {
        std::ofstream(path(name)) << text;
        return path(name);
    }

private:
    std::filesystem::path dir_;
};

} // namespace dsoc::testing
