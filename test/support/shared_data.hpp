#pragma once

/// @file
/// Locating ../shared/data (real stereo data with ground truth) for `data` tests.
/// Order: $UGV_SHARED_DATA, then the path configured at build time (UGV_SHARED_DATA_DEFAULT).

#include <filesystem>
#include <optional>
#include <string>

#include <gtest/gtest.h>

namespace ugv::test {

/// The folder `sub` inside the shared data root, if it exists.
std::optional<std::filesystem::path> sharedData(const std::string& sub);

/// The message a test prints when it skips for want of the data.
std::string sharedDataMissingMessage(const std::string& sub);

} // namespace ugv::test

/// Declares `const std::filesystem::path var` for shared-data folder `sub`, or skips the test with a
/// message saying where it looked and how to point it elsewhere.
#define UGV_REQUIRE_SHARED_DATA(var, sub)                                                                              \
    const auto maybe_##var = ::ugv::test::sharedData(sub);                                                             \
    if (!maybe_##var) {                                                                                                \
        GTEST_SKIP() << ::ugv::test::sharedDataMissingMessage(sub);                                                    \
    }                                                                                                                  \
    const std::filesystem::path var = *maybe_##var
