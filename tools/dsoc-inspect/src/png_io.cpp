#include "dsoc/inspect/png_io.hpp"

#include <png.h>

#include <cstring>
#include <vector>

namespace dsoc::inspect {

static_assert(sizeof(Rgb) == 3, "Rgb must be three packed bytes: it is handed to libpng as is");

std::string write_png(const Image& image, const std::string& path) {
    if (image.empty()) {
        return "cannot write " + path + ": the image is empty";
    }
    png_image png;
    std::memset(&png, 0, sizeof png);
    png.version = PNG_IMAGE_VERSION;
    png.width = static_cast<png_uint_32>(image.width());
    png.height = static_cast<png_uint_32>(image.height());
    png.format = PNG_FORMAT_RGB;
    if (png_image_write_to_file(&png, path.c_str(), 0, image.pixels().data(), 0, nullptr) == 0) {
        std::string why = png.message;
        png_image_free(&png);
        return "cannot write " + path + ": " + why;
    }
    return {};
}

std::string read_png(const std::string& path, Image& out) {
    png_image png;
    std::memset(&png, 0, sizeof png);
    png.version = PNG_IMAGE_VERSION;
    if (png_image_begin_read_from_file(&png, path.c_str()) == 0) {
        std::string why = png.message;
        png_image_free(&png);
        return "cannot read " + path + ": " + why;
    }
    if (png.width < 1 || png.height < 1 || png.width > Image::kMaxSide ||
        png.height > Image::kMaxSide) {
        png_image_free(&png);
        return "cannot read " + path + ": size " + std::to_string(png.width) + " x " +
               std::to_string(png.height) + " is outside 1.." + std::to_string(Image::kMaxSide);
    }
    png.format = PNG_FORMAT_RGB;
    Image image(static_cast<int>(png.width), static_cast<int>(png.height));
    std::vector<Rgb> buffer(static_cast<std::size_t>(png.width) * png.height);
    const png_color black{0, 0, 0};
    if (png_image_finish_read(&png, &black, buffer.data(), 0, nullptr) == 0) {
        std::string why = png.message;
        png_image_free(&png);
        return "cannot decode " + path + ": " + why;
    }
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            image.set(
                x, y,
                buffer[static_cast<std::size_t>(y) * png.width + static_cast<std::size_t>(x)]);
        }
    }
    out = std::move(image);
    return {};
}

} // namespace dsoc::inspect
