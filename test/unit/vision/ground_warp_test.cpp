// Ground-plane warp: SIMD kernel vs scalar reference vs cv::remap, span/validity rules, status codes, a
// simulator render of empty ground, and allocation-free steady state.

#include "ugv/vision/ground_warp.hpp"

#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "mat_view.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"
#include "ugv/vision/ground_plane.hpp"

namespace {

using ugv::test::view;

using ugv::vision::DisparityPlane;
using ugv::vision::GroundWarpStatus;
using ugv::vision::WarpSpan;

constexpr int kLanes = 16; // 128-bit vectors of uint8

cv::Mat randomImage(int width, int height, std::uint64_t seed)
{
    cv::Mat image(height, width, CV_8UC1);
    cv::RNG rng(seed);
    rng.fill(image, cv::RNG::UNIFORM, 0, 256);
    return image;
}

/// Small disparities (0.3..~4 px) so that narrow images still have valid pixels; a != 0 (roll).
DisparityPlane smallPlane(int y0)
{
    return DisparityPlane{0.004, 0.01, 0.3 - 0.01 * y0};
}

struct WarpCase {
    int width;
    int xOffset; ///< ROI offset inside the parent image (unaligned rows)
    int y0;
};

TEST(GroundWarp, SimdMatchesScalarReferenceForAllWidthsAndOffsets)
{
    const std::vector<WarpCase> cases = {
        {1, 0, 0},     {kLanes - 1, 3, 232}, {kLanes, 1, 100}, {kLanes + 1, 5, 232}, {2 * kLanes + 3, 7, 240},
        {640, 0, 232}, {637, 3, 300}};
    constexpr int kRows = 12;
    for (const WarpCase& c : cases) {
        for (const DisparityPlane& plane :
             {smallPlane(c.y0), DisparityPlane{0.02, 0.51, -121.0}, DisparityPlane{-0.03, 0.49, -110.0}}) {
            const cv::Mat parent = randomImage(c.width + c.xOffset + 2, kRows, 7U + static_cast<unsigned>(c.width));
            const cv::Mat left = parent(cv::Rect(c.xOffset, 0, c.width, kRows));
            cv::Mat simdParent(kRows, c.width + c.xOffset, CV_8UC1, cv::Scalar(77));
            cv::Mat simdOut = simdParent(cv::Rect(c.xOffset, 0, c.width, kRows));
            cv::Mat refOut(kRows, c.width, CV_8UC1, cv::Scalar(99));
            std::vector<WarpSpan> simdSpans(kRows);
            std::vector<WarpSpan> refSpans(kRows);

            ASSERT_EQ(ugv::vision::warpGround(view(left), plane, c.y0, view(simdOut), simdSpans), GroundWarpStatus::Ok);
            ASSERT_EQ(ugv::vision::warpGroundReference(view(left), plane, c.y0, view(refOut), refSpans),
                      GroundWarpStatus::Ok);

            for (int r = 0; r < kRows; ++r) {
                EXPECT_EQ(simdSpans[r].begin, refSpans[r].begin) << "width " << c.width << " row " << r;
                EXPECT_EQ(simdSpans[r].end, refSpans[r].end) << "width " << c.width << " row " << r;
            }
            double maxDiff = 0.0;
            cv::minMaxLoc(cv::abs(simdOut - refOut), nullptr, &maxDiff);
            EXPECT_LE(maxDiff, 1.0) << "width " << c.width << " offset " << c.xOffset; // stated tolerance
            EXPECT_EQ(maxDiff, 0.0) << "same arithmetic: expected bit-exact";
            // Pixels left of the ROI in the parent buffer are untouched.
            if (c.xOffset > 0) {
                EXPECT_EQ(simdParent.at<std::uint8_t>(0, c.xOffset - 1), 77);
            }
        }
    }
}

TEST(GroundWarp, MatchesCvRemapInsideTheValidSpanAndIsZeroOutside)
{
    constexpr int kWidth = 640;
    constexpr int kRows = 48;
    constexpr int kY0 = 300;
    const DisparityPlane plane{0.03, 0.5, -118.3}; // ~5 deg of roll equivalent, d 32..78 px
    const cv::Mat left = randomImage(kWidth, kRows, 3);
    cv::GaussianBlur(left, left, cv::Size(3, 3), 0.8);
    cv::Mat mapX(kRows, kWidth, CV_32FC1);
    cv::Mat mapY(kRows, kWidth, CV_32FC1);
    for (int r = 0; r < kRows; ++r) {
        const ugv::vision::WarpRowMap m = ugv::vision::warpRowMap(plane, kY0 + r);
        for (int x = 0; x < kWidth; ++x) {
            mapX.at<float>(r, x) = static_cast<float>(x) * m.scale + m.offset;
            mapY.at<float>(r, x) = static_cast<float>(r);
        }
    }
    cv::Mat expected;
    cv::remap(left, expected, mapX, mapY, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    cv::Mat warped(kRows, kWidth, CV_8UC1);
    std::vector<WarpSpan> spans(kRows);

    ASSERT_EQ(ugv::vision::warpGround(view(left), plane, kY0, view(warped), spans), GroundWarpStatus::Ok);

    int compared = 0;
    for (int r = 0; r < kRows; ++r) {
        ASSERT_LT(spans[r].begin, spans[r].end);
        for (int x = 0; x < kWidth; ++x) {
            const float xs = mapX.at<float>(r, x);
            const bool inside = x >= spans[r].begin && x < spans[r].end;
            // Validity rule: the 2-tap support lies inside the row (with 1/32 px rounding at the ends).
            if (xs >= 0.05F && xs <= kWidth - 1 - 0.05F) {
                EXPECT_TRUE(inside) << r << "," << x;
            }
            if (xs < -0.05F || xs > kWidth - 1 + 0.05F) {
                EXPECT_FALSE(inside) << r << "," << x;
            }
            if (inside) {
                EXPECT_LE(std::abs(warped.at<std::uint8_t>(r, x) - expected.at<std::uint8_t>(r, x)), 1)
                    << r << "," << x;
                ++compared;
            } else {
                EXPECT_EQ(warped.at<std::uint8_t>(r, x), 0) << r << "," << x;
            }
        }
    }
    EXPECT_GT(compared, kRows * kWidth / 2);
}

TEST(GroundWarp, RejectsBadSizesAndPlanesWithoutWriting)
{
    const cv::Mat left = randomImage(64, 4, 1);
    cv::Mat out(4, 64, CV_8UC1, cv::Scalar(5));
    cv::Mat narrow(4, 63, CV_8UC1, cv::Scalar(5));
    std::vector<WarpSpan> spans(4);
    std::vector<WarpSpan> shortSpans(3);
    const DisparityPlane good{0.0, 0.0, 2.0};

    EXPECT_EQ(ugv::vision::warpGround(view(left), good, 0, view(narrow), spans), GroundWarpStatus::SizeMismatch);
    EXPECT_EQ(ugv::vision::warpGround(view(left), good, 0, view(out), shortSpans), GroundWarpStatus::SizeMismatch);
    EXPECT_EQ(ugv::vision::warpGround(view(left), DisparityPlane{0.0, 0.0, std::nan("")}, 0, view(out), spans),
              GroundWarpStatus::InvalidPlane);
    EXPECT_EQ(ugv::vision::warpGroundReference(view(left), DisparityPlane{0.9, 0.0, 0.0}, 0, view(out), spans),
              GroundWarpStatus::InvalidPlane);
    EXPECT_EQ(cv::countNonZero(out != 5), 0);
    // A huge offset leaves every row invalid (zeros), without overflow.
    EXPECT_EQ(ugv::vision::warpGround(view(left), DisparityPlane{0.0, 0.0, 1e12}, 0, view(out), spans),
              GroundWarpStatus::Ok);
    EXPECT_EQ(cv::countNonZero(out), 0);
    EXPECT_EQ(spans[0].begin, spans[0].end);
}

TEST(GroundWarp, WarpedLeftMatchesRightOnSimulatedEmptyGround)
{
    auto scene = ugv::sim::makeScene("empty", 5.0, 0.0, ugv::sim::GroundTexture::Asphalt, 11);
    ASSERT_TRUE(scene.has_value());
    scene->rig.rollDeg = 2.0; // d_g varies along x
    auto frame = ugv::sim::render(*scene);
    ASSERT_TRUE(frame.has_value());
    const ugv::sim::Rig& rig = scene->rig;
    const ugv::vision::RectifiedProjection proj{rig.focalPx, rig.focalPx, rig.cx(), rig.cy(), rig.baselineM};
    const DisparityPlane plane =
        ugv::vision::GroundPlane::fromMount({rig.heightM, rig.pitchDeg, rig.rollDeg}).disparityPlane(proj);
    constexpr int kY0 = 232;
    const cv::Mat left = frame->left.rowRange(kY0, rig.height);
    const cv::Mat right = frame->right.rowRange(kY0, rig.height);
    cv::Mat warped(left.size(), CV_8UC1);
    std::vector<WarpSpan> spans(static_cast<std::size_t>(left.rows));

    ASSERT_EQ(ugv::vision::warpGround(view(left), plane, kY0, view(warped), spans), GroundWarpStatus::Ok);

    double warpedSum = 0.0;
    double rawSum = 0.0;
    int n = 0;
    for (int r = 0; r < left.rows; ++r) {
        for (int x = spans[r].begin; x < spans[r].end; ++x) {
            const int rv = right.at<std::uint8_t>(r, x);
            warpedSum += std::abs(rv - warped.at<std::uint8_t>(r, x));
            rawSum += std::abs(rv - left.at<std::uint8_t>(r, x));
            ++n;
        }
    }
    ASSERT_GT(n, left.rows * left.cols / 2);
    const double warpedMad = warpedSum / n;
    const double rawMad = rawSum / n;
    std::printf("[ MEASURE  ] empty asphalt, roll 2 deg: mean |R - W| = %.2f, mean |R - L| = %.2f grey\n", warpedMad,
                rawMad);
    EXPECT_LT(warpedMad, 4.0);
    EXPECT_LT(warpedMad * 3.0, rawMad);
}

TEST(GroundWarp, SteadyStateAllocatesNothing)
{
    const cv::Mat left = randomImage(640, 248, 5);
    cv::Mat warped(248, 640, CV_8UC1);
    std::vector<WarpSpan> spans(248);
    const DisparityPlane plane{0.0, 0.508, -121.7};
    int ok = 0;

    const ugv::test::AllocationScope scope;
    for (int i = 0; i < 300; ++i) {
        ok += ugv::vision::warpGround(view(left), plane, 232, view(warped), spans) == GroundWarpStatus::Ok ? 1 : 0;
    }
    EXPECT_EQ(scope.count(), 0U);
    EXPECT_EQ(ok, 300);
}

} // namespace
