#include "dsoc/inspect/png_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace dsoc::inspect {
namespace {

std::string temp_path(const std::string& name) {
    return (std::filesystem::temp_directory_path() /
            ("dsoc_inspect_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
             "_" + name))
        .string();
}

TEST(PngIo, RoundTripKeepsSizeAndEveryPixel) {
    Image image(37, 11, Rgb{1, 2, 3});
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            image.set(x, y,
                      Rgb{static_cast<std::uint8_t>(x * 7), static_cast<std::uint8_t>(y * 23),
                          static_cast<std::uint8_t>((x + y) % 256)});
        }
    }
    const std::string path = temp_path("round_trip.png");
    ASSERT_EQ(write_png(image, path), "");
    Image back;
    ASSERT_EQ(read_png(path, back), "");
    std::filesystem::remove(path);
    ASSERT_EQ(back.width(), 37);
    ASSERT_EQ(back.height(), 11);
    EXPECT_EQ(back.pixels(), image.pixels());
}

TEST(PngIo, ErrorsNameTheFile) {
    Image out;
    const std::string missing = temp_path("does_not_exist.png");
    const std::string error = read_png(missing, out);
    EXPECT_NE(error.find(missing), std::string::npos) << error;
    EXPECT_TRUE(out.empty());

    const std::string not_png = temp_path("not_a_png.png");
    {
        std::FILE* f = std::fopen(not_png.c_str(), "wb");
        ASSERT_NE(f, nullptr);
        std::fputs("this is not a PNG file", f);
        std::fclose(f);
    }
    EXPECT_NE(read_png(not_png, out).find(not_png), std::string::npos);
    std::filesystem::remove(not_png);

    EXPECT_NE(write_png(Image(4, 4), "/nonexistent-dir/x.png").find("/nonexistent-dir/x.png"),
              std::string::npos);
    EXPECT_NE(write_png(Image(), temp_path("empty.png")), "");
}

TEST(Image, DrawingClipsAndFillsConvexPolygons) {
    Image image(10, 10);
    image.fill_rect(-5, -5, 2, 2, Rgb{9, 9, 9}); // clipped to (0..2, 0..2)
    EXPECT_EQ(image.at(0, 0), (Rgb{9, 9, 9}));
    EXPECT_EQ(image.at(2, 2), (Rgb{9, 9, 9}));
    EXPECT_EQ(image.at(3, 3), (Rgb{}));
    image.draw_line(-100, 5, 100, 5, Rgb{1, 1, 1});
    for (int x = 0; x < 10; ++x) {
        EXPECT_EQ(image.at(x, 5), (Rgb{1, 1, 1}));
    }
    // A triangle over the lower-right half: centres with x >= y are inside.
    Image tri(8, 8);
    const glm::vec2 pts[] = {{0.0f, 0.0f}, {8.0f, 0.0f}, {8.0f, 8.0f}};
    tri.fill_convex(pts, Rgb{5, 5, 5});
    EXPECT_EQ(tri.at(6, 1), (Rgb{5, 5, 5}));
    EXPECT_EQ(tri.at(1, 6), (Rgb{}));
    EXPECT_THROW(Image(0, 3), std::invalid_argument);
    EXPECT_THROW(Image(Image::kMaxSide + 1, 3), std::invalid_argument);
}

} // namespace
} // namespace dsoc::inspect
