#include "dsoc/maps/load_error.hpp"

namespace dsoc::maps {

std::string LoadError::message() const {
    std::string out = file.empty() ? std::string("<memory>") : file;
    if (!lump.empty()) {
        out += ": ";
        out += lump;
    }
    out += ": ";
    out += what;
    return out;
}

} // namespace dsoc::maps
