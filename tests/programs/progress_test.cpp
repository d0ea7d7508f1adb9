#include "dsoc/cli/progress.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace dsoc::testing {
namespace {

/// What a ProgressLine wrote for 200 calls from 0 to 1.
std::string written(bool terminal) {
    std::FILE* file = std::tmpfile();
    EXPECT_NE(file, nullptr);
    {
        cli::ProgressLine progress("baking oa_dm4", file, terminal);
        for (int k = 0; k <= 200; ++k) {
            progress(k / 200.0, k * 0.5);
        }
    }
    std::string out;
    std::rewind(file);
    for (int c = std::fgetc(file); c != EOF; c = std::fgetc(file)) {
        out += static_cast<char>(c);
    }
    std::fclose(file);
    return out;
}

std::size_t count(const std::string& text, char c) {
    std::size_t n = 0;
    for (const char x : text) {
        n += x == c ? 1 : 0;
    }
    return n;
}

TEST(ProgressLine, ALogGetsALineAtEveryTenthAndNoCarriageReturns) {
    const std::string log = written(false);
    EXPECT_EQ(count(log, '\r'), 0u) << log;
    EXPECT_EQ(count(log, '\n'), 11u) << log; // 0%, 10%, ..., 100%
    EXPECT_NE(log.find("baking oa_dm4: 100.0%, 100.0 s elapsed, ETA 0.0 s\n"), std::string::npos)
        << log;
}

TEST(ProgressLine, ATerminalGetsOneLineRewrittenInPlace) {
    const std::string shown = written(true);
    EXPECT_EQ(count(shown, '\r'), 201u);
    EXPECT_EQ(count(shown, '\n'), 1u); // ended once the work is done
    EXPECT_EQ(shown.back(), '\n');
}

} // namespace
} // namespace dsoc::testing
