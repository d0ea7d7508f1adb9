#include "dsoc/visibility/version.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

TEST(Version, IsSemanticVersion) {
    const std::string v = dsoc::version();
    EXPECT_EQ(std::count(v.begin(), v.end(), '.'), 2) << v;
}
