#pragma once
// What a renderer's image looks like to a user: written as a PNG file and decoded again.

#include "dsoc/inspect/png_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace dsoc::inspect::testing {

/// `image` written to `file_name` in the temporary directory, read back and the file
/// removed. A failure to write or read fails the test and gives an empty image.
inline Image through_png(const Image& image, const std::string& file_name) {
    const std::string path = (std::filesystem::temp_directory_path() / file_name).string();
    Image decoded;
    const std::string written = write_png(image, path);
    EXPECT_EQ(written, "");
    if (written.empty()) {
        EXPECT_EQ(read_png(path, decoded), "");
    }
    std::filesystem::remove(path);
    return decoded;
}

} // namespace dsoc::inspect::testing
