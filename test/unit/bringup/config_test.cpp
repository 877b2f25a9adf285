#include "ugv/adapters/config.hpp"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <utility>

#include <gtest/gtest.h>

#include "ugv/rt/task.hpp"

namespace ugv::adapters {
namespace {

constexpr const char* kValidMinimal = "calibration: calib.yaml\ncamera:\n  replay_path: rec.bin\n";

/// All error messages joined, for substring assertions.
std::string joined(const ConfigErrors& errors)
{
    std::string text;
    for (const auto& e : errors) {
        text += e.message() + "\n";
    }
    return text;
}

ConfigErrors parseErrors(const std::string& yaml)
{
    auto result = parseConfig(yaml, "test.yaml", "/etc/ugvsense");
    EXPECT_FALSE(result.has_value()) << "expected errors for:\n" << yaml;
    return result.has_value() ? ConfigErrors{} : result.error();
}

TEST(Config, MinimalFileGivesDefaultsAndResolvesRelativePaths)
{
    const auto sut = parseConfig(kValidMinimal, "test.yaml", "/etc/ugvsense");

    ASSERT_TRUE(sut.has_value()) << joined(sut.error());
    EXPECT_EQ(sut->calibrationPath, "/etc/ugvsense/calib.yaml");
    EXPECT_EQ(sut->camera.replayPath, "/etc/ugvsense/rec.bin");
    EXPECT_EQ(sut->camera.width, 640);
    EXPECT_EQ(sut->stereo.numDisparities, 128);
    EXPECT_EQ(sut->obstacles.sectorCount, 64);
    EXPECT_DOUBLE_EQ(sut->obstacles.minHeightM, 0.10);
    EXPECT_EQ(sut->stereo.mode, MatcherMode::CensusSgm);
    EXPECT_EQ(sut->handover.spinUs, 2000);
}

TEST(Config, EveryKeyIsParsed)
{
    const std::string yaml =
        "vehicle_id: rover-7\ncalibration: /c.yaml\n"
        "camera:\n  backend: v4l2\n  left_device: /dev/video4\n  right_device: ''\n  width: 1280\n"
        "  height: 720\n  fps: 15\n  max_pair_skew_ms: 2.5\n  replay_path: /r\n  replay_pace: fixed\n  replay_fps: 60\n"
        "roi:\n  top_fraction: 0.4\n  matcher_margin_rows: 4\n"
        "stereo:\n  mode: sgbm_3way\n  num_disparities: 64\n  block_size: 7\n  ground_range: false\n"
        "  ground_range_drop_m: 0.5\n  ground_range_margin_deg: 2.5\n  half_resolution_min_ground_px: 0\n"
        "obstacles:\n  detector: both\n  sector_count: 32\n  danger_distance_m: 1\n  caution_distance_m: 4\n"
        "  min_height_m: 0.2\n  min_depth_m: 0.15\n  max_range_disparity_px: 8\n"
        "overload:\n  policy: drop\n  deadline_factor: 2\n"
        "handover:\n  spin_us: 0\n";

    const auto sut = parseConfig(yaml, "test.yaml", "/");

    ASSERT_TRUE(sut.has_value()) << joined(sut.error());
    EXPECT_EQ(sut->vehicleId, "rover-7");
    EXPECT_EQ(sut->camera.backend, CameraBackend::V4l2);
    EXPECT_EQ(sut->camera.leftDevice, "/dev/video4");
    EXPECT_EQ(sut->camera.rightDevice, "");
    EXPECT_EQ(sut->camera.width, 1280);
    EXPECT_EQ(sut->camera.height, 720);
    EXPECT_DOUBLE_EQ(sut->camera.fps, 15.0);
    EXPECT_DOUBLE_EQ(sut->camera.maxPairSkewMs, 2.5);
    EXPECT_EQ(sut->camera.replayPace, ReplayPace::Fixed);
    EXPECT_DOUBLE_EQ(sut->camera.replayFps, 60.0);
    EXPECT_DOUBLE_EQ(sut->roi.topFraction, 0.4);
    EXPECT_EQ(sut->roi.matcherMarginRows, 4);
    EXPECT_EQ(sut->stereo.mode, MatcherMode::Sgbm3Way);
    EXPECT_EQ(sut->stereo.numDisparities, 64);
    EXPECT_EQ(sut->stereo.blockSize, 7);
    EXPECT_FALSE(sut->stereo.groundRange);
    EXPECT_DOUBLE_EQ(sut->stereo.groundRangeDropM, 0.5);
    EXPECT_DOUBLE_EQ(sut->stereo.groundRangeMarginDeg, 2.5);
    EXPECT_EQ(sut->obstacles.detector, DetectorMode::Both);
    EXPECT_EQ(sut->obstacles.sectorCount, 32);
    EXPECT_DOUBLE_EQ(sut->obstacles.dangerDistanceM, 1.0);
    EXPECT_DOUBLE_EQ(sut->obstacles.cautionDistanceM, 4.0);
    EXPECT_DOUBLE_EQ(sut->obstacles.minHeightM, 0.2);
    EXPECT_DOUBLE_EQ(sut->obstacles.minDepthM, 0.15);
    EXPECT_DOUBLE_EQ(sut->obstacles.maxRangeDisparityPx, 8.0);
    EXPECT_EQ(sut->overload.policy, OverloadChoice::Drop);
    EXPECT_DOUBLE_EQ(sut->overload.deadlineFactor, 2.0);
    EXPECT_EQ(sut->handover.spinUs, 0);
}

TEST(Config, UnknownKeyIsAnErrorWithLineAndSuggestion)
{
    const auto errors = parseErrors(std::string(kValidMinimal) + "stereo:\n  num_disparites: 64\n");

    ASSERT_EQ(errors.size(), 1u);
    EXPECT_EQ(errors[0].where, "test.yaml:5 (stereo.num_disparites)");
    EXPECT_EQ(errors[0].what, "unknown key");
    EXPECT_NE(errors[0].fix.find("did you mean 'stereo.num_disparities'"), std::string::npos);
}

TEST(Config, OutOfRangeValueNamesKeyValueAndRange)
{
    const auto errors = parseErrors(std::string(kValidMinimal) + "stereo:\n  block_size: 13\n");

    ASSERT_EQ(errors.size(), 1u);
    EXPECT_EQ(errors[0].where, "test.yaml:5 (stereo.block_size)");
    EXPECT_NE(errors[0].what.find("'13'"), std::string::npos);
    EXPECT_NE(errors[0].fix.find("[1, 11]"), std::string::npos);
}

TEST(Config, CorrelatorClockSkewIsReadAndBounded)
{
    const auto sut =
        parseConfig(std::string(kValidMinimal) + "correlator:\n  max_clock_skew_ms: 250\n", "test.yaml", "/");
    ASSERT_TRUE(sut.has_value()) << joined(sut.error());
    EXPECT_DOUBLE_EQ(sut->correlator.maxClockSkewMs, 250.0);

    const auto errors = parseErrors(std::string(kValidMinimal) + "correlator:\n  max_clock_skew_ms: -1\n");
    ASSERT_EQ(errors.size(), 1u) << joined(errors);
    EXPECT_EQ(errors[0].where, "test.yaml:5 (correlator.max_clock_skew_ms)");
}

TEST(Config, CorrelatorModeTakesItsNameAndTheAliasImproved)
{
    for (const auto& [name, want] :
         {std::pair{"pose-corrected", correlator::Mode::PoseCorrected},
          std::pair{"improved", correlator::Mode::PoseCorrected}, std::pair{"original", correlator::Mode::Original}}) {
        const auto sut =
            parseConfig(std::string(kValidMinimal) + "correlator:\n  mode: " + name + "\n", "test.yaml", "/");
        ASSERT_TRUE(sut.has_value()) << name << ": " << joined(sut.error());
        EXPECT_EQ(sut->correlator.mode, want) << name;
    }

    const auto errors = parseErrors(std::string(kValidMinimal) + "correlator:\n  mode: fancy\n");
    ASSERT_EQ(errors.size(), 1u) << joined(errors);
    EXPECT_EQ(errors[0].where, "test.yaml:5 (correlator.mode)");
}

TEST(Config, NonNumbersNanAndFractionalIntegersAreRejected)
{
    for (const char* bad :
         {"fps: fast", "fps: .nan", "fps: nan", "fps: 1e999", "width: 640.5", "width: ''", "fps: [1, 2]", "fps:"}) {
        const auto errors = parseErrors(std::string(kValidMinimal) + "  " + bad + "\n");
        ASSERT_EQ(errors.size(), 1u) << bad << "\n" << joined(errors);
        EXPECT_NE(errors[0].where.find("camera."), std::string::npos) << bad;
    }
}

TEST(Config, BadChoiceListsTheAllowedValues)
{
    const auto errors = parseErrors(std::string(kValidMinimal) + "  backend: usb\n");

    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].what.find("'usb'"), std::string::npos);
    EXPECT_NE(errors[0].fix.find("v4l2 libcamera replay"), std::string::npos);
}

TEST(Config, CrossFieldRulesAreChecked)
{
    const auto errors =
        parseErrors("calibration: c\ncamera:\n  backend: replay\nstereo:\n  num_disparities: 40\n  block_size: 4\n"
                    "obstacles:\n  danger_distance_m: 5\n  caution_distance_m: 2\n");
    const std::string text = joined(errors);

    EXPECT_EQ(errors.size(), 4u) << text;
    EXPECT_NE(text.find("camera.replay_path"), std::string::npos);
    EXPECT_NE(text.find("multiple of 16"), std::string::npos);
    EXPECT_NE(text.find("is even"), std::string::npos);
    EXPECT_NE(text.find("not above danger_distance_m"), std::string::npos);
}

TEST(Config, GroundRangeNeedsTheCensusMatcherAndAPositiveDrop)
{
    const auto on = parseConfig(std::string(kValidMinimal) + "stereo:\n  ground_range: true\n", "test.yaml", "/");
    const auto errors = parseErrors(std::string(kValidMinimal) +
                                    "stereo:\n  mode: sgbm\n  ground_range: true\n  ground_range_drop_m: 0\n");
    const std::string text = joined(errors);

    ASSERT_TRUE(on.has_value()) << joined(on.error());
    EXPECT_TRUE(on->stereo.groundRange);
    EXPECT_EQ(errors.size(), 2u) << text;
    EXPECT_NE(text.find("stereo.ground_range_drop_m"), std::string::npos) << text;
    EXPECT_NE(text.find("is true but stereo.mode is sgbm"), std::string::npos) << text;
}

TEST(Config, HalfResolutionRowsNeedTheCensusMatcherAndDisparitiesInThirtyTwos)
{
    const auto on =
        parseConfig(std::string(kValidMinimal) + "stereo:\n  half_resolution_min_ground_px: 48\n", "test.yaml", "/");
    ASSERT_TRUE(on.has_value()) << joined(on.error());
    EXPECT_DOUBLE_EQ(on->stereo.halfResolutionMinGroundPx, 48.0);
    for (const char* stereo : {"stereo:\n  mode: sgbm_3way\n  half_resolution_min_ground_px: 48\n",
                               "stereo:\n  num_disparities: 48\n  half_resolution_min_ground_px: 48\n",
                               "stereo:\n  half_resolution_min_ground_px: -1\n"}) {
        const auto errors = parseErrors(std::string(kValidMinimal) + stereo);
        ASSERT_EQ(errors.size(), 1u) << stereo << joined(errors);
        EXPECT_NE(errors[0].where.find("stereo.half_resolution_min_ground_px"), std::string::npos) << joined(errors);
    }
}

TEST(Config, OneCameraNeedsTheOneCameraDetector)
{
    const std::string oneCamera = "calibration: c\ncamera:\n  backend: v4l2\n  right_device: none\n";
    const auto colour = parseConfig(oneCamera + "obstacles:\n  detector: colour\n", "test.yaml", "/");
    const auto errors = parseErrors(oneCamera + "obstacles:\n  detector: both\n");
    const std::string text = joined(errors);

    ASSERT_TRUE(colour.has_value()) << joined(colour.error());
    EXPECT_EQ(colour->camera.rightDevice, kNoRightCamera);
    ASSERT_EQ(errors.size(), 1u) << text;
    EXPECT_NE(text.find("camera.right_device"), std::string::npos) << text;
    EXPECT_NE(text.find("is none (one camera) but obstacles.detector needs a stereo pair"), std::string::npos) << text;
    EXPECT_NE(text.find("set obstacles.detector: colour"), std::string::npos) << text;
}

TEST(Config, ColourFramesComeFromAYuyvCameraOrLibcameraWhenAskedAndAreRefusedFromAGreyCamera)
{
    const std::string v4l2 = "calibration: c\ncamera:\n  backend: v4l2\n";
    const auto parsed = [](const std::string& text) {
        auto config = parseConfig(text, "test.yaml", "/");
        EXPECT_TRUE(config.has_value()) << (config ? "" : joined(config.error()));
        return config.value_or(ServiceConfig{});
    };
    // auto: colour from a V4L2 yuyv camera (whatever the detector: stereo's fallback to the left camera uses it),
    // grey from a grey V4L2 camera and from libcamera unless asked (a replay has its recording's format).
    EXPECT_TRUE(captureInColour(parsed(v4l2)));
    EXPECT_TRUE(captureInColour(parsed(v4l2 + "obstacles:\n  detector: colour\n")));
    EXPECT_FALSE(captureInColour(parsed(v4l2 + "  format: grey\nobstacles:\n  detector: both\n")));
    EXPECT_FALSE(
        captureInColour(parsed("calibration: c\ncamera:\n  backend: libcamera\nobstacles:\n  detector: both\n")));
    // false: grey whatever the detector; true: as auto, but an error where no colour comes (below).
    EXPECT_TRUE(captureInColour(parsed(v4l2 + "  colour: true\n")));
    EXPECT_FALSE(captureInColour(parsed(v4l2 + "  colour: false\nobstacles:\n  detector: colour\n")));

    const std::string grey = joined(parseErrors(v4l2 + "  format: grey\n  colour: true\n"));
    EXPECT_NE(grey.find("camera.colour"), std::string::npos) << grey;
    EXPECT_NE(grey.find("is true but camera.format is grey (a grey camera has no colour)"), std::string::npos) << grey;
    // libcamera streams YUV420 whatever camera.format (a V4L2 key) says: colour when asked for.
    EXPECT_TRUE(captureInColour(parsed("calibration: c\ncamera:\n  backend: libcamera\n  colour: true\n")));
    EXPECT_TRUE(
        captureInColour(parsed("calibration: c\ncamera:\n  backend: libcamera\n  format: grey\n  colour: true\n")));
}

TEST(Config, DisparityRangeMustFitTheImage)
{
    const auto errors = parseErrors(std::string(kValidMinimal) + "  width: 128\nstereo:\n  num_disparities: 128\n");

    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].what.find("not below the image width"), std::string::npos);
}

TEST(Config, TheReachMustBeInsideTheDisparitySearch)
{
    const auto errors = parseErrors(std::string(kValidMinimal) +
                                    "stereo:\n  num_disparities: 32\nobstacles:\n  max_range_disparity_px: 40\n");

    ASSERT_EQ(errors.size(), 1u) << joined(errors);
    EXPECT_NE(errors[0].where.find("obstacles.max_range_disparity_px"), std::string::npos) << errors[0].where;
    EXPECT_NE(errors[0].what.find("not below stereo.num_disparities (32)"), std::string::npos) << errors[0].what;
    EXPECT_NE(errors[0].fix.find("lower max_range_disparity_px"), std::string::npos) << errors[0].fix;
}

TEST(Config, SectionGivenAsScalarIsAnError)
{
    const auto errors = parseErrors(std::string(kValidMinimal) + "stereo: 5\n");

    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].what.find("is a section"), std::string::npos);
}

TEST(Config, AllErrorsAreCollectedNotJustTheFirst)
{
    const auto errors = parseErrors(std::string(kValidMinimal) + "  fps: 0\n  width: 9999\nbogus: 1\n");

    EXPECT_EQ(errors.size(), 3u) << joined(errors);
}

TEST(Config, SyntaxErrorGivesLineAndColumn)
{
    const auto errors = parseErrors("camera:\n  fps: [30\n");

    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].where.find("test.yaml:"), std::string::npos);
    EXPECT_NE(errors[0].what.find("not valid YAML"), std::string::npos);
    EXPECT_NE(errors[0].fix.find("truncated"), std::string::npos);
}

TEST(Config, EmptyAndNonMapFilesAreRejected)
{
    EXPECT_EQ(parseErrors("").at(0).what, "the file is empty");
    EXPECT_EQ(parseErrors("- a\n- b\n").at(0).what, "the top level is not a map of keys");
    EXPECT_EQ(parseErrors("just text").at(0).what, "the top level is not a map of keys");
}

TEST(Config, BinaryGarbageIsAnErrorNotACrash)
{
    std::string garbage;
    for (int i = 0; i < 512; ++i) {
        garbage.push_back(static_cast<char>((i * 7919) % 256));
    }
    const auto result = parseConfig(garbage, "garbage.yaml", "/");

    EXPECT_FALSE(result.has_value());
}

// Issue 22: hostile config text is refused before yaml-cpp reads it (whose own limit said only "bad file").
TEST(ConfigHostile, DeepNestingIsRefusedWithTheLine)
{
    const std::string brackets = std::string(kValidMinimal) + "vehicle_id: " + std::string(40000, '[') + "\n";
    std::string chain = std::string(kValidMinimal) + "vehicle_id: ";
    for (int i = 0; i < 40000; ++i) {
        chain += "x: ";
    }

    for (const std::string& deep : {brackets, chain + "1\n"}) {
        const auto errors = parseErrors(deep);

        ASSERT_EQ(errors.size(), 1U);
        EXPECT_EQ(errors[0].where, "test.yaml:4");
        EXPECT_NE(errors[0].what.find("nested deeper than 16 levels"), std::string::npos) << errors[0].message();
    }
}

TEST(ConfigHostile, OverLongTextIsRefused)
{
    const auto errors = parseErrors(std::string(kValidMinimal) + "# " + std::string(300 * 1024, 'x') + "\n");

    ASSERT_EQ(errors.size(), 1U);
    EXPECT_NE(errors[0].what.find("more than the 262144 a valid file can have"), std::string::npos)
        << errors[0].message();
}

TEST(ConfigHostile, NulByteIsRefused)
{
    const auto errors = parseErrors(std::string(kValidMinimal) + std::string("vehicle_id: a\0b\n", 16));

    ASSERT_EQ(errors.size(), 1U);
    EXPECT_EQ(errors[0].where, "test.yaml:4");
    EXPECT_NE(errors[0].what.find("NUL byte"), std::string::npos) << errors[0].message();
}

TEST(ConfigHostile, DuplicateKeyNamesBothLines)
{
    const auto top = joined(parseErrors(std::string(kValidMinimal) + "vehicle_id: a\nvehicle_id: b\n"));
    EXPECT_NE(top.find("test.yaml:5 (vehicle_id): is given twice (first at line 4)"), std::string::npos) << top;
    const auto inner =
        joined(parseErrors(std::string(kValidMinimal) + "roi:\n  top_fraction: 0.5\n  top_fraction: 0.6\n"));
    EXPECT_NE(inner.find("test.yaml:6 (roi.top_fraction): is given twice (first at line 5)"), std::string::npos)
        << inner;
}

TEST(ConfigHostile, BusNamesAndDiscoveryServerAreChecked)
{
    const auto longId = joined(parseErrors(std::string(kValidMinimal) + "vehicle_id: " + std::string(200, 'v') + "\n"));
    EXPECT_NE(longId.find("(vehicle_id): '"), std::string::npos) << longId;
    EXPECT_NE(longId.find("(200 characters) is not a vehicle name (fix: give 1 to 64"), std::string::npos) << longId;

    const auto control = joined(parseErrors(std::string(kValidMinimal) + "vehicle_id: \"ugv\\t1\"\n"));
    EXPECT_NE(control.find("(vehicle_id): '(unprintable)' (5 characters) is not a vehicle name"), std::string::npos)
        << control;
    EXPECT_TRUE(parseConfig(std::string(kValidMinimal) + "vehicle_id: ugv-ä\n", "test.yaml", "/").has_value());

    for (const char* ns : {"/abc/", "abc/", "a//b", "a-b"}) {
        const auto bad = joined(parseErrors(std::string(kValidMinimal) + "dds:\n  ros_namespace: " + ns + "\n"));
        EXPECT_NE(bad.find("test.yaml:5 (dds.ros_namespace): '" + std::string(ns) + "' is not a ROS 2 namespace"),
                  std::string::npos)
            << bad;
    }
    const auto server =
        joined(parseErrors(std::string(kValidMinimal) + "dds:\n  domain_id: 1\n  discovery_server: not-an-address\n"));
    EXPECT_NE(server.find("test.yaml:6 (dds.discovery_server): bad discovery server list 'not-an-address'"),
              std::string::npos)
        << server;

    const auto good = parseConfig(std::string(kValidMinimal) +
                                      "dds:\n  ros_namespace: team/ugv1\n  discovery_server: 192.168.1.10:11811\n",
                                  "test.yaml", "/etc/ugvsense");
    EXPECT_TRUE(good.has_value()) << joined(good.error());
}

// dds.security.* (issue 22 item 4): with security on, every file is checked at start and by check-config, each error
// at its key's line with what is wrong and how to make the files.
class ConfigSecurity : public ::testing::Test {
protected:
    void SetUp() override
    {
        dir_ = std::filesystem::temp_directory_path() / ("ugv-config-security-" + std::to_string(::getpid()));
        std::filesystem::create_directories(dir_);
        write("ca.pem", kCertificate);
        write("cert.pem", kCertificate);
        write("key.pem", "-----BEGIN PRIVATE KEY-----\nAA==\n-----END PRIVATE KEY-----\n");
        write("governance.p7s", kSigned);
        write("permissions.p7s", kSigned);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }
    void write(const std::string& name, const std::string& text) const { std::ofstream(dir_ / name) << text; }
    /// A secured config whose files are in the test's folder (relative paths), `certificate` replaced.
    [[nodiscard]] std::string yaml(const std::string& certificate = "cert.pem") const
    {
        return std::string(kValidMinimal) + "dds:\n  security:\n    enabled: true\n    identity_ca: ca.pem\n" +
               "    certificate: " + certificate + "\n    private_key: key.pem\n    permissions_ca: ca.pem\n" +
               "    governance: governance.p7s\n    permissions: permissions.p7s\n";
    }

    /// The errors of `text` read from the test's folder.
    [[nodiscard]] std::string errorsIn(const std::string& text) const
    {
        auto result = parseConfig(text, "test.yaml", dir_.string());
        EXPECT_FALSE(result.has_value()) << "expected errors for:\n" << text;
        return result.has_value() ? std::string() : joined(result.error());
    }

    static constexpr const char* kCertificate = "-----BEGIN CERTIFICATE-----\nAA==\n-----END CERTIFICATE-----\n";
    static constexpr const char* kSigned =
        "MIME-Version: 1.0\nContent-Type: multipart/signed; protocol=\"application/x-pkcs7-signature\"\n";
    std::filesystem::path dir_;
};

TEST_F(ConfigSecurity, OffByDefaultAndThenNeedsNoFiles)
{
    const auto sut = parseConfig(kValidMinimal, "test.yaml", "/etc/ugvsense");

    ASSERT_TRUE(sut.has_value()) << joined(sut.error());
    EXPECT_FALSE(sut->dds.security.enabled);
}

TEST_F(ConfigSecurity, FilesThatLookRightAreAcceptedAndResolvedAgainstTheConfigsFolder)
{
    const auto sut = parseConfig(yaml(), "test.yaml", dir_.string());

    ASSERT_TRUE(sut.has_value()) << joined(sut.error());
    EXPECT_TRUE(sut->dds.security.enabled);
    EXPECT_EQ(sut->dds.security.certificate, (dir_ / "cert.pem").string());
    EXPECT_EQ(sut->dds.security.permissions, (dir_ / "permissions.p7s").string());
}

TEST_F(ConfigSecurity, EnabledWithoutFilesNamesEveryKey)
{
    const auto errors = parseErrors(std::string(kValidMinimal) + "dds:\n  security:\n    enabled: true\n");

    const std::string text = joined(errors);
    EXPECT_EQ(errors.size(), 6U) << text;
    for (const char* key :
         {"identity_ca", "certificate", "private_key", "permissions_ca", "governance", "permissions"}) {
        EXPECT_NE(text.find("(dds.security." + std::string(key) + "): is empty but dds.security.enabled is true"),
                  std::string::npos)
            << key << "\n"
            << text;
    }
    EXPECT_NE(text.find("make_security.sh"), std::string::npos) << text;
}

TEST_F(ConfigSecurity, AMissingFileIsNamedWithItsLine)
{
    const std::string text = errorsIn(yaml("missing.pem"));

    EXPECT_NE(
        text.find("test.yaml:8 (dds.security.certificate): '" + (dir_ / "missing.pem").string() + "' cannot be read"),
        std::string::npos)
        << text;
}

TEST_F(ConfigSecurity, AFileOfTheWrongKindIsRefused)
{
    const std::string text = errorsIn(yaml("key.pem"));

    EXPECT_NE(text.find("(dds.security.certificate): '" + (dir_ / "key.pem").string() +
                        "' is not this participant's certificate (PEM)"),
              std::string::npos)
        << text;
}

TEST_F(ConfigSecurity, AVehicleIdThatCannotNameAPartitionIsRefusedWhenSecured)
{
    const std::string text = errorsIn(yaml() + "vehicle_id: ugv 1\n");

    EXPECT_NE(text.find("(vehicle_id): 'ugv 1' cannot name a partition"), std::string::npos) << text;
    EXPECT_TRUE(parseConfig(std::string(kValidMinimal) + "vehicle_id: ugv 1\n", "test.yaml", "/").has_value());
}

TEST(Config, LoadConfigReportsMissingFile)
{
    const auto result = loadConfig("/nonexistent/ugvsense.yaml");

    ASSERT_FALSE(result.has_value());
    EXPECT_EQ(result.error().at(0).where, "/nonexistent/ugvsense.yaml");
    EXPECT_NE(result.error().at(0).what.find("not found"), std::string::npos);
}

TEST(Config, LoadConfigResolvesAgainstTheFilesFolder)
{
    const auto dir = std::filesystem::temp_directory_path() / "ugv-config-test";
    std::filesystem::create_directories(dir);
    const auto file = dir / "config.yaml";
    std::ofstream(file) << kValidMinimal;

    const auto sut = loadConfig(file.string());

    ASSERT_TRUE(sut.has_value());
    EXPECT_EQ(sut->calibrationPath, (dir / "calib.yaml").string());
    EXPECT_EQ(sut->sourceFile, file.string());
    std::filesystem::remove_all(dir);
}

TEST(Config, TruncatedFileIsReportedNotSilentlyDefaulted)
{
    // A config cut in the middle of a key: the partial key is unknown and named.
    const auto errors = parseErrors(std::string(kValidMinimal) + "stereo:\n  num_dispar");

    ASSERT_FALSE(errors.empty());
    EXPECT_NE(joined(errors).find("stereo"), std::string::npos);
}

TEST(Config, ShippedExampleIsValid)
{
    const auto sut = loadConfig(UGV_SOURCE_DIR "/bringup/deploy/config.example.yaml");

    ASSERT_TRUE(sut.has_value()) << joined(sut.error());
}

TEST(Config, FormatConfigRoundTrips)
{
    auto original = parseConfig(std::string(kValidMinimal) + "  fps: 12.5\nstereo:\n  mode: hh4\n", "t.yaml", "/d");
    ASSERT_TRUE(original.has_value());

    const auto again = parseConfig(formatConfig(*original), "formatted.yaml", "/");

    ASSERT_TRUE(again.has_value()) << joined(again.error());
    EXPECT_DOUBLE_EQ(again->camera.fps, 12.5);
    EXPECT_EQ(again->stereo.mode, MatcherMode::Hh4);
    EXPECT_EQ(again->calibrationPath, "/d/calib.yaml");
}

TEST(Config, TaskTableOverrides)
{
    const auto sut = parseConfig(std::string(kValidMinimal) + "tasks:\n  vision:\n    priority: 75\n    cpu: 0\n"
                                                              "  logger:\n    policy: other\n",
                                 "t.yaml", "/");

    ASSERT_TRUE(sut.has_value()) << joined(sut.error());
    const auto vision = rt::findTask(sut->tasks, "vision");
    ASSERT_TRUE(vision.has_value());
    EXPECT_EQ(vision->priority, 75);
    EXPECT_EQ(vision->cpu, 0);
    EXPECT_EQ(rt::findTask(sut->tasks, "capture")->priority, rt::findTask(rt::kDefaultTaskTable, "capture")->priority);
}

TEST(Config, InvalidTaskOverrideNamesTheTaskAndField)
{
    const auto errors = parseErrors(std::string(kValidMinimal) + "tasks:\n  vision:\n    priority: 0\n  logger:\n"
                                                                 "    policy: fifo\n  capture:\n    cpu: 1000\n");
    const std::string text = joined(errors);

    ASSERT_EQ(errors.size(), 3u) << text;
    EXPECT_NE(text.find("(tasks.vision): field 'priority' = 0"), std::string::npos) << text;
    EXPECT_NE(text.find("(tasks.logger): field 'priority' = 0"), std::string::npos) << text;
    EXPECT_NE(text.find("(tasks.capture): field 'cpu' = 1000"), std::string::npos) << text;
}

TEST(Config, UnknownTaskIsAnUnknownKey)
{
    const auto errors = parseErrors(std::string(kValidMinimal) + "tasks:\n  camera:\n    priority: 50\n");

    ASSERT_EQ(errors.size(), 1u);
    EXPECT_EQ(errors[0].what, "unknown key");
}

TEST(Config, ConfigPathPrecedence)
{
    EXPECT_EQ(configPath("/a.yaml"), "/a.yaml");
    ::setenv("UGV_CONFIG", "/env.yaml", 1); // single-threaded test
    EXPECT_EQ(configPath(nullptr), "/env.yaml");
    ::unsetenv("UGV_CONFIG");
    EXPECT_EQ(configPath(nullptr), "/etc/ugvsense/config.yaml");
}

TEST(Config, RosDomainIdIsTheDomainWhenTheFileGivesNone)
{
    ::setenv("ROS_DOMAIN_ID", "37", 1); // single-threaded test
    const auto fromRos = parseConfig(kValidMinimal, "t.yaml", "/d");
    const auto fromFile = parseConfig(std::string(kValidMinimal) + "dds:\n  domain_id: 5\n", "t.yaml", "/d");
    ::setenv("ROS_DOMAIN_ID", "233", 1);
    const auto bad = parseConfig(kValidMinimal, "t.yaml", "/d");
    ::unsetenv("ROS_DOMAIN_ID");
    const auto unset = parseConfig(kValidMinimal, "t.yaml", "/d");

    ASSERT_TRUE(fromRos.has_value()) << joined(fromRos.error());
    EXPECT_EQ(fromRos->dds.domainId, 37);
    ASSERT_TRUE(fromFile.has_value()) << joined(fromFile.error());
    EXPECT_EQ(fromFile->dds.domainId, 5); // dds.domain_id wins
    ASSERT_FALSE(bad.has_value());
    EXPECT_NE(joined(bad.error()).find("$ROS_DOMAIN_ID: '233' is not a DDS domain id"), std::string::npos)
        << joined(bad.error());
    ASSERT_TRUE(unset.has_value());
    EXPECT_EQ(unset->dds.domainId, 0);
}

TEST(Config, CalibrationEnvironmentOverride)
{
    ::setenv("UGV_CALIBRATION", "/override.yaml", 1); // single-threaded test
    const auto sut = parseConfig(kValidMinimal, "t.yaml", "/d");
    ::unsetenv("UGV_CALIBRATION");

    ASSERT_TRUE(sut.has_value());
    EXPECT_EQ(sut->calibrationPath, "/override.yaml");
}

} // namespace
} // namespace ugv::adapters
