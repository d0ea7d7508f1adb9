#include "dsoc/cli/progress.hpp"

#include <algorithm>
#include <cmath>
#include <unistd.h>
#include <utility>

namespace dsoc::cli {

ProgressLine::ProgressLine(std::string what)
    : ProgressLine(std::move(what), stderr, isatty(fileno(stderr)) != 0) {}

ProgressLine::ProgressLine(std::string what, std::FILE* out, bool terminal)
    : what_(std::move(what)), out_(out), terminal_(terminal) {}

void ProgressLine::operator()(double fraction, double elapsed_seconds) {
    fraction = std::clamp(fraction, 0.0, 1.0);
    const double eta = fraction > 0.0 ? elapsed_seconds * (1.0 - fraction) / fraction : 0.0;
    const bool done = fraction >= 1.0;
    if (terminal_) {
        std::fprintf(out_, "\r%s: %5.1f%%, %6.1f s elapsed, ETA %6.1f s %s", what_.c_str(),
                     100.0 * fraction, elapsed_seconds, eta, done ? "\n" : "");
    } else {
        const int tenth = static_cast<int>(std::floor(fraction * 10.0));
        if (tenth <= last_tenth_) {
            return;
        }
        last_tenth_ = tenth;
        std::fprintf(out_, "%s: %5.1f%%, %.1f s elapsed, ETA %.1f s\n", what_.c_str(),
                     100.0 * fraction, elapsed_seconds, eta);
    }
    written_ = !done;
    std::fflush(out_);
}

void ProgressLine::restart() {
    if (terminal_ && written_) {
        std::fputc('\n', out_);
        std::fflush(out_);
    }
    written_ = false;
    last_tenth_ = -1;
}

} // namespace dsoc::cli
