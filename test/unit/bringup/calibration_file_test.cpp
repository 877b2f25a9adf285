#include "ugv/adapters/calibration_file.hpp"

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

#include "run_command.hpp"
#include "test_rig.hpp"

namespace {

using ugv::test::readText;
using ugv::test::writeText;

using ugv::adapters::loadCalibration;
using ugv::adapters::saveCalibration;
using ugv::vision::StereoCalibration;

std::filesystem::path tempPath(const std::string& name)
{
    const auto dir = std::filesystem::temp_directory_path() / "ugv-calibration-test";
    std::filesystem::create_directories(dir);
    return dir / name;
}

/// The tests' distorted pair with everything a calibration file holds.
StereoCalibration makeFull()
{
    StereoCalibration c = ugv::test::distortedCalibration();
    c.E = cv::Mat::eye(3, 3, CV_64F);
    c.F = cv::Mat::eye(3, 3, CV_64F);
    c.rmsPx = 0.21;
    c.epipolarPx = 0.26;
    c.rectifiedDyPx = 0.12;
    c.pairsUsed = 13;
    c.pairsRejected = 1;
    return c;
}

/// Saves a valid full calibration, applies `edit` to its text and loads it; returns the error message.
std::string loadEditedFull(const std::string& name, const std::string& from, const std::string& to)
{
    const auto path = tempPath(name);
    EXPECT_TRUE(saveCalibration(path.string(), makeFull()).has_value());
    std::string text = readText(path);
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) {
        text.replace(at, from.size(), to);
    }
    writeText(path, text);
    const auto loaded = loadCalibration(path.string());
    EXPECT_FALSE(loaded.has_value());
    return loaded.has_value() ? std::string() : loaded.error().message();
}

constexpr const char* kRectified = "%YAML:1.0\n---\nschema_version: 1\nrectified: 1\nimage_width: 640\n"
                                   "image_height: 480\nfx: 500.\nfy: 501.\ncx: 320.\ncy: 240.\nbaseline_m: 0.12\n";

std::string loadRectifiedText(const std::string& name, const std::string& text)
{
    const auto path = tempPath(name);
    writeText(path, text);
    const auto loaded = loadCalibration(path.string());
    EXPECT_FALSE(loaded.has_value());
    return loaded.has_value() ? std::string() : loaded.error().message();
}

std::string replaced(std::string text, const std::string& from, const std::string& to)
{
    text.replace(text.find(from), from.size(), to);
    return text;
}

TEST(CalibrationFile, FullFormRoundTrips)
{
    const auto path = tempPath("full.yaml");
    StereoCalibration original = makeFull();
    original.mount = ugv::vision::Mount{0.45, 12.0, -1.5};

    ASSERT_TRUE(saveCalibration(path.string(), original).has_value());
    const auto loaded = loadCalibration(path.string());

    ASSERT_TRUE(loaded.has_value()) << loaded.error().message();
    EXPECT_EQ(loaded->imageSize, original.imageSize);
    for (const auto& [a, b] : {std::pair{&loaded->K1, &original.K1},
                               {&loaded->D2, &original.D2},
                               {&loaded->R, &original.R},
                               {&loaded->T, &original.T},
                               {&loaded->P2, &original.P2},
                               {&loaded->Q, &original.Q}}) {
        EXPECT_LE(cv::norm(*a, *b, cv::NORM_INF), 1e-12);
    }
    EXPECT_DOUBLE_EQ(loaded->rmsPx, 0.21);
    EXPECT_DOUBLE_EQ(loaded->rectifiedDyPx, 0.12);
    EXPECT_EQ(loaded->pairsUsed, 13);
    EXPECT_EQ(loaded->pairsRejected, 1);
    EXPECT_FALSE(loaded->rectified);
    ASSERT_TRUE(loaded->mount.has_value());
    EXPECT_DOUBLE_EQ(loaded->mount->heightM, 0.45);
    EXPECT_DOUBLE_EQ(loaded->mount->pitchDeg, 12.0);
    EXPECT_DOUBLE_EQ(loaded->mount->rollDeg, -1.5);
}

TEST(CalibrationFile, RectifiedFormRoundTrips)
{
    const auto path = tempPath("rectified.yaml");
    const StereoCalibration original =
        ugv::vision::makeRectifiedCalibration(cv::Size(640, 480), 500.0, 501.0, 320.0, 240.0, 0.12);

    ASSERT_TRUE(saveCalibration(path.string(), original).has_value());
    const auto loaded = loadCalibration(path.string());

    ASSERT_TRUE(loaded.has_value()) << loaded.error().message();
    EXPECT_TRUE(loaded->rectified);
    EXPECT_DOUBLE_EQ(loaded->baselineM(), 0.12);
    EXPECT_DOUBLE_EQ(loaded->rectifiedFocalPx(), 500.0);
    EXPECT_DOUBLE_EQ(loaded->P2.at<double>(0, 3), -500.0 * 0.12);
    EXPECT_FALSE(loaded->mount.has_value());
}

TEST(CalibrationFile, TheRightCamerasPrincipalPointRoundTripsWhenItIsElsewhere)
{
    const auto path = tempPath("rectified-doffs.yaml");
    const StereoCalibration original =
        ugv::vision::makeRectifiedCalibration(cv::Size(741, 497), 999.421, 999.421, 294.182, 252.932, 0.193001, 326.96);

    ASSERT_TRUE(saveCalibration(path.string(), original).has_value());
    EXPECT_NE(readText(path).find("cx_right: 3.269"), std::string::npos) << readText(path);
    const auto loaded = loadCalibration(path.string());

    ASSERT_TRUE(loaded.has_value()) << loaded.error().message();
    EXPECT_DOUBLE_EQ(loaded->P1.at<double>(0, 2), 294.182);
    EXPECT_DOUBLE_EQ(loaded->P2.at<double>(0, 2), 326.96);
    EXPECT_DOUBLE_EQ(loaded->K2.at<double>(0, 2), 326.96);
    // Without it the right camera's is the left's, and the file does not name it.
    ASSERT_TRUE(saveCalibration(path.string(), ugv::vision::makeRectifiedCalibration(cv::Size(640, 480), 500.0, 501.0,
                                                                                     320.0, 240.0, 0.12))
                    .has_value());
    EXPECT_EQ(readText(path).find("cx_right"), std::string::npos) << readText(path);
}

TEST(CalibrationFile, ARightPrincipalPointOutsideTheImageIsNamed)
{
    const std::string message =
        loadRectifiedText("cx-right.yaml", replaced(kRectified, "baseline_m: 0.12", "baseline_m: 0.12\ncx_right: 900"));
    EXPECT_NE(message.find("cx-right.yaml: cx_right"), std::string::npos) << message;
    EXPECT_NE(message.find("leave it out when it equals cx"), std::string::npos) << message;
}

TEST(CalibrationFile, HandWrittenRectifiedFormNeedsOnlyItsKeys)
{
    const auto path = tempPath("hand.yaml");
    writeText(path, std::string(kRectified) + "mount: { height_m: 0.6, pitch_deg: -10, roll_deg: 2 }\n");

    const auto loaded = loadCalibration(path.string());

    ASSERT_TRUE(loaded.has_value()) << loaded.error().message();
    EXPECT_DOUBLE_EQ(loaded->P1.at<double>(1, 1), 501.0);
    ASSERT_TRUE(loaded->mount.has_value());
    EXPECT_DOUBLE_EQ(loaded->mount->pitchDeg, -10.0);
}

TEST(CalibrationFile, MissingFileNamesThePath)
{
    const auto loaded = loadCalibration("/nonexistent/calib.yaml");
    ASSERT_FALSE(loaded.has_value());
    EXPECT_EQ(loaded.error().where, "/nonexistent/calib.yaml");
    EXPECT_NE(loaded.error().what.find("not found"), std::string::npos);
}

TEST(CalibrationFile, TruncatedYamlIsAnErrorNotAThrow)
{
    const auto path = tempPath("truncated.yaml");
    ASSERT_TRUE(saveCalibration(path.string(), makeFull()).has_value());
    const std::string text = readText(path);
    writeText(path, text.substr(0, text.find("data: [") + 12));

    const auto loaded = loadCalibration(path.string());

    ASSERT_FALSE(loaded.has_value());
    EXPECT_NE(loaded.error().message().find(path.string()), std::string::npos) << loaded.error().message();
}

TEST(CalibrationFile, CorruptYamlIsAnError)
{
    const std::string message = loadRectifiedText("corrupt.yaml", "%YAML:1.0\n---\nfx: [1, 2\n  }{ :\n");
    EXPECT_NE(message.find("corrupt.yaml"), std::string::npos) << message;
}

TEST(CalibrationFile, MissingKeyIsNamed)
{
    const std::string message = loadEditedFull("missing-key.yaml", "R2:", "XX:");
    EXPECT_NE(message.find("missing-key.yaml: R2"), std::string::npos) << message;
    EXPECT_NE(message.find("missing key"), std::string::npos) << message;
}

TEST(CalibrationFile, WrongMatrixSizeIsNamed)
{
    const std::string message = loadEditedFull("wrong-size.yaml", "T: !!opencv-matrix\n   rows: 3\n   cols: 1",
                                               "T: !!opencv-matrix\n   rows: 1\n   cols: 3");
    EXPECT_NE(message.find("wrong-size.yaml: T"), std::string::npos) << message;
    EXPECT_NE(message.find("expected 3x1"), std::string::npos) << message;
}

TEST(CalibrationFile, WrongMatrixTypeIsNamed)
{
    const std::string message =
        loadEditedFull("wrong-type.yaml", "Q: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d",
                       "Q: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: f");
    EXPECT_NE(message.find("wrong-type.yaml: Q"), std::string::npos) << message;
}

TEST(CalibrationFile, NanInMatrixIsNamed)
{
    const auto path = tempPath("nan.yaml");
    StereoCalibration calib = makeFull();
    calib.E.at<double>(1, 2) = std::numeric_limits<double>::quiet_NaN();
    ASSERT_TRUE(saveCalibration(path.string(), calib).has_value());

    const auto loaded = loadCalibration(path.string());

    ASSERT_FALSE(loaded.has_value());
    EXPECT_NE(loaded.error().message().find("nan.yaml: E"), std::string::npos) << loaded.error().message();
}

TEST(CalibrationFile, InfiniteNumberIsNamed)
{
    const std::string message = loadRectifiedText("inf.yaml", replaced(kRectified, "fy: 501.", "fy: .Inf"));
    EXPECT_NE(message.find("inf.yaml: fy"), std::string::npos) << message;
}

TEST(CalibrationFile, NonPositiveFocalIsNamed)
{
    const std::string message = loadRectifiedText("focal.yaml", replaced(kRectified, "fx: 500.", "fx: -3."));
    EXPECT_NE(message.find("focal.yaml: fx"), std::string::npos) << message;
}

TEST(CalibrationFile, NonPositiveFocalInFullFormIsNamed)
{
    const std::string message = loadEditedFull("focal-full.yaml", "data: [ 540., 0.", "data: [ -540., 0.");
    EXPECT_NE(message.find("focal-full.yaml: K1"), std::string::npos) << message;
}

TEST(CalibrationFile, BadBaselineIsNamedWithTheRange)
{
    const std::string message =
        loadRectifiedText("baseline.yaml", replaced(kRectified, "baseline_m: 0.12", "baseline_m: 0"));
    EXPECT_NE(message.find("baseline.yaml: baseline_m"), std::string::npos) << message;
    EXPECT_NE(message.find("[0.01, 5] metres"), std::string::npos) << message;
}

TEST(CalibrationFile, NonPositiveImageSizeIsNamed)
{
    const std::string message =
        loadRectifiedText("size.yaml", replaced(kRectified, "image_width: 640", "image_width: 0"));
    EXPECT_NE(message.find("size.yaml: image_width"), std::string::npos) << message;
}

TEST(CalibrationFile, UnsupportedSchemaVersionIsNamed)
{
    const std::string message =
        loadRectifiedText("schema.yaml", replaced(kRectified, "schema_version: 1", "schema_version: 2"));
    EXPECT_NE(message.find("schema.yaml: schema_version"), std::string::npos) << message;
    EXPECT_NE(message.find("unsupported schema_version 2"), std::string::npos) << message;
}

TEST(CalibrationFile, NumberAsTextIsNamed)
{
    const std::string message = loadRectifiedText("text.yaml", replaced(kRectified, "cx: 320.", "cx: middle"));
    EXPECT_NE(message.find("text.yaml: cx"), std::string::npos) << message;
}

TEST(CalibrationFile, MountHeightOutOfRangeIsNamed)
{
    const std::string message = loadRectifiedText(
        "mount-height.yaml", std::string(kRectified) + "mount: { height_m: 12, pitch_deg: 0, roll_deg: 0 }\n");
    EXPECT_NE(message.find("mount-height.yaml: height_m"), std::string::npos) << message;
    EXPECT_NE(message.find("[0.05, 10] metres"), std::string::npos) << message;
}

TEST(CalibrationFile, MountPitchAndRollOutOfRangeAreNamed)
{
    const std::string pitch = loadRectifiedText(
        "mount-pitch.yaml", std::string(kRectified) + "mount: { height_m: 0.5, pitch_deg: 50, roll_deg: 0 }\n");
    EXPECT_NE(pitch.find("mount-pitch.yaml: pitch_deg"), std::string::npos) << pitch;
    const std::string roll = loadRectifiedText(
        "mount-roll.yaml", std::string(kRectified) + "mount: { height_m: 0.5, pitch_deg: 0, roll_deg: -31 }\n");
    EXPECT_NE(roll.find("mount-roll.yaml: roll_deg"), std::string::npos) << roll;
}

TEST(CalibrationFile, UnwritablePathIsAnError)
{
    const auto saved = saveCalibration("/nonexistent/dir/calib.yaml", makeFull());
    ASSERT_FALSE(saved.has_value());
    EXPECT_EQ(saved.error().where, "/nonexistent/dir/calib.yaml");
}

} // namespace

// Issue 22: every class of hostile calibration text is refused with the file, line or key, before OpenCV parses it.

constexpr const char* kHeader = "%YAML:1.0\n---\n";

TEST(CalibrationFileHostile, DeepBracketsAreRefusedBeforeOpenCVOverflowsItsStack)
{
    constexpr int kLevels = 30000; // 60 KB: under the size limit, so the depth limit must catch it
    const std::string deep =
        std::string(kHeader) + "x: " + std::string(kLevels, '[') + std::string(kLevels, ']') + "\n";

    const std::string message = loadRectifiedText("deep-brackets.yaml", deep);

    EXPECT_NE(message.find("deep-brackets.yaml:3: nested deeper than 8 levels"), std::string::npos) << message;
}

TEST(CalibrationFileHostile, DeepKeyChainIsRefusedWithItsLine)
{
    std::string chain;
    for (int i = 0; i < 20000; ++i) {
        chain += "x: ";
    }
    const std::string message =
        loadRectifiedText("deep-chain.yaml", std::string(kRectified) + "mount: " + chain + "1\n");

    EXPECT_NE(message.find("deep-chain.yaml:12: nested deeper"), std::string::npos) << message;
}

TEST(CalibrationFileHostile, OverLongTextIsRefusedBeforeItIsRead)
{
    const std::string message = loadRectifiedText(
        "long.yaml", std::string(kRectified) + "# " + std::string(ugv::adapters::kMaxCalibrationBytes, 'x') + "\n");

    EXPECT_NE(message.find("long.yaml: the file is"), std::string::npos) << message;
    EXPECT_NE(message.find("more than the 65536"), std::string::npos) << message;
}

TEST(CalibrationFileHostile, RecordingTextIsCheckedToo)
{
    const std::string deep = std::string(kHeader) + "x: " + std::string(30000, '{') + "\n";

    const auto parsed = ugv::adapters::parseCalibration(deep, "rec.ugvrec (its stored calibration)");

    ASSERT_FALSE(parsed.has_value());
    EXPECT_NE(parsed.error().message().find("rec.ugvrec (its stored calibration):3: nested deeper"), std::string::npos)
        << parsed.error().message();
}

TEST(CalibrationFileHostile, IntegerBeyond32BitsIsRefusedNotWrapped)
{
    // OpenCV 4.6 reads 4294967536 as 240 (modulo 2^32), inside the image: it would pass the range check.
    const std::string message = loadRectifiedText("wide.yaml", replaced(kRectified, "cy: 240.", "cy: 4294967536"));

    EXPECT_NE(message.find("wide.yaml:10: integer 4294967536 does not fit in 32 bits"), std::string::npos) << message;
}

TEST(CalibrationFileHostile, FractionalImageSizeIsRefused)
{
    const std::string message =
        loadRectifiedText("fraction.yaml", replaced(kRectified, "image_width: 640", "image_width: 640.5"));

    EXPECT_NE(message.find("fraction.yaml: image_width: value 640.5 is not an integer in [16, 16384]"),
              std::string::npos)
        << message;
}

TEST(CalibrationFileHostile, TinyFocalBaselineAndMountHeightAreRefused)
{
    const std::string fx = loadRectifiedText("tiny-fx.yaml", replaced(kRectified, "fx: 500.", "fx: 1e-300"));
    EXPECT_NE(fx.find("tiny-fx.yaml: fx: value 1e-300 out of range"), std::string::npos) << fx;
    const std::string baseline =
        loadRectifiedText("tiny-baseline.yaml", replaced(kRectified, "baseline_m: 0.12", "baseline_m: 1e-300"));
    EXPECT_NE(baseline.find("tiny-baseline.yaml: baseline_m: value 1e-300 out of range"), std::string::npos)
        << baseline;
    const std::string mount = loadRectifiedText(
        "tiny-mount.yaml", std::string(kRectified) + "mount: { height_m: 1e-300, pitch_deg: 0, roll_deg: 0 }\n");
    EXPECT_NE(mount.find("tiny-mount.yaml: height_m: value 1e-300 out of range"), std::string::npos) << mount;
}

TEST(CalibrationFileHostile, AMatrixTagCutShortIsAnErrorNotACrash)
{
    // The calibration fuzz target's first find (test/fuzz/corpus/calibration/crash-opencv-length-error.yaml, in
    // short): OpenCV 4.6's reader throws std::length_error, not cv::Exception, at a key cut out of a matrix node.
    const std::string text = "%YAML:1.0\n---\nschema_version: 1\nK1: !!opencv-matrix\n   rows: 3\n   cols: 3\n   : d\n"
                             "   data: [ 5.4e+02, 0., 3.1e+02, 0.,\n       5.4e+02, 2.3e+02, 0., 0., 1. ]\n"
                             "R: !!opencv-matri      4.4e+00 ]\nK2: !!opencv-matrix\n   rows: 3\n   col84183e+00 ]\n"
                             "K2: !!\n\n\n\n";
    const auto parsed = ugv::adapters::parseCalibration(text, "cut.yaml");
    ASSERT_FALSE(parsed.has_value());
    EXPECT_NE(parsed.error().message().find("cut.yaml"), std::string::npos) << parsed.error().message();
}

TEST(CalibrationFileHostile, TinyFocalInFullFormIsRefused)
{
    const std::string message = loadEditedFull("tiny-focal-full.yaml", "data: [ 540., 0.", "data: [ 1.e-300, 0.");
    EXPECT_NE(message.find("tiny-focal-full.yaml: K1: focal length fx 1e-300"), std::string::npos) << message;
}

TEST(CalibrationFileHostile, FullFormWithANonNegativeP2BaselineIsRefused)
{
    for (const double sign : {0.0, 1.0}) {
        StereoCalibration c = makeFull();
        c.P2.at<double>(0, 3) = sign * std::abs(c.P2.at<double>(0, 3));
        const auto path = tempPath("p2-baseline.yaml");
        ASSERT_TRUE(saveCalibration(path.string(), c).has_value());

        const auto loaded = loadCalibration(path.string());

        ASSERT_FALSE(loaded.has_value()) << "P2(0,3) sign " << sign;
        EXPECT_NE(loaded.error().message().find("p2-baseline.yaml: P2: rectified baseline"), std::string::npos)
            << loaded.error().message();
    }
}

TEST(CalibrationFileHostile, RotationThatIsNoRotationIsRefused)
{
    StereoCalibration c = makeFull();
    c.R1 *= 2.0;
    const auto path = tempPath("not-rotation.yaml");
    ASSERT_TRUE(saveCalibration(path.string(), c).has_value());

    const auto loaded = loadCalibration(path.string());

    ASSERT_FALSE(loaded.has_value());
    EXPECT_NE(loaded.error().message().find("not-rotation.yaml: R1: not a rotation"), std::string::npos)
        << loaded.error().message();
}

TEST(CalibrationFileHostile, DuplicateKeyIsRefused)
{
    const std::string top = loadRectifiedText("duplicate.yaml", std::string(kRectified) + "fx: 600.\n");
    EXPECT_NE(top.find("duplicate.yaml: fx: the key is given twice"), std::string::npos) << top;
    const std::string inner = loadRectifiedText(
        "duplicate-mount.yaml",
        std::string(kRectified) + "mount: { height_m: 0.5, pitch_deg: 0, roll_deg: 0, height_m: 5 }\n");
    EXPECT_NE(inner.find("duplicate-mount.yaml: mount.height_m: the key is given twice"), std::string::npos) << inner;
}

TEST(CalibrationFileHostile, SyntaxErrorNamesTheLineNotOpenCVsFunction)
{
    const std::string message =
        loadRectifiedText("syntax.yaml", std::string(kHeader) + "schema_version: 1\na: [1, 2\nb: 3\n");

    // The guard in front of OpenCV (YamlLimits::openCvSubset) names it: an unclosed matrix runs into "b: 3".
    EXPECT_NE(message.find("syntax.yaml:5: 'b' in a matrix's data"), std::string::npos) << message;
    EXPECT_EQ(message.find("parseValue"), std::string::npos) << message;
    EXPECT_EQ(message.find("skipSpaces"), std::string::npos) << message;
}

TEST(CalibrationFileHostile, TextWithoutTheYamlHeaderIsNamed)
{
    const std::string message = loadRectifiedText("no-header.yaml", replaced(kRectified, "%YAML:1.0\n---\n", ""));

    EXPECT_NE(message.find("no-header.yaml: does not start with '%YAML:1.0'"), std::string::npos) << message;
}
