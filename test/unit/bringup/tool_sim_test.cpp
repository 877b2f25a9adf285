// Runs the built `ugvsense sim` binary: every simulator scene renders and writes its files, courses write numbered
// samples and poses or a recording with its truth (checked through `ugvsense recording info/export/import`),
// --list/--help, the chessboard scene still works, and bad input fails with what/where/fix.

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "run_command.hpp"
#include "ugv/sim/scene.hpp"
namespace {

using ToolRun = ugv::test::CommandRun;

/// The built `ugvsense` with `args`.
ToolRun run(const std::string& args)
{
    return ugv::test::runCommand(std::string(UGVSENSE_PATH) + " " + args);
}

std::filesystem::path tempDir(const std::string& name)
{
    const auto dir = std::filesystem::temp_directory_path() / ("ugv-tool-sim-test-" + std::to_string(::getpid())) /
                     name; // per process: parallel ctest runs
    std::filesystem::remove_all(dir);
    return dir;
}

bool contains(const std::string& text, const std::string& part)
{
    return text.find(part) != std::string::npos;
}

TEST(ToolSim, EverySimulatorSceneRendersAndWritesItsFiles)
{
    for (const std::string& name : ugv::sim::sceneNames()) {
        const auto dir = tempDir("scene-" + name);

        const ToolRun sim =
            run("sim --scene " + name + " --range 4 --bearing 3 --texture gravel --out " + dir.string());

        ASSERT_EQ(sim.exitCode, 0) << name << ": " << sim.output;
        for (const char* suffix :
             {"_left.png", "_right.png", "_disparity.png", "_depth.png", "_labels.png", "_ids.png", "_sectors.json"}) {
            const auto path = dir / (name + suffix);
            EXPECT_TRUE(std::filesystem::is_regular_file(path)) << path;
            EXPECT_GT(std::filesystem::file_size(path), 0U) << path;
        }
        EXPECT_TRUE(std::filesystem::is_regular_file(dir / "calibration.yaml")) << name;
    }
}

TEST(ToolSim, MountOptionsReachTheCalibration)
{
    const auto dir = tempDir("mount");

    const ToolRun sim = run("sim --scene pole --pitch 4 --roll -1.5 --height 0.8 --seed 9 --out " + dir.string());

    ASSERT_EQ(sim.exitCode, 0) << sim.output;
    std::ifstream in(dir / "calibration.yaml");
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    EXPECT_TRUE(contains(text, "height_m: 8.0000000000000004e-01") || contains(text, "height_m: 0.8")) << text;
    EXPECT_TRUE(contains(text, "pitch_deg: 4")) << text;
    EXPECT_TRUE(contains(text, "roll_deg: -1.5")) << text;
}

std::string fileText(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(ToolSim, ConditionsChangeTheImagesAndTheKerbTheTruth)
{
    const auto plain = tempDir("cond-plain");
    const auto painted = tempDir("cond-paint");
    const auto kerb = tempDir("cond-kerb");

    ASSERT_EQ(run("sim --scene empty --out " + plain.string()).exitCode, 0);
    const ToolRun paint =
        run("sim --scene empty --condition paint,shadow --puddle 3,0,0.8,0.5,0.7 --jpeg 70 --out " + painted.string());
    const ToolRun kerbRun = run("sim --scene empty --kerb-height 0.15 --kerb-y -2 --out " + kerb.string());

    ASSERT_EQ(paint.exitCode, 0) << paint.output;
    ASSERT_EQ(kerbRun.exitCode, 0) << kerbRun.output;
    EXPECT_NE(fileText(painted / "empty_left.png"), fileText(plain / "empty_left.png"));
    EXPECT_EQ(fileText(painted / "empty_labels.png"), fileText(plain / "empty_labels.png"));
    EXPECT_EQ(fileText(painted / "empty_disparity.png"), fileText(plain / "empty_disparity.png"));
    EXPECT_FALSE(contains(fileText(painted / "empty_sectors.json"), "\"obstacle\""));
    EXPECT_NE(fileText(kerb / "empty_labels.png"), fileText(plain / "empty_labels.png"));
    EXPECT_TRUE(contains(fileText(kerb / "empty_sectors.json"), "\"obstacle\""));
}

TEST(ToolSim, BadConditionsFailWithWhatAndFix)
{
    const auto dir = tempDir("cond-bad");

    const ToolRun unknown = run("sim --scene empty --condition fog --out " + dir.string());
    const ToolRun puddle = run("sim --scene empty --puddle 1,2 --out " + dir.string());
    const ToolRun shadow = run("sim --scene empty --shadow 1,2,3,4 --out " + dir.string());
    const ToolRun camber = run("sim --scene empty --camber 0.5 --out " + dir.string());

    EXPECT_EQ(unknown.exitCode, 1);
    EXPECT_TRUE(contains(unknown.output, "unknown condition 'fog'") && contains(unknown.output, "puddle"))
        << unknown.output;
    EXPECT_EQ(puddle.exitCode, 1);
    EXPECT_TRUE(contains(puddle.output, "--puddle")) << puddle.output;
    EXPECT_EQ(shadow.exitCode, 1);
    EXPECT_TRUE(contains(shadow.output, "3 or more")) << shadow.output;
    EXPECT_NE(camber.exitCode, 0);
    EXPECT_TRUE(contains(camber.output, "--camber")) << camber.output;
}

TEST(ToolSim, CourseWritesNumberedFramesCalibrationAndPoses)
{
    const auto dir = tempDir("course");

    const ToolRun sim = run("sim --course default --frames 3 --fps 5 --out " + dir.string());

    ASSERT_EQ(sim.exitCode, 0) << sim.output;
    for (const char* file :
         {"frame_0000_left.png", "frame_0001_right.png", "frame_0002_sectors.json", "calibration.yaml", "poses.csv"}) {
        EXPECT_TRUE(std::filesystem::is_regular_file(dir / file)) << file;
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "frame_0003_left.png"));
    std::ifstream poses(dir / "poses.csv");
    std::string line;
    ASSERT_TRUE(std::getline(poses, line));
    EXPECT_EQ(line, "frame,t,x,y,yaw");
    ASSERT_TRUE(std::getline(poses, line));
    EXPECT_EQ(line, "0,0,0,0,0");
    ASSERT_TRUE(std::getline(poses, line));
    EXPECT_EQ(line, "1,0.2,0.3,0,0"); // 1.5 m/s at 5 fps
}

TEST(ToolSim, CourseRecordingHasTruthAndRoundTripsThroughExportAndImport)
{
    const auto dir = tempDir("course-recording");
    std::filesystem::create_directories(dir);
    const std::string rec = (dir / "drive.ugvrec").string();

    const ToolRun sim = run("sim --course default --frames 3 --fps 5 --out " + rec);
    ASSERT_EQ(sim.exitCode, 0) << sim.output;
    std::ifstream truth(rec + ".truth.csv");
    std::string line;
    ASSERT_TRUE(std::getline(truth, line));
    EXPECT_EQ(line, "sequence,t_s,x_m,y_m,yaw_deg,sector,bearing_min_deg,bearing_max_deg,state,kind,range_m,class");
    int rows = 0;
    while (std::getline(truth, line)) {
        ++rows;
    }
    EXPECT_EQ(rows, 3 * 64);

    const ToolRun info = run("recording info " + rec);
    ASSERT_EQ(info.exitCode, 0) << info.output;
    EXPECT_TRUE(contains(info.output, "640x480")) << info.output;
    EXPECT_TRUE(contains(info.output, "frames: 3 complete (sequence 0..2, 0 missing")) << info.output;
    EXPECT_TRUE(contains(info.output, "5.00 fps")) << info.output;

    const auto exported = dir / "exported";
    const ToolRun out = run("recording export " + rec + " --out " + exported.string());
    ASSERT_EQ(out.exitCode, 0) << out.output;
    for (const char* file : {"frame_000000_left.png", "frame_000002_right.png", "frames.csv", "calibration.yaml"}) {
        EXPECT_TRUE(std::filesystem::is_regular_file(exported / file)) << file;
    }
    // Back in as PNG pairs named left*/right*, with the recorded stamps.
    const auto pairs = dir / "pairs";
    std::filesystem::create_directories(pairs);
    std::ofstream stamps(dir / "stamps.csv");
    stamps << "frame,stamp_ns\n";
    for (int k = 0; k < 3; ++k) {
        const std::string n = "00000" + std::to_string(k);
        std::filesystem::copy_file(exported / ("frame_" + n + "_left.png"), pairs / ("left" + n + ".png"));
        std::filesystem::copy_file(exported / ("frame_" + n + "_right.png"), pairs / ("right" + n + ".png"));
        stamps << k << ',' << 1000000000 + k * 200000000 << '\n';
    }
    stamps.close();
    const std::string back = (dir / "back.ugvrec").string();
    const ToolRun imported =
        run("recording import --pairs " + pairs.string() + " --calib " + (exported / "calibration.yaml").string() +
            " --timestamps " + (dir / "stamps.csv").string() + " --out " + back);
    ASSERT_EQ(imported.exitCode, 0) << imported.output;
    EXPECT_TRUE(contains(imported.output, "imported 3 pair(s) of 3 (0 skipped)")) << imported.output;
    const ToolRun backInfo = run("recording info " + back);
    EXPECT_TRUE(contains(backInfo.output, "frames: 3 complete")) << backInfo.output;
    EXPECT_TRUE(contains(backInfo.output, "5.00 fps")) << backInfo.output;

    // Importing over an existing recording needs --force.
    const ToolRun again = run("recording import --pairs " + pairs.string() + " --calib " +
                              (exported / "calibration.yaml").string() + " --out " + back);
    EXPECT_EQ(again.exitCode, 1);
    EXPECT_TRUE(contains(again.output, "EEXIST")) << again.output;
}

/// The colour type of a PNG file's IHDR chunk (byte 25): 0 grey, 2 RGB; -1 when unreadable.
int pngColourType(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    char head[26] = {};
    return in.read(head, sizeof(head)) ? static_cast<unsigned char>(head[25]) : -1;
}

TEST(ToolSim, AColourCourseRecordingRoundTripsInColourThroughExportAndImport)
{
    const auto dir = tempDir("colour-recording");
    std::filesystem::create_directories(dir);
    const std::string rec = (dir / "drive.ugvrec").string();

    const ToolRun sim = run("sim --course default --frames 2 --colour --out " + rec);
    ASSERT_EQ(sim.exitCode, 0) << sim.output;
    const ToolRun info = run("recording info " + rec);
    EXPECT_TRUE(contains(info.output, "640x480 colour (BGR) stereo")) << info.output;
    EXPECT_TRUE(contains(info.output, "frames: 2 complete")) << info.output;
    EXPECT_EQ(std::filesystem::file_size(rec) > 2 * 6 * 640 * 480, true);

    const auto exported = dir / "exported";
    ASSERT_EQ(run("recording export " + rec + " --out " + exported.string()).exitCode, 0);
    EXPECT_EQ(pngColourType(exported / "frame_000000_left.png"), 2);
    EXPECT_EQ(pngColourType(exported / "frame_000001_right.png"), 2);

    const auto pairs = dir / "pairs";
    std::filesystem::create_directories(pairs);
    for (const char* n : {"000000", "000001"}) {
        std::filesystem::copy_file(exported / ("frame_" + std::string(n) + "_left.png"),
                                   pairs / ("left" + std::string(n) + ".png"));
        std::filesystem::copy_file(exported / ("frame_" + std::string(n) + "_right.png"),
                                   pairs / ("right" + std::string(n) + ".png"));
    }
    const std::string calib = (exported / "calibration.yaml").string();
    const std::string colour = (dir / "colour.ugvrec").string();
    const std::string grey = (dir / "grey.ugvrec").string();
    ASSERT_EQ(
        run("recording import --colour --pairs " + pairs.string() + " --calib " + calib + " --out " + colour).exitCode,
        0);
    ASSERT_EQ(run("recording import --pairs " + pairs.string() + " --calib " + calib + " --out " + grey).exitCode, 0);
    EXPECT_TRUE(contains(run("recording info " + colour).output, "colour (BGR) stereo"));
    EXPECT_TRUE(contains(run("recording info " + grey).output, "640x480 grey stereo"));
    EXPECT_EQ(std::filesystem::file_size(colour),
              std::filesystem::file_size(rec)); // the same frames, byte for byte size
}

TEST(ToolSim, TruncatedRecordingReportsWhatWasRecovered)
{
    const auto dir = tempDir("truncated-recording");
    std::filesystem::create_directories(dir);
    const std::string rec = (dir / "cut.ugvrec").string();
    ASSERT_EQ(run("sim --course default --frames 3 --out " + rec).exitCode, 0);
    std::filesystem::resize_file(rec, std::filesystem::file_size(rec) - 1000);

    const ToolRun info = run("recording info " + rec);

    ASSERT_EQ(info.exitCode, 0) << info.output;
    EXPECT_TRUE(contains(info.output, "frames: 2 complete")) << info.output;
    EXPECT_TRUE(contains(info.output, "truncated: the last")) << info.output;
    EXPECT_TRUE(contains(info.output, "the 2 complete frames before it are recovered")) << info.output;

    std::ofstream(dir / "junk.ugvrec") << "not a recording at all, but long enough to hold a header ........";
    const ToolRun junk = run("recording info " + (dir / "junk.ugvrec").string());
    EXPECT_EQ(junk.exitCode, 1);
    EXPECT_TRUE(contains(junk.output, "junk.ugvrec: not a ugvsense recording")) << junk.output;
    EXPECT_TRUE(contains(junk.output, "fix:")) << junk.output;
}

TEST(ToolSim, ListPrintsScenesAndCourses)
{
    const ToolRun list = run("sim --list");

    ASSERT_EQ(list.exitCode, 0) << list.output;
    EXPECT_TRUE(contains(list.output, "chessboard")) << list.output;
    for (const std::string& name : ugv::sim::sceneNames()) {
        EXPECT_TRUE(contains(list.output, name)) << name;
    }
    EXPECT_TRUE(contains(list.output, "courses: default")) << list.output;
}

TEST(ToolSim, HelpNamesOptionsAndBothCourseOutputs)
{
    const ToolRun help = run("sim --help");

    ASSERT_EQ(help.exitCode, 0) << help.output;
    for (const char* part : {"usage: ugvsense sim", "--course", "--texture", "--pitch", "--frames", "--out REC.ugvrec",
                             "REC.ugvrec.truth.csv", "--out DIR"}) {
        EXPECT_TRUE(contains(help.output, part)) << part;
    }
}

TEST(ToolSim, ChessboardStillWritesPairsAndTruth)
{
    const auto dir = tempDir("chessboard");

    const ToolRun sim = run("sim --scene chessboard --pairs 2 --out " + dir.string());

    ASSERT_EQ(sim.exitCode, 0) << sim.output;
    for (const char* file : {"left_01.png", "right_01.png", "left_02.png", "right_02.png", "truth.yaml"}) {
        EXPECT_TRUE(std::filesystem::is_regular_file(dir / file)) << file;
    }
}

TEST(ToolSim, UnknownSceneFailsNamingTheValidOnes)
{
    const ToolRun sim = run("sim --scene unicorn --out " + tempDir("unknown").string());

    EXPECT_EQ(sim.exitCode, 1);
    EXPECT_TRUE(contains(sim.output, "--scene: unknown scene 'unicorn'")) << sim.output;
    EXPECT_TRUE(contains(sim.output, "fix: use one of: chessboard, empty, pole")) << sim.output;
}

TEST(ToolSim, UnknownCourseFails)
{
    const ToolRun sim = run("sim --course nowhere --out " + tempDir("unknown-course").string());

    EXPECT_EQ(sim.exitCode, 1);
    EXPECT_TRUE(contains(sim.output, "unknown course 'nowhere'")) << sim.output;
}

TEST(ToolSim, NonPositiveRangeFails)
{
    for (const char* range : {"0", "-2"}) {
        const auto dir = tempDir("range");

        const ToolRun sim = run(std::string("sim --scene box --range ") + range + " --out " + dir.string());

        EXPECT_EQ(sim.exitCode, 1) << range;
        EXPECT_TRUE(contains(sim.output, "--range: range " + std::string(range) + " m is not positive")) << sim.output;
        EXPECT_FALSE(std::filesystem::exists(dir / "box_left.png"));
    }
}

TEST(ToolSim, UnknownTextureFails)
{
    const ToolRun sim = run("sim --scene box --texture lava --out " + tempDir("texture").string());

    EXPECT_EQ(sim.exitCode, 1);
    EXPECT_TRUE(contains(sim.output, "use one of: asphalt, grass, gravel, floor")) << sim.output;
}

TEST(ToolSim, UnwritableOutputFolderFailsNamingIt)
{
    const ToolRun sim = run("sim --scene box --out /proc/ugv-not-writable");

    EXPECT_EQ(sim.exitCode, 1);
    EXPECT_TRUE(contains(sim.output, "/proc/ugv-not-writable: cannot create the output folder")) << sim.output;
}

TEST(ToolSim, UsageErrorsExitWithTwo)
{
    const ToolRun neither = run("sim --out /tmp/x");
    const ToolRun both = run("sim --scene box --course default --out /tmp/x");
    const ToolRun noOut = run("sim --scene box");
    const ToolRun badOption = run("sim --scene box --out /tmp/x --frob 1");

    EXPECT_EQ(neither.exitCode, 2);
    EXPECT_TRUE(contains(neither.output, "exactly one of --scene NAME and --course NAME")) << neither.output;
    EXPECT_EQ(both.exitCode, 2);
    EXPECT_EQ(noOut.exitCode, 2);
    EXPECT_TRUE(contains(noOut.output, "--out DIR")) << noOut.output;
    EXPECT_EQ(badOption.exitCode, 2);
}

} // namespace
