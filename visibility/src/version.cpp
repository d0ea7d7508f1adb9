#include "dsoc/visibility/version.hpp"

namespace dsoc {

const char* version() noexcept {
    return DSOC_VERSION_STRING;
}

} // namespace dsoc
