// The correlator's mode names: the canonical ones, the alias `improved` of pose-corrected, and unknown names.

#include "ugv/correlator/mode.hpp"

#include <gtest/gtest.h>

namespace ugv::correlator {
namespace {

TEST(CorrelatorMode, EachCanonicalNameParsesBackToItsMode)
{
    for (const Mode mode : {Mode::Original, Mode::PoseCorrected}) {
        EXPECT_EQ(parseMode(modeName(mode)), mode) << modeName(mode);
    }
}

TEST(CorrelatorMode, ImprovedIsAnAliasOfPoseCorrected)
{
    EXPECT_EQ(parseMode("improved"), Mode::PoseCorrected);
    EXPECT_STREQ(modeName(Mode::PoseCorrected), "pose-corrected");
}

TEST(CorrelatorMode, OtherNamesAreRefused)
{
    for (const char* name : {"", "fancy", "Improved", "pose_corrected", "original "}) {
        EXPECT_FALSE(parseMode(name).has_value()) << '"' << name << '"';
    }
}

} // namespace
} // namespace ugv::correlator
