// Runs the built `ugvsense` binary: sim -> calibrate -> rectify on rendered pairs, and the error paths.

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "run_command.hpp"
#include "ugv/adapters/calibration_file.hpp"
#include "ugv/hal/recording.hpp"
namespace {

using ugv::test::readText;
using ugv::test::writeText;

using ToolRun = ugv::test::CommandRun;

/// The built `ugvsense` with `args`.
ToolRun run(const std::string& args)
{
    return ugv::test::runCommand(std::string(UGVSENSE_PATH) + " " + args);
}

std::filesystem::path tempDir(const std::string& name)
{
    const auto dir = std::filesystem::temp_directory_path() /
                     ("ugv-tool-calibrate-test-" + std::to_string(::getpid())) /
                     name; // per process: parallel ctest runs
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

TEST(ToolCalibrate, RenderedPairsCalibrateWriteFileAndJsonThenRectify)
{
    const auto dir = tempDir("rendered");
    const ToolRun sim = run("sim --scene chessboard --out " + dir.string() + " --pairs 10 --seed 3");
    ASSERT_EQ(sim.exitCode, 0) << sim.output;
    const auto calibPath = dir / "calib.yaml";
    const auto jsonPath = dir / "report.json";

    const ToolRun calibrate = run("calibrate --images " + dir.string() + " --board 9x6 --square 0.025 --out " +
                                  calibPath.string() + " --json " + jsonPath.string() + " --mount-height 0.5");

    ASSERT_EQ(calibrate.exitCode, 0) << calibrate.output;
    EXPECT_NE(calibrate.output.find("RMS reprojection error"), std::string::npos) << calibrate.output;
    const auto loaded = ugv::adapters::loadCalibration(calibPath.string());
    ASSERT_TRUE(loaded.has_value()) << loaded.error().message();
    EXPECT_NEAR(loaded->baselineM(), 0.20, 0.002);
    ASSERT_TRUE(loaded->mount.has_value());
    const std::string json = readText(jsonPath);
    for (const char* key : {"\"rms_px\":", "\"epipolar_px\":", "\"rectified_dy_px\":", "\"pairs_used\": 10",
                            "\"pairs_rejected\": 0", "\"rejected\": [", "\"per_pair\": ["}) {
        EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
    }

    const ToolRun rectify = run("rectify --calib " + calibPath.string() + " --images " + dir.string() + " --full");
    ASSERT_EQ(rectify.exitCode, 0) << rectify.output;
    EXPECT_NE(rectify.output.find("chessboard mean |dy| in rectified images"), std::string::npos) << rectify.output;
}

TEST(ToolCalibrate, EmptyFolderFailsNamingIt)
{
    const auto dir = tempDir("empty");
    const ToolRun r =
        run("calibrate --images " + dir.string() + " --board 9x6 --square 0.025 --out " + (dir / "c.yaml").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("no left*/right* image pairs found"), std::string::npos) << r.output;
}

TEST(ToolCalibrate, MissingFolderFailsNamingIt)
{
    const ToolRun r = run("calibrate --images /nonexistent/pairs --board 9x6 --square 0.025 --out /tmp/c.yaml");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("/nonexistent/pairs: image folder not found"), std::string::npos) << r.output;
}

TEST(ToolCalibrate, BadBoardIsAUsageError)
{
    for (const char* board : {"9x", "0x6", "nine", "9x6x2"}) {
        const ToolRun r =
            run(std::string("calibrate --images /tmp --board ") + board + " --square 0.025 --out /tmp/c.yaml");
        EXPECT_EQ(r.exitCode, 2) << board << ": " << r.output;
        EXPECT_NE(r.output.find("bad board '" + std::string(board) + "'"), std::string::npos) << r.output;
    }
}

TEST(ToolCalibrate, BadSquareIsAUsageError)
{
    for (const char* square : {"0", "-0.025", "nan", "abc"}) {
        const ToolRun r =
            run(std::string("calibrate --images /tmp --board 9x6 --square ") + square + " --out /tmp/c.yaml");
        EXPECT_EQ(r.exitCode, 2) << square << ": " << r.output;
        EXPECT_NE(r.output.find("--square"), std::string::npos) << r.output;
    }
}

TEST(ToolCalibrate, UnwritableOutFails)
{
    const ToolRun r = run("calibrate --images /tmp --board 9x6 --square 0.025 --out /nonexistent/dir/c.yaml");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("/nonexistent/dir/c.yaml"), std::string::npos) << r.output;
}

TEST(ToolCalibrate, HelpExitsZero)
{
    const ToolRun r = run("calibrate --help");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("usage: ugvsense calibrate"), std::string::npos) << r.output;
}

// Issue 22: hostile input through the commands, as a user gives it. Each is refused with exit status 1 (no crash)
// and a message naming the file and the line or key.

constexpr const char* kRectifiedCalibration = "%YAML:1.0\n---\nschema_version: 1\nrectified: 1\nimage_width: 640\n"
                                              "image_height: 480\nfx: 500.\nfy: 500.\ncx: 320.\ncy: 240.\n"
                                              "baseline_m: 0.12\nmount: { height_m: 0.6, pitch_deg: 0, roll_deg: 0 }\n";

/// A recording of one grey frame of `size` carrying `calibration` as its stored calibration text.
void writeRecording(const std::filesystem::path& path, cv::Size size, const std::string& calibration)
{
    auto writer = ugv::hal::RecordingWriter::create(path.string(), static_cast<std::uint32_t>(size.width),
                                                    static_cast<std::uint32_t>(size.height), calibration);
    ASSERT_TRUE(writer.has_value()) << writer.error().message();
    const std::vector<std::uint8_t> pixels(static_cast<std::size_t>(size.area()), 128);
    const ugv::ConstImageViewU8 view(pixels.data(), size.width, size.height, size.width);
    ASSERT_TRUE(writer->append(0, 0, 0, greyViews(view, view)).has_value());
}

/// A folder with left1.png, right1.png (plain grey of these sizes) and calib.yaml (kRectifiedCalibration, 640x480).
std::filesystem::path pairWithCalibration(const std::string& name, cv::Size left, cv::Size right)
{
    const auto dir = tempDir(name);
    cv::imwrite((dir / "left1.png").string(), cv::Mat(left, CV_8UC1, cv::Scalar(100)));
    cv::imwrite((dir / "right1.png").string(), cv::Mat(right, CV_8UC1, cv::Scalar(100)));
    writeText(dir / "calib.yaml", kRectifiedCalibration);
    return dir;
}

TEST(ToolHostile, DeepCalibrationIsRefusedByEveryCommandThatReadsOne)
{
    const auto dir = tempDir("deep");
    const auto deep = dir / "deep.yaml";
    writeText(deep, "%YAML:1.0\n---\nx: " + std::string(30000, '[') + std::string(30000, ']') + "\n");
    writeText(dir / "config.yaml", "calibration: deep.yaml\ncamera:\n  backend: v4l2\n");
    ASSERT_EQ(run("sim --scene chessboard --out " + (dir / "pairs").string() + " --pairs 1").exitCode, 0);

    for (const std::string& command :
         {"check-config " + (dir / "config.yaml").string(),
          "detect --calib " + deep.string() + " --left l.png --right r.png",
          "rectify --calib " + deep.string() + " --images " + (dir / "pairs").string(),
          "recording import --pairs " + (dir / "pairs").string() + " --calib " + deep.string() + " --out " +
              (dir / "r.ugvrec").string(),
          "record --out " + (dir / "r.ugvrec").string() + " --calib " + deep.string() + " --frames 1"}) {
        const ToolRun sut = run(command);

        EXPECT_EQ(sut.exitCode, 1) << command << "\n" << sut.output;
        EXPECT_NE(sut.output.find("deep.yaml:3: nested deeper than 8 levels"), std::string::npos) << command << "\n"
                                                                                                  << sut.output;
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "r.ugvrec"));
}

TEST(ToolHostile, CheckConfigRefusesARecordingWhoseFramesDifferFromItsCalibration)
{
    const auto dir = tempDir("recording-size");
    writeRecording(dir / "small.ugvrec", cv::Size(320, 240), kRectifiedCalibration);
    writeText(dir / "config.yaml", "camera:\n  backend: replay\n  replay_path: small.ugvrec\n");

    const ToolRun sut = run("check-config " + (dir / "config.yaml").string());

    EXPECT_EQ(sut.exitCode, 1) << sut.output;
    EXPECT_NE(sut.output.find("small.ugvrec"), std::string::npos) << sut.output;
    EXPECT_NE(sut.output.find("delivers 320x240 frames but the calibration is for 640x480"), std::string::npos)
        << sut.output;
    EXPECT_NE(sut.output.find("the service would refuse to start"), std::string::npos) << sut.output;
    const ToolRun info = run("recording info " + (dir / "small.ugvrec").string());
    EXPECT_EQ(info.exitCode, 1) << info.output;
    EXPECT_NE(info.output.find("calibration: for 640x480, not the frames' size"), std::string::npos) << info.output;
}

TEST(ToolHostile, ADeepCalibrationInsideARecordingIsRefusedByEveryReader)
{
    const auto dir = tempDir("recording-deep");
    writeRecording(dir / "deep.ugvrec", cv::Size(640, 480),
                   "%YAML:1.0\n---\nx: " + std::string(30000, '[') + std::string(30000, ']') + "\n");
    writeText(dir / "config.yaml", "camera:\n  backend: replay\n  replay_path: deep.ugvrec\ndds:\n  enabled: false\n");
    const std::string expected = "(its stored calibration):3: nested deeper than 8 levels";

    for (const std::string& command : {std::string(UGVSENSE_PATH) + " recording info " + (dir / "deep.ugvrec").string(),
                                       std::string(UGVSENSE_PATH) + " check-config " + (dir / "config.yaml").string(),
                                       std::string(UGVSENSED_PATH) + " --config " + (dir / "config.yaml").string()}) {
        const ToolRun sut = ugv::test::runCommand(command);

        EXPECT_EQ(sut.exitCode, 1) << command << "\n" << sut.output;
        EXPECT_NE(sut.output.find(expected), std::string::npos) << command << "\n" << sut.output;
        EXPECT_NE(sut.output.find("deep.ugvrec"), std::string::npos) << command << "\n" << sut.output;
    }
}

TEST(ToolHostile, RecordingImportRefusesImagesOfAnotherSizeThanTheCalibration)
{
    const auto dir = pairWithCalibration("import-size", cv::Size(320, 240), cv::Size(320, 240));

    const ToolRun sut = run("recording import --pairs " + dir.string() + " --calib " + (dir / "calib.yaml").string() +
                            " --out " + (dir / "r.ugvrec").string());

    EXPECT_EQ(sut.exitCode, 1) << sut.output;
    EXPECT_NE(sut.output.find("left1.png: image size 320x240 differs from"), std::string::npos) << sut.output;
}

TEST(ToolHostile, RectifyNamesTheImageWhoseSizeDiffersFromTheCalibration)
{
    const auto dir = pairWithCalibration("rectify-size", cv::Size(640, 480), cv::Size(320, 240));

    const ToolRun sut = run("rectify --calib " + (dir / "calib.yaml").string() + " --images " + dir.string());

    EXPECT_NE(sut.output.find("skipped, right1.png is 320x240 but the calibration is for 640x480"), std::string::npos)
        << sut.output;
}

TEST(ToolHostile, ImageDeclaringAHugeSizeIsRefusedBeforeDecoding)
{
    const auto dir = tempDir("huge-image");
    // A PNG signature and an IHDR chunk declaring 30000x30000 (8-bit grey); nothing after it.
    const std::string header(
        "\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR\x00\x00\x75\x30\x00\x00\x75\x30\x08\x00\x00\x00\x00", 29);
    std::ofstream((dir / "left1.png").string(), std::ios::binary) << header;
    std::ofstream((dir / "right1.png").string(), std::ios::binary) << header;
    writeText(dir / "calib.yaml", kRectifiedCalibration);

    const ToolRun detect = run("detect --calib " + (dir / "calib.yaml").string() + " --left " +
                               (dir / "left1.png").string() + " --right " + (dir / "right1.png").string());
    EXPECT_EQ(detect.exitCode, 1) << detect.output;
    EXPECT_NE(detect.output.find("left1.png: the header declares 30000x30000 pixels, outside 1..16384"),
              std::string::npos)
        << detect.output;

    const ToolRun rectify = run("rectify --calib " + (dir / "calib.yaml").string() + " --images " + dir.string());
    EXPECT_NE(rectify.output.find("left1.png: the header declares 30000x30000"), std::string::npos) << rectify.output;
}

// eval's readers (Middlebury here; the real-data reader uses the same call) check the header before decoding.
TEST(ToolHostile, EvalRefusesAHugeImageBeforeDecoding)
{
    const auto dir = tempDir("huge-eval");
    std::filesystem::create_directories(dir / "middlebury" / "tsukuba");
    const std::string header(
        "\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR\x00\x00\x75\x30\x00\x00\x75\x30\x08\x00\x00\x00\x00", 29);
    for (const char* name : {"im3.png", "im4.png", "disp3.pgm"}) {
        std::ofstream((dir / "middlebury" / "tsukuba" / name).string(), std::ios::binary) << header;
    }

    const ToolRun sut = run("eval --middlebury --data " + dir.string());

    EXPECT_EQ(sut.exitCode, 1) << sut.output;
    EXPECT_NE(sut.output.find("im3.png: the header declares 30000x30000 pixels"), std::string::npos) << sut.output;
}

TEST(ToolHostile, JpegBmpAndPgmHeadersAreCheckedToo)
{
    const auto dir = tempDir("huge-headers");
    writeText(dir / "calib.yaml", kRectifiedCalibration);
    // 30000 = 0x7530: a JPEG start-of-frame after an APP0 segment, a BMP info header, a PGM header.
    const std::vector<std::pair<std::string, std::string>> files = {
        {"huge.jpg",
         std::string("\xFF\xD8\xFF\xE0\x00\x04\x00\x00\xFF\xC0\x00\x0B\x08\x75\x30\x75\x30\x01\x01\x11\x00", 21)},
        {"huge.bmp", std::string("BM") + std::string(16, '\0') + std::string("\x30\x75\x00\x00\x30\x75\x00\x00", 8)},
        {"huge.pgm", "P5\n# a comment\n30000 30000\n255\n"},
    };
    for (const auto& [name, bytes] : files) {
        std::ofstream((dir / name).string(), std::ios::binary) << bytes;

        const ToolRun sut = run("detect --calib " + (dir / "calib.yaml").string() + " --left " + (dir / name).string() +
                                " --right " + (dir / name).string());

        EXPECT_EQ(sut.exitCode, 1) << name << "\n" << sut.output;
        EXPECT_NE(sut.output.find(name + ": the header declares 30000x30000 pixels"), std::string::npos) << name << "\n"
                                                                                                         << sut.output;
    }
}

} // namespace
