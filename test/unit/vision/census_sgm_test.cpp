#include "ugv/vision/census_sgm.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "ugv/platform/cpu_level.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"
#include "ugv/vision/ground_plane.hpp"

namespace ugv::vision {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 96;

ConstImageViewU8 viewOf(const cv::Mat& m)
{
    return {m.ptr<std::uint8_t>(0), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step[0])};
}

/// Smoothed uniform noise: texture everywhere, so every pixel has a unique match.
cv::Mat texture(cv::Size size, int seed)
{
    cv::Mat noise(size, CV_8UC1);
    cv::RNG rng(static_cast<std::uint64_t>(seed));
    rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(noise, noise, cv::Size(3, 3), 0.8);
    return noise;
}

/// right(x) = left(x + shift): every left pixel has disparity `shift`.
cv::Mat shifted(const cv::Mat& left, int shift)
{
    cv::Mat right(left.size(), CV_8UC1, cv::Scalar(0));
    left(cv::Rect(shift, 0, left.cols - shift, left.rows)).copyTo(right(cv::Rect(0, 0, left.cols - shift, left.rows)));
    return right;
}

CensusSgm makeSut(const CensusSgmConfig& config, cv::Size size = {kWidth, kHeight})
{
    auto result = CensusSgm::create(config, size);
    EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().message());
    return std::move(result).value();
}

TEST(CensusSgm, CreateRejectsInvalidConfig)
{
    const auto rejects = [](auto change, cv::Size size = {kWidth, kHeight}) {
        CensusSgmConfig config;
        config.numDisparities = 64;
        change(config);
        return !CensusSgm::create(config, size).has_value();
    };
    EXPECT_TRUE(rejects([](CensusSgmConfig& c) { c.numDisparities = 40; }));
    EXPECT_TRUE(rejects([](CensusSgmConfig& c) { c.numDisparities = 272; }));
    EXPECT_TRUE(rejects([](CensusSgmConfig& c) { c.p2 = c.p1; }));
    EXPECT_TRUE(rejects([](CensusSgmConfig& c) { c.p2 = 224; }));
    EXPECT_TRUE(rejects([](CensusSgmConfig& c) { c.p1 = 0; }));
    EXPECT_TRUE(rejects([](CensusSgmConfig& c) { c.uniquenessRatio = 100; }));
    EXPECT_TRUE(rejects([](CensusSgmConfig& c) { c.speckleRange = -1; }));
    EXPECT_TRUE(rejects([](CensusSgmConfig& c) { c.groundPriorTolerancePx = -1.0; }));
    EXPECT_TRUE(rejects([](CensusSgmConfig&) {}, cv::Size(64, kHeight))); // not wider than the search range
    const auto error = CensusSgm::create(CensusSgmConfig{.p2 = 5}, cv::Size(kWidth, kHeight)).error();
    EXPECT_NE(error.message().find("p2"), std::string::npos) << error.message();
}

TEST(CensusSgm, ConstantShiftIsExactInTheInterior)
{
    CensusSgmConfig config;
    config.numDisparities = 64;
    for (const int shift : {0, 7, 23, 63}) {
        const cv::Mat left = texture({kWidth, kHeight}, 3);
        const cv::Mat right = shifted(left, shift);
        auto sut = makeSut(config);
        cv::Mat disp(left.size(), CV_16SC1, cv::Scalar(0));

        ASSERT_TRUE(sut.match(viewOf(left), viewOf(right), disp));

        int good = 0;
        int total = 0;
        for (int y = 4; y < kHeight - 4; ++y) {
            for (int x = config.numDisparities; x < kWidth - shift - 5; ++x) {
                ++total;
                const int d = disp.at<std::int16_t>(y, x);
                good += (d >= 0 && std::abs(d - shift * CensusSgm::kScale) <= CensusSgm::kScale / 4) ? 1 : 0;
            }
        }
        EXPECT_GT(good, total * 99 / 100) << "shift " << shift;
        // Columns without a full search range are invalid, as in OpenCV.
        EXPECT_EQ(disp.at<std::int16_t>(kHeight / 2, config.numDisparities - 2), CensusSgm::kInvalid);
    }
}

TEST(CensusSgm, TexturelessIsInvalidNotZero)
{
    const cv::Mat flat(kHeight, kWidth, CV_8UC1, cv::Scalar(128));
    auto sut = makeSut(CensusSgmConfig{.numDisparities = 64});
    cv::Mat disp(flat.size(), CV_16SC1, cv::Scalar(0));

    ASSERT_TRUE(sut.match(viewOf(flat), viewOf(flat), disp));

    EXPECT_EQ(cv::countNonZero(disp != CensusSgm::kInvalid), 0);
}

TEST(CensusSgm, RejectsWrongSizes)
{
    auto sut = makeSut(CensusSgmConfig{.numDisparities = 64});
    const cv::Mat image = texture({kWidth, kHeight}, 1);
    const cv::Mat small = texture({kWidth - 16, kHeight}, 1);
    cv::Mat disp(image.size(), CV_16SC1, cv::Scalar(7));
    cv::Mat wrongType(image.size(), CV_32FC1);

    EXPECT_FALSE(sut.match(viewOf(small), viewOf(image), disp));
    EXPECT_FALSE(sut.match(viewOf(image), viewOf(small), disp));
    EXPECT_FALSE(sut.match(viewOf(image), viewOf(image), wrongType));
    EXPECT_EQ(disp.at<std::int16_t>(0, 0), 7); // untouched
}

// The SIMD width our kernels get follows the build's x86-64 level (toolchain/cpu-level.cmake): OpenCV's headers
// outside OpenCV's build assume SSE2 unless told; at x86-64-v3 they must give 256-bit vectors.
TEST(CensusSgm, SimdWidthFollowsTheBuiltCpuLevel)
{
    const int lanes = cv::v_uint8::nlanes;
    if (std::string_view(ugv::builtCpuLevel()) == "x86-64-v3") {
        EXPECT_EQ(lanes, 32);
        EXPECT_EQ(CV_AVX2, 1);
    } else {
        EXPECT_EQ(lanes, 16) << "128-bit: SSE2 or SSE4.2 on x86-64, NEON on aarch64";
    }
    if (std::string_view(ugv::builtCpuLevel()) == "x86-64-v2") {
        EXPECT_EQ(CV_SSE4_2, 1);
    }
}

TEST(CensusSgm, SimdMatchesScalar)
{
    auto scene = sim::makeScene("box", 4.0, 5.0, sim::GroundTexture::Gravel, 11);
    ASSERT_TRUE(scene.has_value());
    auto frame = sim::render(scene.value());
    ASSERT_TRUE(frame.has_value());
    const cv::Rect roi(0, 232, 640, 248);
    const cv::Mat left = frame->left(roi).clone();
    const cv::Mat right = frame->right(roi).clone();
    // 128 (the default, whole 256-bit blocks), and counts that end in a 128-bit block (48, 16) or are one (16):
    // the kernels must neither run past the last disparity nor skip it (ASan checks the first in its build).
    // Ranged (setSearchFloor): a floor rising down the rows (the ground's: ranges that start at 16, 32, ... and
    // so end in either block width), one falling down the rows (the rows above hold stale entries below their
    // range, which must read as saturated), each also with the ground prior's shifted top path.
    struct Floor {
        const char* name;
        double b; ///< [px per row] the floor d = 0.02 x + b y + c
        double c; ///< [px]
        bool prior;
    };
    constexpr Floor kFloors[] = {{"full range", 0.0, -1.0, false},
                                 {"rising floor", 0.45, -20.0, false},
                                 {"rising floor and prior", 0.45, -20.0, true},
                                 {"falling floor", -0.45, 100.0, true}};
    for (const int disparities : {128, 48, 16}) {
        for (const int paths : {3, 5}) {
            for (const Floor& floor : kFloors) {
                SCOPED_TRACE("numDisparities " + std::to_string(disparities) + ", paths " + std::to_string(paths) +
                             ", " + floor.name);
                CensusSgmConfig simdConfig;
                simdConfig.numDisparities = disparities;
                simdConfig.paths = paths;
                CensusSgmConfig scalarConfig = simdConfig;
                scalarConfig.simd = false;
                auto simd = makeSut(simdConfig, roi.size());
                auto scalar = makeSut(scalarConfig, roi.size());
                for (CensusSgm* sut : {&simd, &scalar}) {
                    sut->setSearchFloor(0.02, floor.b, floor.c);
                    if (floor.prior) {
                        sut->setGroundPrior(0.0, 0.5, -5.0);
                    }
                }
                cv::Mat a(roi.size(), CV_16SC1);
                cv::Mat b(roi.size(), CV_16SC1);

                ASSERT_TRUE(simd.match(viewOf(left), viewOf(right), a));
                ASSERT_TRUE(scalar.match(viewOf(left), viewOf(right), b));

                EXPECT_EQ(cv::countNonZero(a != b), 0);
                EXPECT_GT(cv::countNonZero(a >= 0), roi.area() / 4); // a real disparity map, not two empty ones
                EXPECT_EQ(simd.searchedFraction(), scalar.searchedFraction());
                if (disparities > 16 && floor.c > 0.0) {
                    EXPECT_LT(simd.searchedFraction(), 1.0);
                }
            }
        }
    }
}

/// The simulator's box pair at the default ROI, and the floor of the default rig's ground (0.59 m, level) for
/// drops down to 0.3 m and a margin of 6 px: the search floor ObstacleDetector derives (RoiMatcherConfig).
struct RangedCase {
    cv::Mat left;
    cv::Mat right;
    DisparityPlane floor; ///< in ROI coordinates
};

RangedCase rangedCase(const char* scene, std::uint64_t seed)
{
    auto made = sim::makeScene(scene, 4.0, 5.0, sim::GroundTexture::Gravel, seed);
    EXPECT_TRUE(made.has_value());
    auto frame = sim::render(made.value());
    EXPECT_TRUE(frame.has_value());
    const cv::Rect roi(0, 232, 640, 248);
    const sim::Rig rig;
    const DisparityPlane ground =
        GroundPlane::fromMount(Mount{rig.heightM, rig.pitchDeg, rig.rollDeg})
            .disparityPlane(RectifiedProjection{rig.focalPx, rig.focalPx, rig.cx(), rig.cy(), rig.baselineM});
    const double scale = rig.heightM / (rig.heightM + 0.3);
    return {frame->left(roi).clone(), frame->right(roi).clone(),
            DisparityPlane{scale * ground.a, scale * ground.b, scale * (ground.c + ground.b * roi.y) - 6.0}};
}

TEST(CensusSgm, SearchFloorBelowZeroIsTheFullRange)
{
    const RangedCase pair = rangedCase("box", 11);
    auto sut = makeSut(CensusSgmConfig{}, pair.left.size());
    cv::Mat full(pair.left.size(), CV_16SC1);
    cv::Mat floored(pair.left.size(), CV_16SC1);
    cv::Mat cleared(pair.left.size(), CV_16SC1);

    ASSERT_TRUE(sut.match(viewOf(pair.left), viewOf(pair.right), full));
    sut.setSearchFloor(0.0, 0.0, -0.5); // below every disparity: nothing cut
    ASSERT_TRUE(sut.match(viewOf(pair.left), viewOf(pair.right), floored));
    const double flooredFraction = sut.searchedFraction();
    sut.setSearchFloor(pair.floor.a, pair.floor.b, pair.floor.c);
    sut.clearSearchFloor();
    ASSERT_TRUE(sut.match(viewOf(pair.left), viewOf(pair.right), cleared));

    EXPECT_EQ(cv::countNonZero(full != floored), 0);
    EXPECT_EQ(cv::countNonZero(full != cleared), 0);
    EXPECT_EQ(flooredFraction, 1.0);
    EXPECT_EQ(sut.searchedFraction(), 1.0);
}

TEST(CensusSgm, SearchFloorCutsTheRowsBelowTheGroundAndKeepsWhatLiesAbove)
{
    const RangedCase pair = rangedCase("box", 11);
    auto sut = makeSut(CensusSgmConfig{}, pair.left.size());
    cv::Mat full(pair.left.size(), CV_16SC1);
    cv::Mat ranged(pair.left.size(), CV_16SC1);
    ASSERT_TRUE(sut.match(viewOf(pair.left), viewOf(pair.right), full));
    sut.setSearchFloor(pair.floor.a, pair.floor.b, pair.floor.c);

    ASSERT_TRUE(sut.match(viewOf(pair.left), viewOf(pair.right), ranged));

    // The expected ranges: the floor at the row's lowest column, rounded down to 16, at most 112.
    long long searched = 0;
    int belowRange = 0;
    int compared = 0;
    int same = 0;
    for (int y = 0; y < ranged.rows; ++y) {
        const double atRow = pair.floor.b * y + pair.floor.c + std::min(pair.floor.a * 127, pair.floor.a * 639);
        const int lo = std::min(static_cast<int>(std::clamp(atRow, 0.0, 128.0)) / 16 * 16, 112);
        searched += 128 - lo;
        for (int x = 127; x < ranged.cols; ++x) {
            const std::int16_t d = ranged.at<std::int16_t>(y, x);
            belowRange += d >= 0 && d < lo * CensusSgm::kScale ? 1 : 0;
            const std::int16_t f = full.at<std::int16_t>(y, x);
            if (f >= (lo + 2) * CensusSgm::kScale) { // the full range found it well inside this row's range
                ++compared;
                same += d >= 0 && std::abs(d - f) <= CensusSgm::kScale / 2 ? 1 : 0;
            }
        }
    }
    const double expectedFraction = static_cast<double>(searched) / (128.0 * ranged.rows);
    std::printf("[ MEASURED ] default rig, drops to 0.3 m, margin 6 px: %.1f %% of the cost cells searched; %d of %d "
                "disparities inside the range found again within 0.5 px\n",
                100.0 * sut.searchedFraction(), same, compared);
    EXPECT_DOUBLE_EQ(sut.searchedFraction(), expectedFraction);
    EXPECT_LT(sut.searchedFraction(), 0.85);
    EXPECT_EQ(belowRange, 0);
    ASSERT_GT(compared, ranged.total() / 4);
    EXPECT_GT(same, compared * 97 / 100);
}

TEST(CensusSgm, RangedMatchDoesNotDependOnEarlierFrames)
{
    const RangedCase first = rangedCase("pole", 3);
    const RangedCase second = rangedCase("box", 11);
    auto used = makeSut(CensusSgmConfig{.paths = 5}, first.left.size());
    auto fresh = makeSut(CensusSgmConfig{.paths = 5}, first.left.size());
    cv::Mat a(first.left.size(), CV_16SC1);
    cv::Mat b(first.left.size(), CV_16SC1);
    used.setSearchFloor(0.0, -0.45, 100.0); // a falling floor leaves other values below each row's range
    ASSERT_TRUE(used.match(viewOf(first.left), viewOf(first.right), a));
    used.setSearchFloor(second.floor.a, second.floor.b, second.floor.c);
    fresh.setSearchFloor(second.floor.a, second.floor.b, second.floor.c);

    ASSERT_TRUE(used.match(viewOf(second.left), viewOf(second.right), a));
    ASSERT_TRUE(fresh.match(viewOf(second.left), viewOf(second.right), b));

    EXPECT_EQ(cv::countNonZero(a != b), 0);
}

/// Mean error [px] of `disp` against the simulator's truth over ground pixels of full-frame rows [y0, y1).
double meanGroundError(const cv::Mat& disp, const sim::RenderResult& truth, int y0, int y1)
{
    double sum = 0.0;
    int n = 0;
    for (int y = y0; y < y1; ++y) {
        for (int x = 140; x < disp.cols; ++x) {
            const std::int16_t d = disp.at<std::int16_t>(y, x);
            if (d >= 0 && truth.height.at<float>(y, x) == 0.0F && truth.disparity.at<float>(y, x) > 0.0F) {
                sum += d / 16.0 - truth.disparity.at<float>(y, x);
                ++n;
            }
        }
    }
    EXPECT_GT(n, 1000);
    return n > 0 ? sum / n : 0.0;
}

TEST(CensusSgm, GroundPriorRemovesTheTopPathsLagOnTheGround)
{
    auto scene = sim::makeScene("empty", 5.0, 0.0, sim::GroundTexture::Asphalt, 1);
    ASSERT_TRUE(scene.has_value());
    auto frame = sim::render(*scene);
    ASSERT_TRUE(frame.has_value());
    const sim::Rig rig;
    const DisparityPlane ground =
        GroundPlane::fromMount(Mount{rig.heightM, rig.pitchDeg, rig.rollDeg})
            .disparityPlane(RectifiedProjection{rig.focalPx, rig.focalPx, rig.cx(), rig.cy(), rig.baselineM});
    const cv::Size size = frame->left.size();
    cv::Mat plain(size, CV_16SC1);
    cv::Mat followed(size, CV_16SC1);
    cv::Mat refused(size, CV_16SC1);
    auto sut = makeSut(CensusSgmConfig{}, size);
    ASSERT_TRUE(sut.match(viewOf(frame->left), viewOf(frame->right), plain));
    sut.setGroundPrior(ground.a, ground.b, ground.c);
    ASSERT_TRUE(sut.match(viewOf(frame->left), viewOf(frame->right), followed));
    sut.setGroundPrior(ground.a, std::nan(""), ground.c); // refused: the plain top path
    ASSERT_TRUE(sut.match(viewOf(frame->left), viewOf(frame->right), refused));

    for (const auto& [y0, y1] : {std::pair{260, 300}, std::pair{300, 470}}) {
        const double before = meanGroundError(plain, *frame, y0, y1);
        const double after = meanGroundError(followed, *frame, y0, y1);
        std::printf("[ MEASURED ] rows %d..%d: mean error on the ground %+.3f px plain, %+.3f px with the prior\n", y0,
                    y1, before, after);
        EXPECT_LT(before, -0.1); // the lag this fixes
        EXPECT_LT(std::abs(after), 0.08);
    }
    EXPECT_EQ(cv::countNonZero(plain != refused), 0);
}

TEST(CensusSgm, NoAllocationPerMatch)
{
    const cv::Mat left = texture({640, 248}, 5);
    const cv::Mat right = shifted(left, 30);
    auto sut = makeSut(CensusSgmConfig{}, left.size());
    cv::Mat disp(left.size(), CV_16SC1);
    ASSERT_TRUE(sut.match(viewOf(left), viewOf(right), disp));

    const test::AllocationScope scope;
    for (int i = 0; i < 20; ++i) {
        // Full range, then ranged (rising and falling floors), then the full range again.
        if (i % 3 == 0) {
            sut.clearSearchFloor();
        } else {
            sut.setSearchFloor(0.01, i % 3 == 1 ? 0.3 : -0.3, i % 3 == 1 ? -10.0 : 90.0);
        }
        ASSERT_TRUE(sut.match(viewOf(left), viewOf(right), disp));
    }

    EXPECT_EQ(scope.count(), 0U);
}

} // namespace
} // namespace ugv::vision
