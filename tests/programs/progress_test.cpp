#include "dsoc/cli/progress.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace dsoc::testing {
namespace {

/// What a ProgressLine wrote for 200 calls from 0 to 1, after `false_starts` tries that
/// gave up at 35% (restart() and a message line after each).
std::string written(bool terminal, int false_starts = 0) {
    std::FILE* file = std::tmpfile();
    EXPECT_NE(file, nullptr);
    {
        cli::ProgressLine progress("baking oa_dm4", file, terminal);
        for (int s = 0; s < false_starts; ++s) {
            for (int k = 0; k <= 70; ++k) {
                progress(k / 200.0, k * 0.5);
            }
            progress.restart();
            std::fputs("given up\n", file);
        }
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

TEST(ProgressLine, AWorkStartedOverIsReportedFromZeroAfterTheMessageOnItsOwnLine) {
    const std::string log = written(false, 2);
    EXPECT_EQ(count(log, '\n'), 2u * (4 + 1) + 11u) << log; // 0-30% and the message, twice
    EXPECT_NE(log.find("30.0 s elapsed, ETA 70.0 s\ngiven up\nbaking oa_dm4:   0.0%"),
              std::string::npos)
        << log;
    const std::string shown = written(true, 2);
    EXPECT_NE(shown.find(" \ngiven up\n\rbaking oa_dm4:   0.0%"), std::string::npos) << shown;
    EXPECT_EQ(count(shown, '\n'), 2u * 2 + 1u); // each try's line ended, each message, the end
}

} // namespace
} // namespace dsoc::testing
