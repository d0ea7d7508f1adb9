#pragma once
// Where a test keeps its files: a fresh directory, removed (with what is in it) at the
// end, or one file's path below the system's temporary directory.

#include <gtest/gtest.h>

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

    [[nodiscard]] const std::filesystem::path& dir() const { return dir_; }
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

/// "<temporary directory>/<stem>-<seed><extension>", with the random seed of this test
/// run: a file of this run's own, so that runs side by side do not share it. Nothing is
/// created; the test removes what it writes there.
inline std::string run_temp_path(const std::string& stem, const std::string& extension) {
    return (std::filesystem::temp_directory_path() /
            (stem + "-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
             extension))
        .string();
}

} // namespace dsoc::testing
