#include "ugv/adapters/yaml_guard.hpp"

#include <string>

#include <gtest/gtest.h>

namespace ugv::adapters {
namespace {

constexpr YamlLimits kLimits{1024, 4, true, false};
constexpr YamlLimits kOpenCvLimits{1024, 4, true, true};

std::string errorOf(const std::string& text, const YamlLimits& limits = kLimits)
{
    const auto checked = checkYamlText(text, "t.yaml", limits);
    return checked ? std::string() : checked.error().message();
}

std::string openCvErrorOf(const std::string& text)
{
    return errorOf(text, kOpenCvLimits);
}

TEST(YamlGuard, AWrittenCalibrationIsWithinTheLimits)
{
    constexpr const char* kCalibration = "%YAML:1.0\n---\nschema_version: 1\nK1: !!opencv-matrix\n   rows: 3\n"
                                         "   cols: 3\n   dt: d\n   data: [ 540., 0., 322.,\n       0., 541., 238., 0., "
                                         "0., 1. ]\nmount:\n   height_m: 0.5\n   pitch_deg: -2.5\n"
                                         "note: \"[[[[ x: y: z: 99999999999 # not counted in quotes\"\n";

    EXPECT_EQ(errorOf(kCalibration), "");
}

TEST(YamlGuard, EachKindOfNestingCounts)
{
    EXPECT_NE(errorOf("a: [[[[1]]]]\n").find("t.yaml:1: nested deeper than 4"), std::string::npos);
    EXPECT_NE(errorOf("a: {b: {c: {d: 1}}}\n").find("t.yaml:1: nested deeper"), std::string::npos);
    EXPECT_NE(errorOf("a: b: c: d: e: 1\n").find("t.yaml:1: nested deeper"), std::string::npos);
    EXPECT_NE(errorOf("- - - - - 1\n").find("t.yaml:1: nested deeper"), std::string::npos);
    EXPECT_NE(errorOf("a:\n b:\n  c:\n   d: 1\n").find("t.yaml:4: nested deeper"), std::string::npos);
    EXPECT_EQ(errorOf("a: [[1]]\nb: [[2]]\nc:\n d: 1\n"), ""); // closed levels do not add up
    // A quote inside a plain scalar opens nothing: the brackets after it still count.
    EXPECT_NE(errorOf("a: [x'y, [[[[1]]]]]\n").find("t.yaml:1: nested deeper"), std::string::npos);
    EXPECT_NE(errorOf("a: [x\"y, [[[[1]]]]]\n").find("t.yaml:1: nested deeper"), std::string::npos);
}

TEST(YamlGuard, IntegersBeyondInt32AreRefusedOthersPass)
{
    EXPECT_EQ(errorOf("a: 2147483647\nb: -2147483648\nc: 1e300\nd: 4294967536.5\ne: '4294967536'\nf: v4294967536\n"),
              "");
    EXPECT_NE(errorOf("a: 2147483648\n").find("t.yaml:1: integer 2147483648 does not fit in 32 bits"),
              std::string::npos);
    EXPECT_NE(errorOf("a: -2147483649\n").find("integer -2147483649"), std::string::npos);
    EXPECT_NE(errorOf("a: [1, 00000000004294967536]\n").find("integer 00000000004294967536"), std::string::npos);
}

TEST(YamlGuard, WhatOpenCVLoopsForeverOnIsRefused)
{
    // OpenCV 4.6 never returns from these files (the calibration fuzz target's timeouts, minimised).
    EXPECT_NE(openCvErrorOf("%YAML:1.0\n---a: 1\n--x-\nc\n").find("t.yaml:2: text after the document start '---'"),
              std::string::npos);
    EXPECT_NE(openCvErrorOf("%YAML:1.0\n   dt: d\n\"a  -.\n03\n").find("t.yaml:3: the quoted text at column 1"),
              std::string::npos);
    EXPECT_NE(openCvErrorOf("%YAML:1.\n x:3\nihc-\n.").find("t.yaml:2: 'x:3' is not a 'key: value' line"),
              std::string::npos);
    // ... and what makes it allocate without bound (a 51 GB matrix).
    EXPECT_NE(
        openCvErrorOf("K: !!opencv-matrix\n   rows: 3\n   cols: 100000\n").find("t.yaml:3: matrix size 'cols: 100000'"),
        std::string::npos);
    EXPECT_NE(openCvErrorOf("K: !!opencv-matrix\n   rows: x\n").find("t.yaml:2: matrix size 'rows: x'"),
              std::string::npos);
    EXPECT_NE(openCvErrorOf("K: !!opencv-matrix\n   cols:\xFF 3\n").find("t.yaml:2: byte 0xFF at column 9"),
              std::string::npos);
    EXPECT_NE(openCvErrorOf("K: [ 1, 2,\n  3, x ]\n").find("t.yaml:2: 'x' in a matrix's data"), std::string::npos);
    // What a calibration is: both forms pass.
    EXPECT_EQ(openCvErrorOf("%YAML:1.0\n---\n# a comment\nschema_version: 1\nrectified: 1\nfx: 546.0  # px\n"
                            "note: \"it's # not a comment\"\nname: 'a b'\n"
                            "mount: { height_m: 0.59, pitch_deg: -2.5, roll_deg: 0.0 }\n"
                            "K1: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 5.4e+02, 0., 3.2e+02,\n"
                            "       0., -1.5e-01, .inf, 0., 0., 1. ]\nmount2:\n   height_m: 0.5\n---\n"),
              "");
    // Only for OpenCV: yaml-cpp (the config) reads "--- a: 1" as YAML says.
    EXPECT_EQ(errorOf("--- a: 1\n"), "");
}

TEST(YamlGuard, SizeAndNulAreRefused)
{
    EXPECT_NE(errorOf(std::string(1025, '#')).find("t.yaml: the text is 1025 bytes, more than the 1024"),
              std::string::npos);
    EXPECT_NE(errorOf(std::string("a: 1\nb: \0\n", 10)).find("t.yaml:2: holds a NUL byte"), std::string::npos);
}

TEST(YamlGuard, ReadTextFileRefusesAnOverLongFileBeforeReadingIt)
{
    const auto missing = readTextFile("/nonexistent/x.yaml", 10, "give a file");
    ASSERT_FALSE(missing.has_value());
    EXPECT_EQ(missing.error().where, "/nonexistent/x.yaml");

    const auto large = readTextFile("/proc/self/exe", 10, "give a file");
    ASSERT_FALSE(large.has_value());
    EXPECT_NE(large.error().what.find("more than the 10"), std::string::npos) << large.error().message();
}

} // namespace
} // namespace ugv::adapters
