#pragma once
// PNG files through libpng's simplified API (8-bit RGB, no alpha). Errors come back
// as text naming the file and libpng's reason; nothing throws.

#include "dsoc/inspect/image.hpp"

#include <string>

namespace dsoc::inspect {

/// Writes `image` (non-empty) to `path`, replacing it. Empty on success, else why not.
[[nodiscard]] std::string write_png(const Image& image, const std::string& path);

/// Reads any PNG libpng can decode (grey, palette, alpha: converted to 8-bit RGB,
/// alpha composited on black) into `out`. Empty on success, else why not.
[[nodiscard]] std::string read_png(const std::string& path, Image& out);

} // namespace dsoc::inspect
