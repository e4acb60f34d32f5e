#include <gtest/gtest.h>
#include "bem/version.hpp"
TEST(Version, NonEmpty) { EXPECT_STRNE(bem::version(), ""); }
