// Runs the built `ugvsense` binary: sim -> calibrate -> rectify on rendered pairs, and the error paths.

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>

#include <gtest/gtest.h>

#include "ugv/bringup/calibration_file.hpp"

namespace {

struct ToolRun {
    int exitCode = -1;
    std::string output;
};

ToolRun run(const std::string& args)
{
    const std::string command = std::string(UGVSENSE_PATH) + " " + args + " 2>&1";
    ToolRun result;
    FILE* pipe = popen(command.c_str(), "r"); // NOLINT(cert-env33-c) test harness runs our own binary
    if (pipe == nullptr) {
        return result;
    }
    char buffer[512];
    while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) {
        result.output += buffer;
    }
    const int status = pclose(pipe);
    result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return result;
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

std::string readText(const std::filesystem::path& path)
{
    std::ifstream in(path);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
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
    const auto loaded = ugv::bringup::loadCalibration(calibPath.string());
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

} // namespace
