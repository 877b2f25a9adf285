// Golden hashes: the kernels that promise bit-exact integer output give the same bytes on every target. Each test
// runs a kernel (SIMD path and scalar reference) on a seeded synthetic input made without OpenCV (an LCG and an
// integer blur) and compares a 64-bit FNV-1a hash of the output with a constant recorded on the x86-64 build
// (SSE2). The same test runs natively in the normal test run and under qemu-aarch64 on the cross build (NEON;
// toolchain/cross.sh), so a target whose vector path or compiler changes a single output byte fails here.
//
// Covered: CensusSgm::match (integer census, 8-bit path costs, integer sub-pixel, OpenCV's integer speckle
// filter), warpGround / warpGroundReference (float coordinate rounded to 5 fractional bits, then integer
// interpolation; our code is compiled with -std=c++20, so without FMA contraction on any target), GroundMismatch
// run / runReference (integer ZSAD and residual search), ObstacleVerifier::run with simd on and off (integer
// zero-mean SAD at 1/16 px, the below-ground re-estimate), Rectifier::rectify (integer bilinear on fixed-point
// tables; the tables come from OpenCV's float initUndistortRectifyMap, and are hashed too so that a difference
// there is told apart from one in our kernel).
//
// When a kernel's algorithm changes on purpose, run `unit-vision --gtest_filter='Golden*'` natively and copy
// the printed hashes here.

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <span>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "mat_view.hpp"
#include "test_rig.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/vision/census_sgm.hpp"
#include "ugv/vision/ground_mismatch.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/ground_warp.hpp"
#include "ugv/vision/obstacle_verifier.hpp"
#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::vision {
namespace {

using ugv::test::view;

/// 64-bit FNV-1a.
class Fnv1a {
public:
    void add(const void* data, std::size_t bytes) noexcept
    {
        const auto* p = static_cast<const std::uint8_t*>(data);
        for (std::size_t i = 0; i < bytes; ++i) {
            hash_ = (hash_ ^ p[i]) * kPrime;
        }
    }
    void addInt(std::int32_t v) noexcept
    {
        // Byte order fixed here (both targets are little-endian anyway).
        const std::array<std::uint8_t, 4> bytes = {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8),
                                                   static_cast<std::uint8_t>(v >> 16),
                                                   static_cast<std::uint8_t>(v >> 24)};
        add(bytes.data(), bytes.size());
    }
    template <class T>
    void addImage(ImageView<const T> image) noexcept
    {
        for (int y = 0; y < image.height(); ++y) {
            add(image.row(y), sizeof(T) * static_cast<std::size_t>(image.width()));
        }
    }
    void addMat(const cv::Mat& m) noexcept
    {
        for (int y = 0; y < m.rows; ++y) {
            add(m.ptr(y), m.elemSize() * static_cast<std::size_t>(m.cols));
        }
    }
    [[nodiscard]] std::uint64_t value() const noexcept { return hash_; }

private:
    static constexpr std::uint64_t kPrime = 0x100000001b3ULL;
    std::uint64_t hash_ = 0xcbf29ce484222325ULL;
};

/// Knuth's MMIX LCG; the high byte is the pixel.
class Lcg {
public:
    explicit Lcg(std::uint64_t seed) : state_(seed) {}
    std::uint8_t next() noexcept
    {
        state_ = state_ * 6364136223846793005ULL + 1442695040888963407ULL;
        return static_cast<std::uint8_t>(state_ >> 56);
    }

private:
    std::uint64_t state_;
};

/// Noise blurred by an integer 3x3 box (replicated border): texture that matches well, no OpenCV involved.
cv::Mat texture(int width, int height, std::uint64_t seed)
{
    Lcg lcg(seed);
    cv::Mat noise(height, width, CV_8UC1);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            noise.at<std::uint8_t>(y, x) = lcg.next();
        }
    }
    cv::Mat out(height, width, CV_8UC1);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            int sum = 0;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    sum += noise.at<std::uint8_t>(std::clamp(y + dy, 0, height - 1), std::clamp(x + dx, 0, width - 1));
                }
            }
            out.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>((sum + 4) / 9);
        }
    }
    return out;
}

ImageViewU8 mutableView(cv::Mat& m)
{
    return {m.ptr<std::uint8_t>(), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step)};
}

/// Integer disparity of the synthetic scene at left pixel (x, y): ground growing down the rows, a box closer
/// than the ground and a pit farther away.
int sceneDisparity(int x, int y)
{
    if (x >= 120 && x < 180 && y >= 20 && y < 70) {
        return 40; // box
    }
    if (x >= 220 && x < 270 && y >= 60) {
        return 4; // pit
    }
    return 8 + y / 6; // ground
}

/// right(xr, y) = left(xr + d, y), the nearest surface (largest d) winning; unseen pixels from the LCG.
cv::Mat rightView(const cv::Mat& left, std::uint64_t seed)
{
    Lcg lcg(seed);
    cv::Mat right(left.size(), CV_8UC1);
    for (int y = 0; y < left.rows; ++y) {
        for (int xr = 0; xr < left.cols; ++xr) {
            int best = -1;
            for (int x = xr; x < left.cols; ++x) {
                const int d = sceneDisparity(x, y);
                if (x - d == xr && d > best) {
                    best = d;
                }
            }
            right.at<std::uint8_t>(y, xr) = best >= 0 ? left.at<std::uint8_t>(y, xr + best) : lcg.next();
        }
    }
    return right;
}

void printHash(const char* name, std::uint64_t hash)
{
    std::printf("[ GOLDEN   ] %s = 0x%016llxULL\n", name, static_cast<unsigned long long>(hash));
}

// Recorded on x86-64 (SSE2), GCC 12, OpenCV 4.6 (Debian 12).
constexpr std::uint64_t kCensusSgm3Paths = 0x2b1f0f58a9a3c4ebULL;
constexpr std::uint64_t kCensusSgm5Paths = 0x4d61043447e52afbULL;
constexpr std::uint64_t kGroundWarp = 0xcd969df459f7d0c9ULL;
constexpr std::uint64_t kGroundMismatch = 0x12fd4ff378de4f1fULL;
constexpr std::uint64_t kRectifierTables = 0xce70db439efb8d46ULL;
constexpr std::uint64_t kRectifier = 0x5ac16c3a81cccf50ULL;
constexpr std::uint64_t kObstacleVerifier = 0x6a1c8d77f504be07ULL;

TEST(Golden, CensusSgmDisparityIsTheSameOnEveryTarget)
{
    constexpr int kTextureWidth = 320;
    constexpr int kTextureHeight = 96;
    const cv::Mat left = texture(kTextureWidth, kTextureHeight, 1);
    const cv::Mat right = rightView(left, 2);
    for (const int paths : {3, 5}) {
        std::uint64_t hashes[2] = {};
        for (const bool simd : {true, false}) {
            CensusSgmConfig config;
            config.numDisparities = 64;
            config.paths = paths;
            config.simd = simd;
            auto sut = CensusSgm::create(config, cv::Size(kTextureWidth, kTextureHeight));
            ASSERT_TRUE(sut.has_value()) << sut.error().message();
            cv::Mat disp(kTextureHeight, kTextureWidth, CV_16SC1, cv::Scalar(0));
            ASSERT_TRUE(sut->match(view(left), view(right), disp));
            Fnv1a hash;
            hash.addMat(disp);
            hashes[simd ? 0 : 1] = hash.value();
            // The scene is matched at all (a hash of an all-invalid map would prove little).
            EXPECT_GT(cv::countNonZero(disp > 0), kTextureWidth * kTextureHeight / 2) << "paths " << paths;
        }
        EXPECT_EQ(hashes[0], hashes[1]) << "SIMD and scalar reference differ, paths " << paths;
        printHash(paths == 3 ? "kCensusSgm3Paths" : "kCensusSgm5Paths", hashes[0]);
        EXPECT_EQ(hashes[0], paths == 3 ? kCensusSgm3Paths : kCensusSgm5Paths) << "paths " << paths;
    }
}

/// Ground ROI: full-frame rows [kY0, kY0 + kRoiHeight) of a 640 x 480 frame.
constexpr int kRoiWidth = 640;
constexpr int kRoiHeight = 248;
constexpr int kY0 = 232;
/// d_g = a x + b y + c, with a roll (a != 0): 8 px at the ROI's top row to about 70 px at the bottom.
constexpr DisparityPlane kPlane{0.01, 0.25, -53.0};

/// The right ROI: the left seen through the plane (nearest integer disparity), a box 12 px closer and a pit 6 px
/// farther.
cv::Mat groundRight(const cv::Mat& left, std::uint64_t seed)
{
    Lcg lcg(seed);
    cv::Mat right(left.size(), CV_8UC1);
    for (int r = 0; r < left.rows; ++r) {
        const int y = kY0 + r;
        for (int xr = 0; xr < left.cols; ++xr) {
            int d = static_cast<int>(kPlane.at(xr, y) + 0.5);
            if (xr >= 200 && xr < 260 && r >= 40 && r < 140) {
                d += 12;
            } else if (xr >= 400 && xr < 470 && r >= 150) {
                d -= 6;
            }
            const int x = xr + d;
            right.at<std::uint8_t>(r, xr) = x >= 0 && x < left.cols ? left.at<std::uint8_t>(r, x) : lcg.next();
        }
    }
    return right;
}

TEST(Golden, GroundWarpAndMismatchAreTheSameOnEveryTarget)
{
    const cv::Mat left = texture(kRoiWidth, kRoiHeight, 3);
    const cv::Mat right = groundRight(left, 4);
    std::uint64_t warpHashes[2] = {};
    std::uint64_t mismatchHashes[2] = {};
    for (const bool simd : {true, false}) {
        cv::Mat warped(kRoiHeight, kRoiWidth, CV_8UC1, cv::Scalar(0));
        std::vector<WarpSpan> spans(static_cast<std::size_t>(kRoiHeight));
        const GroundWarpStatus warpStatus =
            simd ? warpGround(view(left), kPlane, kY0, mutableView(warped), spans)
                 : warpGroundReference(view(left), kPlane, kY0, mutableView(warped), spans);
        ASSERT_EQ(warpStatus, GroundWarpStatus::Ok);
        Fnv1a warpHash;
        warpHash.addMat(warped);
        for (const WarpSpan& span : spans) {
            warpHash.addInt(span.begin);
            warpHash.addInt(span.end);
        }
        warpHashes[simd ? 0 : 1] = warpHash.value();

        GroundMismatchConfig config;
        config.width = kRoiWidth;
        config.height = kRoiHeight;
        auto sut = GroundMismatch::create(config);
        ASSERT_TRUE(sut.has_value()) << sut.error().message();
        const GroundMismatchStatus status =
            simd ? sut->run(view(left), view(right), view(warped), spans, kPlane, kY0)
                 : sut->runReference(view(left), view(right), view(warped), spans, kPlane, kY0);
        ASSERT_EQ(status, GroundMismatchStatus::Ok);
        const GroundMismatchCounts& counts = sut->counts();
        EXPECT_GT(counts.positive, 100);
        EXPECT_GT(counts.negative, 100);
        Fnv1a mismatchHash;
        mismatchHash.addImage(sut->labels());
        mismatchHash.addImage(sut->residuals());
        for (const int n : {counts.tested, counts.ground, counts.positive, counts.negative, counts.unsure}) {
            mismatchHash.addInt(n);
        }
        mismatchHashes[simd ? 0 : 1] = mismatchHash.value();
    }
    EXPECT_EQ(warpHashes[0], warpHashes[1]) << "warpGround and warpGroundReference differ";
    EXPECT_EQ(mismatchHashes[0], mismatchHashes[1]) << "run and runReference differ";
    printHash("kGroundWarp", warpHashes[0]);
    printHash("kGroundMismatch", mismatchHashes[0]);
    EXPECT_EQ(warpHashes[0], kGroundWarp);
    EXPECT_EQ(mismatchHashes[0], kGroundMismatch);
}

/// The matcher's disparity for groundRight(): the scene's x16 with jitter, and every 7th pixel a wrong guess in
/// [0, 90) px, so that the verifier keeps, rejects and re-estimates.
cv::Mat matcherGuess(std::uint64_t seed)
{
    Lcg lcg(seed);
    cv::Mat disp(kRoiHeight, kRoiWidth, CV_16SC1);
    for (int r = 0; r < kRoiHeight; ++r) {
        for (int x = 0; x < kRoiWidth; ++x) {
            double d = kPlane.at(x, kY0 + r);
            if (x >= 200 && x < 260 && r >= 40 && r < 140) {
                d += 12.0;
            } else if (x >= 400 && x < 470 && r >= 150) {
                d -= 6.0;
            }
            const int jitter = static_cast<int>(lcg.next() % 17U) - 8;
            const bool wrong = (r * kRoiWidth + x) % 7 == 0;
            const unsigned random = static_cast<unsigned>(lcg.next()) << 8U | lcg.next();
            const int d16 = wrong ? static_cast<int>(random % (90U * 16U)) : static_cast<int>(d * 16.0) + jitter;
            disp.at<std::int16_t>(r, x) = static_cast<std::int16_t>(d16);
        }
    }
    return disp;
}

TEST(Golden, ObstacleVerifierIsTheSameOnEveryTarget)
{
    const cv::Mat left = texture(kRoiWidth, kRoiHeight, 7);
    const cv::Mat right = groundRight(left, 8);
    const cv::Mat guess = matcherGuess(9);
    const ImageView<const std::int16_t> guessView(reinterpret_cast<const std::int16_t*>(guess.data), guess.cols,
                                                  guess.rows, static_cast<std::ptrdiff_t>(guess.step));
    std::uint64_t hashes[2] = {};
    for (const bool simd : {true, false}) {
        ObstacleVerifierConfig config;
        config.width = kRoiWidth;
        config.height = kRoiHeight;
        config.simd = simd;
        auto sut = ObstacleVerifier::create(config);
        ASSERT_TRUE(sut.has_value()) << sut.error().message();
        ASSERT_EQ(sut->run(view(left), view(right), guessView, kPlane, kY0), VerifyStatus::Ok);
        const VerifyCounts& counts = sut->counts();
        EXPECT_GT(counts.rejected, 1000);
        EXPECT_GT(counts.refined, 100);
        EXPECT_GT(counts.tested - counts.rejected - counts.refined - counts.undecided, 1000) << "kept";
        Fnv1a hash;
        hash.addImage(sut->disparity());
        for (const int n : {counts.tested, counts.rejected, counts.refined, counts.undecided}) {
            hash.addInt(n);
        }
        hashes[simd ? 0 : 1] = hash.value();
    }
    EXPECT_EQ(hashes[0], hashes[1]) << "SIMD and scalar reference differ";
    printHash("kObstacleVerifier", hashes[0]);
    EXPECT_EQ(hashes[0], kObstacleVerifier);
}

/// A rig with distortion and a small rotation, rectification given directly (no stereoRectify).
StereoCalibration goldenCalibration()
{
    StereoCalibration c = ugv::test::distortedIntrinsics();
    c.R1 = (cv::Mat_<double>(3, 3) << 0.99995, -0.005, 0.00866, 0.00504, 0.99998, -0.00433, -0.00864, 0.00437, 0.99995);
    c.R2 = (cv::Mat_<double>(3, 3) << 0.99998, 0.003, -0.00612, -0.00297, 0.99999, 0.00285, 0.00613, -0.00283, 0.99998);
    c.P1 = (cv::Mat_<double>(3, 4) << 530, 0, 320.5, 0, 0, 530, 240.25, 0, 0, 0, 1, 0);
    c.P2 = (cv::Mat_<double>(3, 4) << 530, 0, 320.5, -63.6, 0, 530, 240.25, 0, 0, 0, 1, 0);
    return c;
}

TEST(Golden, RectifierIsTheSameOnEveryTarget)
{
    const StereoCalibration calib = goldenCalibration();
    auto sut = Rectifier::create(calib, RectifierConfig{});
    ASSERT_TRUE(sut.has_value()) << sut.error().message();
    const cv::Mat left = texture(640, 480, 5);
    const cv::Mat right = texture(640, 480, 6);
    ASSERT_EQ(sut->rectify(view(left), view(right)), RectifyStatus::Ok);

    // The fixed-point tables as Rectifier::create builds them (OpenCV's float code), hashed apart.
    Fnv1a tables;
    const Rect roi = sut->roi();
    for (int camera = 0; camera < 2; ++camera) {
        cv::Mat mapX;
        cv::Mat mapY;
        cv::initUndistortRectifyMap(camera == 0 ? calib.K1 : calib.K2, camera == 0 ? calib.D1 : calib.D2,
                                    camera == 0 ? calib.R1 : calib.R2, camera == 0 ? calib.P1 : calib.P2,
                                    calib.imageSize, CV_32FC1, mapX, mapY);
        cv::Mat mapXY;
        cv::Mat mapFrac;
        const cv::Range rows(roi.y, roi.y + roi.height);
        cv::convertMaps(mapX.rowRange(rows), mapY.rowRange(rows), mapXY, mapFrac, CV_16SC2);
        tables.addMat(mapXY);
        tables.addMat(mapFrac);
    }
    Fnv1a output;
    output.addImage(sut->rectifiedLeft());
    output.addImage(sut->rectifiedRight());
    printHash("kRectifierTables", tables.value());
    printHash("kRectifier", output.value());
    EXPECT_EQ(tables.value(), kRectifierTables) << "OpenCV's remap tables differ on this target";
    EXPECT_EQ(output.value(), kRectifier);
}

} // namespace
} // namespace ugv::vision
