// `ugvsense eval --real` scoring: the per-sector truth from a synthetic disparity map (a flat road with a box and a
// kerb), the outcome of every kind of report, and the tallies.

#include "ugv/tool/real_eval.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "ugv/vision/ground_plane.hpp"

namespace {

using ugv::ObstacleKind;
using ugv::ObstacleSectors;
using ugv::Sector;
using ugv::SectorState;
using ugv::tool::RealOutcome;
using ugv::tool::RealScoringRules;
using ugv::tool::RealTally;
using ugv::tool::SectorTruth;

constexpr int kWidth = 640;
constexpr int kHeight = 480;
constexpr double kCameraHeightM = 1.0;
const ugv::vision::RectifiedProjection kProj{500.0, 500.0, 319.5, 239.5, 0.5};
const ugv::vision::GroundPlane kRoad = ugv::vision::GroundPlane::fromMount({kCameraHeightM, 0.0, 0.0});

/// The road's disparity everywhere below the horizon, with a fronto-parallel face of `heightM` at `rangeM` over
/// the columns [u0, u1) (its pixels from the road up to its top).
cv::Mat roadWithFace(double rangeM, double heightM, int u0, int u1)
{
    cv::Mat d(kHeight, kWidth, CV_32F, cv::Scalar(0));
    const double fb = kProj.fx * kProj.baselineM;
    for (int v = 0; v < kHeight; ++v) {
        for (int u = 0; u < kWidth; ++u) {
            const double ground = (v - kProj.cy) * kProj.baselineM / kCameraHeightM; // level camera
            d.at<float>(v, u) = ground > 0.0 ? static_cast<float>(ground) : 0.0F;
            // The face: rows whose ray at rangeM is between the road and heightM above it.
            const double y = (v - kProj.cy) * rangeM / kProj.fy; // below the camera at the face's depth
            if (u >= u0 && u < u1 && y <= kCameraHeightM && y >= kCameraHeightM - heightM && fb / rangeM > ground) {
                d.at<float>(v, u) = static_cast<float>(fb / rangeM);
            }
        }
    }
    return d;
}

ObstacleSectors layout(int count)
{
    ObstacleSectors s;
    const double hfov = 2.0 * std::atan(kWidth / (2.0 * kProj.fx)) * 180.0 / 3.14159265358979323846;
    ugv::initSectors(s, count, static_cast<float>(hfov));
    return s;
}

Sector report(SectorState state, float rangeM = std::numeric_limits<float>::infinity())
{
    Sector s;
    s.state = state;
    s.kind = state == SectorState::Obstacle ? ObstacleKind::Positive : ObstacleKind::None;
    s.rangeM = rangeM;
    return s;
}

TEST(RealEval, TruthFindsAFaceAtItsRangeOnlyInItsSectors)
{
    constexpr double kRangeM = 8.0;
    const cv::Mat d = roadWithFace(kRangeM, 1.0, 300, 340); // straight ahead
    const ObstacleSectors sectors = layout(16);

    const auto sut = ugv::tool::sectorTruth(d, kHeight / 2, kRoad, kProj, sectors, RealScoringRules{});

    ASSERT_EQ(sut.size(), 16U);
    for (int s = 0; s < 16; ++s) {
        const SectorTruth& t = sut[static_cast<std::size_t>(s)];
        EXPECT_TRUE(t.scored) << s;
        if (s == 7 || s == 8) {
            ASSERT_TRUE(t.hasObstacle()) << s;
            EXPECT_NEAR(t.obstacleRangeM, kRangeM, 0.05) << s;
        } else {
            EXPECT_FALSE(t.hasObstacle()) << s << " at " << t.obstacleRangeM;
        }
    }
}

TEST(RealEval, ALowKerbIsNoObstacleButAKerb)
{
    const cv::Mat d = roadWithFace(6.0, 0.15, 0, kWidth); // 15 cm across the whole view
    const auto sut = ugv::tool::sectorTruth(d, kHeight / 2, kRoad, kProj, layout(8), RealScoringRules{});

    const double edge = 6.0 / std::cos(std::atan(kWidth / (2.0 * kProj.fx))); // [m] the face at the view's edge
    for (const SectorTruth& t : sut) {
        EXPECT_FALSE(t.hasObstacle());
        EXPECT_GE(t.kerbRangeM, 5.95);
        EXPECT_LE(t.kerbRangeM, edge + 0.05);
    }
}

TEST(RealEval, SectorsWithLittleTruthAreNotScored)
{
    cv::Mat d = roadWithFace(8.0, 1.0, 300, 340);
    d.colRange(0, kWidth / 2).setTo(0); // no GT on the right half of the image (left of centre in bearing)
    const auto sut = ugv::tool::sectorTruth(d, kHeight / 2, kRoad, kProj, layout(8), RealScoringRules{});

    EXPECT_TRUE(sut[0].scored);
    EXPECT_FALSE(sut[7].scored);
    EXPECT_EQ(ugv::tool::scoreRealSector(sut[7], report(SectorState::Obstacle, 3.0F), RealScoringRules{}),
              RealOutcome::NotScored);
}

TEST(RealEval, EveryOutcome)
{
    constexpr RealScoringRules kRules;
    SectorTruth obstacle;
    obstacle.scored = true;
    obstacle.obstacleRangeM = 10.0;
    SectorTruth free;
    free.scored = true;
    SectorTruth kerbOnly = free;
    kerbOnly.kerbRangeM = 4.0;

    EXPECT_EQ(scoreRealSector(obstacle, report(SectorState::Obstacle, 10.9F), kRules), RealOutcome::Correct);
    EXPECT_EQ(scoreRealSector(obstacle, report(SectorState::Obstacle, 8.9F), kRules), RealOutcome::TooNear);
    EXPECT_EQ(scoreRealSector(obstacle, report(SectorState::Obstacle, 11.2F), kRules), RealOutcome::Missed);
    EXPECT_EQ(scoreRealSector(obstacle, report(SectorState::Clear), kRules), RealOutcome::Missed);
    EXPECT_EQ(scoreRealSector(obstacle, report(SectorState::Unknown), kRules), RealOutcome::Missed);
    EXPECT_EQ(scoreRealSector(free, report(SectorState::Obstacle, 5.0F), kRules), RealOutcome::False);
    EXPECT_EQ(scoreRealSector(free, report(SectorState::Clear), kRules), RealOutcome::FreeOk);
    EXPECT_EQ(scoreRealSector(free, report(SectorState::Obstacle, 40.0F), kRules), RealOutcome::FreeOk); // beyond 25 m
    EXPECT_EQ(scoreRealSector(kerbOnly, report(SectorState::Obstacle, 4.5F), kRules), RealOutcome::FreeOk);
    EXPECT_EQ(scoreRealSector(kerbOnly, report(SectorState::Obstacle, 6.0F), kRules), RealOutcome::False);
    // An obstacle behind a kerb: the kerb's range counts.
    SectorTruth both = obstacle;
    both.kerbRangeM = 5.0;
    EXPECT_EQ(scoreRealSector(both, report(SectorState::Obstacle, 5.2F), kRules), RealOutcome::Correct);
    // A wall 26 m away, just beyond the 25 m horizon: no obstacle sector, but a report of it is not false (its
    // tolerance reaches 27.5 m); a report at 26 m where the truth sees nothing out to 27.5 m is.
    SectorTruth beyond = free;
    beyond.obstacleRangeM = 26.0;
    EXPECT_FALSE(beyond.hasObstacle());
    EXPECT_EQ(scoreRealSector(beyond, report(SectorState::Obstacle, 26.5F), kRules), RealOutcome::FreeOk);
    EXPECT_EQ(scoreRealSector(beyond, report(SectorState::Obstacle, 20.0F), kRules), RealOutcome::False);
    EXPECT_EQ(scoreRealSector(free, report(SectorState::Obstacle, 26.0F), kRules), RealOutcome::False);
}

TEST(RealEval, TallyCountsAndRates)
{
    SectorTruth obstacle;
    obstacle.scored = true;
    obstacle.obstacleRangeM = 10.0;
    SectorTruth free;
    free.scored = true;
    RealTally sut;

    sut.add(RealOutcome::Correct, obstacle, report(SectorState::Obstacle, 10.5F));
    sut.add(RealOutcome::TooNear, obstacle, report(SectorState::Obstacle, 5.0F));
    sut.add(RealOutcome::False, free, report(SectorState::Obstacle, 5.0F));
    sut.add(RealOutcome::FreeOk, free, report(SectorState::Clear));
    sut.add(RealOutcome::NotScored, free, report(SectorState::Clear));

    EXPECT_EQ(sut.scored, 4);
    EXPECT_EQ(sut.gtObstacle, 2);
    EXPECT_DOUBLE_EQ(sut.correctRate(), 0.5);
    EXPECT_DOUBLE_EQ(sut.wrongRate(), 0.5);
    ASSERT_EQ(sut.rangeErrorsM.size(), 1U);
    EXPECT_NEAR(sut.rangeErrorsM[0], 0.5, 1e-6);
}

} // namespace

namespace {

/// A PFM file as Middlebury writes it: header, then the rows bottom-up as little-endian float32.
std::filesystem::path writePfm(const std::string& name, const std::string& header, const cv::Mat& topDown,
                               std::size_t dropBytes = 0)
{
    const auto path = std::filesystem::temp_directory_path() / ("ugv-pfm-test-" + std::to_string(::getpid()) + name);
    std::string bytes = header;
    for (int v = topDown.rows - 1; v >= 0; --v) {
        bytes.append(reinterpret_cast<const char*>(topDown.ptr<float>(v)),
                     static_cast<std::size_t>(topDown.cols) * sizeof(float));
    }
    bytes.resize(bytes.size() - dropBytes);
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

cv::Mat pfmPattern()
{
    cv::Mat m(3, 4, CV_32F);
    for (int v = 0; v < m.rows; ++v) {
        for (int u = 0; u < m.cols; ++u) {
            m.at<float>(v, u) = static_cast<float>(10 * v + u) + 0.25F;
        }
    }
    m.at<float>(1, 2) = std::numeric_limits<float>::infinity(); // no GT there
    return m;
}

} // namespace

TEST(RealEval, APfmIsReadTopRowFirstWithItsValuesAsStoredWhateverItsScale)
{
    const cv::Mat expected = pfmPattern();
    const auto path = writePfm("ok.pfm", "Pf\n4 3\n-0.003922\n", expected);
    std::string why;
    const cv::Mat read = ugv::tool::readPfmDisparity(path, cv::Size(4, 3), why);
    std::filesystem::remove(path);
    ASSERT_EQ(read.type(), CV_32FC1) << why;
    for (int v = 0; v < 3; ++v) {
        for (int u = 0; u < 4; ++u) {
            EXPECT_EQ(read.at<float>(v, u), expected.at<float>(v, u)) << v << "," << u;
        }
    }
}

TEST(RealEval, AMalformedPfmIsRefusedWithWhatIsWrong)
{
    const cv::Mat m = pfmPattern();
    const struct {
        const char* name;
        std::string header;
        std::size_t dropBytes;
        cv::Size size;
        const char* why;
    } cases[] = {
        {"colour.pfm", "PF\n4 3\n-1\n", 0, {4, 3}, "not a one-channel PFM"},
        {"size.pfm", "Pf\n4 3\n-1\n", 0, {5, 3}, "a PFM of 4x3, the index says 5x3"},
        {"big.pfm", "Pf\n4 3\n1\n", 0, {4, 3}, "big-endian"},
        {"short.pfm", "Pf\n4 3\n-1\n", 5, {4, 3}, "truncated: 43 of 48 data bytes"},
        {"empty.pfm", "", 48, {4, 3}, "not a one-channel PFM"},
    };
    for (const auto& c : cases) {
        const auto path = writePfm(c.name, c.header, m, c.dropBytes);
        std::string why;
        const cv::Mat read = ugv::tool::readPfmDisparity(path, c.size, why);
        std::filesystem::remove(path);
        EXPECT_TRUE(read.empty()) << c.name;
        EXPECT_NE(why.find(c.why), std::string::npos) << c.name << ": " << why;
    }
}

TEST(RealEval, AMountForOneDataSetAppliesToItsPairsOnly)
{
    const auto kitti = ugv::tool::parseMount("KITTI=1.65,0.5,-1");
    ASSERT_TRUE(kitti.has_value()) << kitti.error().message();
    EXPECT_EQ(kitti->dataset, "KITTI");
    EXPECT_DOUBLE_EQ(kitti->mount.heightM, 1.65);
    EXPECT_DOUBLE_EQ(kitti->mount.pitchDeg, 0.5);
    EXPECT_DOUBLE_EQ(kitti->mount.rollDeg, -1.0);
    EXPECT_TRUE(kitti->appliesTo("KITTI 2015"));
    EXPECT_TRUE(kitti->appliesTo("KITTI 2012"));
    EXPECT_FALSE(kitti->appliesTo("Middlebury 2014"));
    EXPECT_FALSE(kitti->appliesTo("")); // an index without the dataset column

    const auto every = ugv::tool::parseMount("1.65,0,0");
    ASSERT_TRUE(every.has_value()) << every.error().message();
    EXPECT_TRUE(every->appliesTo("Middlebury 2014"));
    EXPECT_TRUE(every->appliesTo(""));

    EXPECT_FALSE(ugv::tool::parseMount("=1.65,0,0").has_value());
    EXPECT_FALSE(ugv::tool::parseMount("KITTI=").has_value());
    EXPECT_FALSE(ugv::tool::parseMount("KITTI=1.65,0").has_value());
}
