// Ground mismatch on simulator renders: obstacles get labels of the right sign on their pixels, empty and
// pitched ground gets almost none; config errors; allocation-free run(); why we do not use cv::Canny.

#include "ugv/vision/ground_mismatch.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "mat_view.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/ground_warp.hpp"

namespace {

using ugv::test::view;

using ugv::vision::GroundLabel;
using ugv::vision::GroundMismatch;
using ugv::vision::GroundMismatchConfig;
using ugv::vision::GroundMismatchStatus;
using ugv::vision::WarpSpan;

constexpr int kY0 = 232; // ROI = bottom 248 rows of 480
constexpr std::uint8_t kNoGt = 255;

/// Ground-truth labels on the RIGHT image grid (where the mismatch labels live): each left pixel is splatted to
/// x - d, the nearest surface (largest disparity) wins; unseen right pixels get kNoGt.
cv::Mat rightLabels(const ugv::sim::RenderResult& frame)
{
    cv::Mat labels(frame.labels.size(), CV_8UC1, cv::Scalar(kNoGt));
    cv::Mat best(frame.labels.size(), CV_32FC1, cv::Scalar(0.0F));
    for (int y = 0; y < labels.rows; ++y) {
        for (int x = 0; x < labels.cols; ++x) {
            const float d = frame.disparity.at<float>(y, x);
            const int xr = cvRound(static_cast<float>(x) - d);
            if (d <= 0.0F || xr < 0 || xr >= labels.cols || d <= best.at<float>(y, xr)) {
                continue;
            }
            best.at<float>(y, xr) = d;
            labels.at<std::uint8_t>(y, xr) = frame.labels.at<std::uint8_t>(y, x);
        }
    }
    return labels;
}

struct Outcome {
    ugv::vision::GroundMismatchCounts counts;
    int onTarget = 0;      ///< labels of the expected kind on pixels whose GT label is the target label
    int expectedKind = 0;  ///< labels of the expected kind anywhere
    int wrongKind = 0;     ///< labels of the opposite sign on target pixels
    int targetTested = 0;  ///< tested edge pixels on the target GT label
    int falseOnGround = 0; ///< Positive/Negative/Unsure on GT ground pixels
    int groundTested = 0;
};

Outcome runScene(const std::string& name, double rangeM, std::uint8_t target, GroundLabel kind, double pitchDeg = 0.0,
                 double rollDeg = 0.0)
{
    Outcome out;
    auto scene = ugv::sim::makeScene(name, rangeM, 0.0, ugv::sim::GroundTexture::Asphalt, 3);
    EXPECT_TRUE(scene.has_value());
    scene->rig.pitchDeg = pitchDeg;
    scene->rig.rollDeg = rollDeg;
    auto frame = ugv::sim::render(*scene);
    EXPECT_TRUE(frame.has_value());
    const ugv::sim::Rig& rig = scene->rig;
    const ugv::vision::RectifiedProjection proj{rig.focalPx, rig.focalPx, rig.cx(), rig.cy(), rig.baselineM};
    const ugv::vision::DisparityPlane plane =
        ugv::vision::GroundPlane::fromMount({rig.heightM, pitchDeg, rollDeg}).disparityPlane(proj);
    const cv::Mat left = frame->left.rowRange(kY0, rig.height);
    const cv::Mat right = frame->right.rowRange(kY0, rig.height);
    const cv::Mat gt = rightLabels(*frame).rowRange(kY0, rig.height);
    cv::Mat warped(left.size(), CV_8UC1);
    std::vector<WarpSpan> spans(static_cast<std::size_t>(left.rows));
    EXPECT_EQ(ugv::vision::warpGround(view(left), plane, kY0, view(warped), spans), ugv::vision::GroundWarpStatus::Ok);
    auto sut = GroundMismatch::create(GroundMismatchConfig{});
    EXPECT_TRUE(sut.has_value());

    EXPECT_EQ(sut->run(view(left), view(right), view(warped), spans, plane, kY0), GroundMismatchStatus::Ok);

    out.counts = sut->counts();
    const GroundLabel opposite = kind == GroundLabel::Positive ? GroundLabel::Negative : GroundLabel::Positive;
    const ugv::ConstImageViewU8 labels = sut->labels();
    for (int r = 0; r < labels.height(); ++r) {
        for (int x = 0; x < labels.width(); ++x) {
            const auto l = static_cast<GroundLabel>(labels.at(x, r));
            const std::uint8_t g = gt.at<std::uint8_t>(r, x);
            if (l == GroundLabel::NotTested) {
                continue;
            }
            out.expectedKind += l == kind ? 1 : 0;
            if (g == target) {
                ++out.targetTested;
                out.onTarget += l == kind ? 1 : 0;
                out.wrongKind += l == opposite ? 1 : 0;
            }
            if (g == 0) {
                ++out.groundTested;
                out.falseOnGround += l != GroundLabel::Ground ? 1 : 0;
            }
        }
    }
    std::printf("[ MEASURE  ] %s at %.1f m (pitch %.1f): tested %d, ground %d, positive %d, negative %d, unsure %d; "
                "target px tested %d, right sign %d (coverage %.0f %%), wrong sign %d; %s labels on target %.0f %%; "
                "non-ground labels on GT ground %d of %d (%.2f %%)\n",
                name.c_str(), rangeM, pitchDeg, out.counts.tested, out.counts.ground, out.counts.positive,
                out.counts.negative, out.counts.unsure, out.targetTested, out.onTarget,
                100.0 * out.onTarget / std::max(1, out.targetTested), out.wrongKind,
                kind == GroundLabel::Positive ? "positive" : "negative",
                100.0 * out.onTarget / std::max(1, out.expectedKind), out.falseOnGround, out.groundTested,
                100.0 * out.falseOnGround / std::max(1, out.groundTested));
    return out;
}

TEST(GroundMismatch, EmptyGroundGivesAlmostNoLabels)
{
    const Outcome o = runScene("empty", 5.0, 1, GroundLabel::Positive);

    ASSERT_GT(o.counts.tested, 3000);
    const double falseRate =
        static_cast<double>(o.counts.positive + o.counts.negative + o.counts.unsure) / o.counts.tested;
    EXPECT_LT(falseRate, 0.01);
}

TEST(GroundMismatch, PitchedCameraWithPitchedModelGivesAlmostNoLabels)
{
    const Outcome o = runScene("empty", 5.0, 1, GroundLabel::Positive, 3.0, 0.0);

    ASSERT_GT(o.counts.tested, 3000);
    EXPECT_LT(static_cast<double>(o.counts.positive + o.counts.negative + o.counts.unsure) / o.counts.tested, 0.01);
}

TEST(GroundMismatch, PoleAt4mIsLabelledPositiveOnItsPixels)
{
    const Outcome o = runScene("pole", 4.0, 1, GroundLabel::Positive);

    EXPECT_GT(o.onTarget, 100);
    EXPECT_GT(o.onTarget, 0.5 * o.targetTested);
    EXPECT_GT(o.onTarget, 0.7 * o.expectedKind); // most positive labels fall on the pole
    EXPECT_LT(o.wrongKind, 0.1 * o.targetTested);
}

TEST(GroundMismatch, BoxAt3mIsLabelledPositiveOnItsPixels)
{
    const Outcome o = runScene("box", 3.0, 1, GroundLabel::Positive);

    EXPECT_GT(o.onTarget, 100);
    EXPECT_GT(o.onTarget, 0.5 * o.targetTested);
    EXPECT_GT(o.onTarget, 0.7 * o.expectedKind);
    EXPECT_LT(o.wrongKind, 0.1 * o.targetTested);
}

// Negative obstacles at 3 m are small in the image (a 1 m trench spans ~27 rows) and their far walls are dark
// and low in texture, so coverage is low (measured 10-25 %); what is required is that the labels that do
// appear are negative and on the hole, not that the hole is covered.
TEST(GroundMismatch, TrenchAt3mIsLabelledNegativeOnItsPixels)
{
    const Outcome o = runScene("trench", 3.0, 2, GroundLabel::Negative);

    EXPECT_GE(o.onTarget, 8);
    EXPECT_GT(o.onTarget, 2 * o.wrongKind);
    EXPECT_GT(o.onTarget, 0.6 * o.expectedKind);
}

TEST(GroundMismatch, HoleAt3mIsLabelledNegativeOnItsPixels)
{
    const Outcome o = runScene("hole", 3.0, 2, GroundLabel::Negative);

    EXPECT_GE(o.onTarget, 5);
    EXPECT_GT(o.onTarget, 2 * o.wrongKind);
    EXPECT_GT(o.onTarget, 0.6 * o.expectedKind);
}

/// run() (16 residuals per universal-intrinsics step) against runReference() (one residual at a time): labels,
/// residuals and counts bit-identical on simulator frames, for level and rolled/pitched rigs (the warp's scale is
/// not 1, so the interpolation weights vary inside a window), several window sizes and residual ranges (fewer
/// than 16 residuals: the scalar path), and narrow ROIs cut at a column offset.
TEST(GroundMismatch, FastRunIsBitExactToReferenceOnSimulatorFrames)
{
    struct Case {
        const char* scene;
        double rangeM;
        double pitchDeg;
        double rollDeg;
        int halfWidth;
        int halfHeight;
        int residualMin;
        int residualMax;
        int x0;
        int width;
    };
    constexpr Case kCases[] = {
        {"box", 3.0, 0.0, 0.0, 3, 1, -16, 48, 0, 640},     {"pole", 4.0, 0.0, 0.0, 3, 1, -16, 48, 0, 640},
        {"hole", 3.0, 3.0, 1.0, 3, 1, -16, 48, 0, 640},    {"trench", 3.0, 0.0, -1.5, 2, 2, -20, 40, 0, 640},
        {"box", 3.0, 0.0, 0.0, 4, 4, -127, 127, 0, 640},   {"box", 3.0, 0.0, 0.0, 3, 1, -5, 7, 0, 640},
        {"person", 2.5, 0.0, 0.0, 3, 1, -16, 48, 200, 33}, {"box", 3.0, 0.0, 0.0, 3, 1, -16, 48, 251, 17},
        {"box", 3.0, 0.0, 0.0, 3, 1, -16, 48, 300, 16},    {"box", 3.0, 0.0, 0.0, 3, 1, -16, 48, 250, 1},
    };
    int notGround = 0;
    for (const Case& c : kCases) {
        auto scene = ugv::sim::makeScene(c.scene, c.rangeM, 0.0, ugv::sim::GroundTexture::Asphalt, 3);
        ASSERT_TRUE(scene.has_value());
        scene->rig.pitchDeg = c.pitchDeg;
        scene->rig.rollDeg = c.rollDeg;
        auto frame = ugv::sim::render(*scene, {}, ugv::sim::RenderOptions{1});
        ASSERT_TRUE(frame.has_value());
        const ugv::sim::Rig& rig = scene->rig;
        const ugv::vision::RectifiedProjection proj{rig.focalPx, rig.focalPx, rig.cx(), rig.cy(), rig.baselineM};
        // The model of a level mount on a tilted render, so that much of the ground is searched too.
        const ugv::vision::DisparityPlane plane =
            ugv::vision::GroundPlane::fromMount({rig.heightM, 0.0, c.rollDeg}).disparityPlane(proj);
        const cv::Mat left = frame->left.rowRange(kY0, rig.height);
        const cv::Mat right = frame->right.rowRange(kY0, rig.height).colRange(c.x0, c.x0 + c.width);
        cv::Mat warpedFull(left.size(), CV_8UC1);
        std::vector<WarpSpan> spans(static_cast<std::size_t>(left.rows));
        ASSERT_EQ(ugv::vision::warpGround(view(left), plane, kY0, view(warpedFull), spans),
                  ugv::vision::GroundWarpStatus::Ok);
        // A column window of the ROI: the spans in window coordinates; the left source stays the full row (the
        // window's left view starts at c.x0, so the model's source columns are shifted by c.x0 as well).
        const cv::Mat warped = warpedFull.colRange(c.x0, c.x0 + c.width);
        const cv::Mat leftWindow = left.colRange(c.x0, c.x0 + c.width);
        std::vector<WarpSpan> windowSpans(spans.size());
        for (std::size_t r = 0; r < spans.size(); ++r) {
            windowSpans[r] = {std::clamp(spans[r].begin - c.x0, 0, c.width),
                              std::clamp(spans[r].end - c.x0, 0, c.width)};
        }
        ugv::vision::DisparityPlane windowPlane = plane; // left x = scale (x + x0) + offset - x0 in window columns
        windowPlane.c += plane.a * c.x0;
        GroundMismatchConfig config;
        config.width = c.width;
        config.height = left.rows;
        config.windowHalfWidth = c.halfWidth;
        config.windowHalfHeight = c.halfHeight;
        config.residualMin = c.residualMin;
        config.residualMax = c.residualMax;
        auto fast = GroundMismatch::create(config);
        auto reference = GroundMismatch::create(config);
        ASSERT_TRUE(fast.has_value());
        ASSERT_TRUE(reference.has_value());

        ASSERT_EQ(fast->run(view(leftWindow), view(right), view(warped), windowSpans, windowPlane, kY0),
                  GroundMismatchStatus::Ok);
        ASSERT_EQ(reference->runReference(view(leftWindow), view(right), view(warped), windowSpans, windowPlane, kY0),
                  GroundMismatchStatus::Ok);

        int differentLabels = 0;
        int differentResiduals = 0;
        for (int r = 0; r < left.rows; ++r) {
            for (int x = 0; x < c.width; ++x) {
                differentLabels += fast->labels().at(x, r) != reference->labels().at(x, r) ? 1 : 0;
                differentResiduals += fast->residuals().at(x, r) != reference->residuals().at(x, r) ? 1 : 0;
            }
        }
        EXPECT_EQ(differentLabels, 0) << c.scene << " x0 " << c.x0 << " width " << c.width;
        EXPECT_EQ(differentResiduals, 0) << c.scene << " x0 " << c.x0 << " width " << c.width;
        EXPECT_EQ(fast->counts().tested, reference->counts().tested);
        EXPECT_EQ(fast->counts().ground, reference->counts().ground);
        EXPECT_EQ(fast->counts().positive, reference->counts().positive);
        EXPECT_EQ(fast->counts().negative, reference->counts().negative);
        EXPECT_EQ(fast->counts().unsure, reference->counts().unsure);
        notGround += reference->counts().positive + reference->counts().negative + reference->counts().unsure;
    }
    EXPECT_GT(notGround, 500); // the residual search did run
}

TEST(GroundMismatch, RejectsInvalidConfigsAndInputs)
{
    GroundMismatchConfig bad;
    bad.residualMin = 1;
    EXPECT_FALSE(GroundMismatch::create(bad).has_value());
    bad = GroundMismatchConfig{};
    bad.windowHalfWidth = 20;
    EXPECT_FALSE(GroundMismatch::create(bad).has_value());
    bad = GroundMismatchConfig{};
    bad.signRatio = 0.0F;
    EXPECT_FALSE(GroundMismatch::create(bad).has_value());

    GroundMismatchConfig config;
    config.width = 32;
    config.height = 8;
    auto sut = GroundMismatch::create(config);
    ASSERT_TRUE(sut.has_value());
    const cv::Mat image(8, 32, CV_8UC1, cv::Scalar(0));
    const cv::Mat wrong(8, 31, CV_8UC1, cv::Scalar(0));
    std::vector<WarpSpan> spans(8);
    const ugv::vision::DisparityPlane plane{0.0, 0.0, 1.0};
    EXPECT_EQ(sut->run(view(image), view(wrong), view(image), spans, plane, 0), GroundMismatchStatus::SizeMismatch);
    EXPECT_EQ(sut->run(view(image), view(image), view(image), std::span<const WarpSpan>(spans).first(7), plane, 0),
              GroundMismatchStatus::SizeMismatch);
    EXPECT_EQ(sut->run(view(image), view(image), view(image), spans, {0.0, std::nan(""), 0.0}, 0),
              GroundMismatchStatus::InvalidPlane);
    // A flat image has no edges: nothing tested.
    EXPECT_EQ(sut->run(view(image), view(image), view(image), spans, plane, 0), GroundMismatchStatus::Ok);
    EXPECT_EQ(sut->counts().tested, 0);
    EXPECT_EQ(cv::countNonZero(cv::Mat(8, 32, CV_8UC1, const_cast<std::uint8_t*>(sut->labels().data())) != 255), 0);
}

TEST(GroundMismatch, RunAllocatesNothingAndCvCannyWould)
{
    auto scene = ugv::sim::makeScene("box", 3.0, 0.0, ugv::sim::GroundTexture::Asphalt, 3);
    ASSERT_TRUE(scene.has_value());
    scene->rig.height = 300; // smaller render, same geometry near the bottom
    auto frame = ugv::sim::render(*scene);
    ASSERT_TRUE(frame.has_value());
    const int y0 = frame->left.rows / 2;
    const cv::Mat left = frame->left.rowRange(y0, frame->left.rows);
    const cv::Mat right = frame->right.rowRange(y0, frame->right.rows);
    const ugv::sim::Rig& rig = scene->rig;
    const ugv::vision::DisparityPlane plane =
        ugv::vision::GroundPlane::fromMount({rig.heightM, 0.0, 0.0})
            .disparityPlane({rig.focalPx, rig.focalPx, rig.cx(), rig.cy(), rig.baselineM});
    cv::Mat warped(left.size(), CV_8UC1);
    std::vector<WarpSpan> spans(static_cast<std::size_t>(left.rows));
    ASSERT_EQ(ugv::vision::warpGround(view(left), plane, y0, view(warped), spans), ugv::vision::GroundWarpStatus::Ok);
    GroundMismatchConfig config;
    config.width = left.cols;
    config.height = left.rows;
    auto sut = GroundMismatch::create(config);
    ASSERT_TRUE(sut.has_value());
    cv::Mat edges(right.size(), CV_8UC1);
    cv::Canny(right, edges, 50, 150); // warm-up: dst already allocated afterwards
    int ok = 0;

    {
        const ugv::test::AllocationScope scope;
        for (int i = 0; i < 300; ++i) {
            ok += sut->run(view(left), view(right), view(warped), spans, plane, y0) == GroundMismatchStatus::Ok ? 1 : 0;
        }
        EXPECT_EQ(scope.count(), 0U);
    }
    EXPECT_EQ(ok, 300);
    EXPECT_GT(sut->counts().positive, 0);

    // Why the stage has its own Sobel-x edge test: cv::Canny allocates on every call even with a preallocated dst.
    const ugv::test::AllocationScope cannyScope;
    cv::Canny(right, edges, 50, 150);
    std::printf("[ MEASURE  ] cv::Canny with preallocated dst: %zu allocations per call\n", cannyScope.count());
    EXPECT_GT(cannyScope.count(), 0U);
}

} // namespace
