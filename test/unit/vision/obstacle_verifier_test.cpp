#include "ugv/vision/obstacle_verifier.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace ugv::vision {
namespace {

constexpr int kVerifierWidth = 160;
constexpr int kVerifierHeight = 40;
constexpr int kY0 = 300;                                   ///< full-frame row of the ROI's first row
constexpr int kGroundD = 10;                               ///< [px] the ground plane's disparity everywhere
constexpr DisparityPlane kGroundDisparity{0.0, 0.0, 10.0}; ///< d_g = 10
constexpr int kObstacleD = 30;                             ///< [px]
constexpr int kBoxX0 = 70;                                 ///< columns [70, 100) of the left image hold the "obstacle"
constexpr int kBoxX1 = 100;
constexpr std::int16_t kInvalid = -16;

ObstacleVerifierConfig config()
{
    ObstacleVerifierConfig c;
    c.width = kVerifierWidth;
    c.height = kVerifierHeight;
    return c;
}

/// A textured scene: the left image is random texture; the right image shows it at the ground disparity except
/// the box columns, which it shows at kObstacleD when `withObstacle` (a real near surface).
struct Pair {
    Image<std::uint8_t> left{kVerifierWidth, kVerifierHeight};
    Image<std::uint8_t> right{kVerifierWidth, kVerifierHeight};
    Image<std::int16_t> disparity{kVerifierWidth, kVerifierHeight};
};

Pair makePair(bool withObstacle, bool textured = true)
{
    Pair p;
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> grey(20, 235);
    // Per image row one texture for the ground and one for the box's own surface; the left image shows the box
    // over its columns when `withObstacle`, the right image shows each surface at its own disparity.
    constexpr int kTexture = kVerifierWidth + 64;
    std::vector<std::uint8_t> ground(kTexture);
    std::vector<std::uint8_t> box(kTexture);
    for (int y = 0; y < kVerifierHeight; ++y) {
        for (std::size_t i = 0; i < ground.size(); ++i) {
            ground[i] = textured ? static_cast<std::uint8_t>(grey(rng)) : std::uint8_t{128};
            box[i] = textured ? static_cast<std::uint8_t>(grey(rng)) : std::uint8_t{128};
        }
        std::uint8_t* l = p.left.view().row(y);
        std::uint8_t* r = p.right.view().row(y);
        const auto inBox = [withObstacle](int xl) { return withObstacle && xl >= kBoxX0 && xl < kBoxX1; };
        for (int x = 0; x < kVerifierWidth; ++x) {
            l[x] = inBox(x) ? box[static_cast<std::size_t>(x)] : ground[static_cast<std::size_t>(x + 40)];
        }
        for (int xr = 0; xr < kVerifierWidth; ++xr) {
            // Right pixel xr sees the left pixel xr + d of the surface in front there (the box occludes).
            const int near = xr + kObstacleD;
            r[xr] = inBox(near) ? box[static_cast<std::size_t>(near)]
                                : ground[static_cast<std::size_t>(xr + kGroundD + 40)];
        }
        std::int16_t* d = p.disparity.view().row(y);
        for (int x = 0; x < kVerifierWidth; ++x) {
            d[x] = static_cast<std::int16_t>(16 * ((x >= kBoxX0 && x < kBoxX1) ? kObstacleD : kGroundD));
        }
    }
    return p;
}

int countInvalidInBox(ImageView<const std::int16_t> d)
{
    int n = 0;
    for (int y = 0; y < kVerifierHeight; ++y) {
        for (int x = kBoxX0; x < kBoxX1; ++x) {
            n += d.row(y)[x] < 0 ? 1 : 0;
        }
    }
    return n;
}

TEST(ObstacleVerifier, CreateRejectsInvalidConfig)
{
    ObstacleVerifierConfig badBelow = config();
    badBelow.belowHalfWidth = 0;
    EXPECT_FALSE(ObstacleVerifier::create(badBelow).has_value());
    badBelow = config();
    badBelow.belowHalfHeight = 5;
    EXPECT_FALSE(ObstacleVerifier::create(badBelow).has_value());
    badBelow = config();
    badBelow.refineMaxGroundPx = -1.0F;
    EXPECT_FALSE(ObstacleVerifier::create(badBelow).has_value());
    ObstacleVerifierConfig empty = config();
    empty.width = 0;
    ObstacleVerifierConfig window = config();
    window.windowHalfWidth = 8;
    ObstacleVerifierConfig ratio = config();
    ratio.acceptRatio = 1.5F;
    ObstacleVerifierConfig slide = config();
    slide.maxSlidePerRow = -1.0F;
    EXPECT_FALSE(ObstacleVerifier::create(slide).has_value());

    EXPECT_FALSE(ObstacleVerifier::create(empty).has_value());
    EXPECT_FALSE(ObstacleVerifier::create(window).has_value());
    EXPECT_FALSE(ObstacleVerifier::create(ratio).has_value());
    EXPECT_TRUE(ObstacleVerifier::create(config()).has_value());
}

TEST(ObstacleVerifier, KeepsAnObstacleTheImagesShow)
{
    const Pair p = makePair(true);
    auto sut = ObstacleVerifier::create(config()).value();

    ASSERT_EQ(sut.run(p.left.view(), p.right.view(), p.disparity.view(), kGroundDisparity, kY0), VerifyStatus::Ok);

    // The window straddles the box edge for hw = 3 columns on each side; the interior must all stand.
    int interiorRejected = 0;
    for (int y = 2; y < kVerifierHeight - 2; ++y) {
        for (int x = kBoxX0 + 3; x < kBoxX1 - 3; ++x) {
            interiorRejected += sut.disparity().row(y)[x] < 0 ? 1 : 0;
        }
    }
    EXPECT_EQ(interiorRejected, 0);
    EXPECT_GT(sut.counts().tested, 0);
}

TEST(ObstacleVerifier, RejectsAnObstacleDisparityTheGroundExplains)
{
    // The images show flat ground everywhere, but the disparity claims a near box (a matcher's fill-in).
    const Pair p = makePair(false);
    auto sut = ObstacleVerifier::create(config()).value();

    ASSERT_EQ(sut.run(p.left.view(), p.right.view(), p.disparity.view(), kGroundDisparity, kY0), VerifyStatus::Ok);

    const int analysable = (kVerifierHeight - 4) * (kBoxX1 - kBoxX0); // rows whose window fits
    EXPECT_GE(countInvalidInBox(sut.disparity()), analysable * 95 / 100);
    EXPECT_GE(sut.counts().rejected, analysable * 95 / 100);
}

TEST(ObstacleVerifier, LeavesGroundPixelsAlone)
{
    const Pair p = makePair(false);
    auto sut = ObstacleVerifier::create(config()).value();

    ASSERT_EQ(sut.run(p.left.view(), p.right.view(), p.disparity.view(), kGroundDisparity, kY0), VerifyStatus::Ok);

    for (int y = 0; y < kVerifierHeight; ++y) {
        for (int x = 0; x < kVerifierWidth; ++x) {
            if (x < kBoxX0 || x >= kBoxX1) {
                ASSERT_EQ(sut.disparity().row(y)[x], 16 * kGroundD) << x << "," << y;
            }
        }
    }
}

TEST(ObstacleVerifier, TexturelessOffGroundPixelsBecomeInvalidNeverGround)
{
    const Pair p = makePair(false, false);
    auto sut = ObstacleVerifier::create(config()).value();

    ASSERT_EQ(sut.run(p.left.view(), p.right.view(), p.disparity.view(), kGroundDisparity, kY0), VerifyStatus::Ok);

    EXPECT_GT(sut.counts().undecided, 0);
    for (int y = 2; y < kVerifierHeight - 2; ++y) {
        for (int x = kBoxX0; x < kBoxX1; ++x) {
            ASSERT_EQ(sut.disparity().row(y)[x], kInvalid) << x << "," << y; // unknown, not ground support
        }
    }
}

/// A surface over the box columns at `surfaceD` with faint texture (uniform +-amplitude grey around 60, like a
/// trench wall in shadow) in front of textured ground at disparity `groundD`; disparity map = the truth.
Pair makeFaintSurface(int groundD, int surfaceD, int amplitude)
{
    Pair p;
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> grey(20, 235);
    std::uniform_int_distribution<int> faint(60 - amplitude, 60 + amplitude);
    constexpr int kTexture = kVerifierWidth + 128;
    std::vector<std::uint8_t> ground(kTexture);
    std::vector<std::uint8_t> surface(kTexture);
    const auto inBox = [](int xl) { return xl >= kBoxX0 && xl < kBoxX1; };
    for (int y = 0; y < kVerifierHeight; ++y) {
        for (std::size_t i = 0; i < ground.size(); ++i) {
            ground[i] = static_cast<std::uint8_t>(grey(rng));
            surface[i] = static_cast<std::uint8_t>(faint(rng));
        }
        std::uint8_t* l = p.left.view().row(y);
        std::uint8_t* r = p.right.view().row(y);
        for (int x = 0; x < kVerifierWidth; ++x) {
            l[x] = inBox(x) ? surface[static_cast<std::size_t>(x)] : ground[static_cast<std::size_t>(x + 60)];
        }
        for (int xr = 0; xr < kVerifierWidth; ++xr) {
            const int onSurface = xr + surfaceD;
            r[xr] = inBox(onSurface) ? surface[static_cast<std::size_t>(onSurface)]
                                     : ground[static_cast<std::size_t>(xr + groundD + 60)];
        }
        std::int16_t* d = p.disparity.view().row(y);
        for (int x = 0; x < kVerifierWidth; ++x) {
            d[x] = static_cast<std::int16_t>(16 * (inBox(x) ? surfaceD : groundD));
        }
    }
    return p;
}

TEST(ObstacleVerifier, FaintSurfaceBelowTheGroundIsKeptAboveItIsUndecided)
{
    // Contrast about 2 grey levels: below minContrast (3) but above minContrastBelow (1). A drop's far wall with
    // that texture keeps its disparity (the ratio test decides); the same texture on a near surface (above the
    // ground, where semi-global fill-in happens) is undecided and invalidated. The images have no flat region: the
    // faint surface's own texture is the flattest, so ImageNoise reads it as the noise (2.5 x that > 3: 3 applies).
    auto sut = ObstacleVerifier::create(config()).value();
    const DisparityPlane ground{0.0, 0.0, 30.0};

    const Pair drop = makeFaintSurface(30, 10, 4);
    ASSERT_EQ(sut.run(drop.left.view(), drop.right.view(), drop.disparity.view(), ground, kY0), VerifyStatus::Ok);
    EXPECT_LT(countInvalidInBox(sut.disparity()), (kBoxX1 - kBoxX0) * kVerifierHeight / 10);

    const Pair near = makeFaintSurface(30, 50, 4);
    ASSERT_EQ(sut.run(near.left.view(), near.right.view(), near.disparity.view(), ground, kY0), VerifyStatus::Ok);
    // Inside the box, where the window holds only the faint surface (the edges see the textured ground too).
    for (int y = 2; y < kVerifierHeight - 2; ++y) {
        for (int x = kBoxX0 + 3; x < kBoxX1 - 3; ++x) {
            ASSERT_EQ(sut.disparity().row(y)[x], kInvalid) << x << "," << y;
        }
    }
}

/// The faint near surface of makeFaintSurface with the camera's noise made visible: the ground right of the box,
/// left columns [110, 160) (right columns [80, 130) at the ground's 30 px, clear of the box's [20, 50)), flat grey
/// 128 with Gaussian noise of `sigma`: the region ImageNoise reads.
Pair withFlatBand(Pair p, double sigma)
{
    std::mt19937 rng(5);
    std::normal_distribution<double> noise(0.0, sigma);
    const auto grey = [&] { return static_cast<std::uint8_t>(std::clamp(std::lround(128.0 + noise(rng)), 0L, 255L)); };
    for (int y = 0; y < kVerifierHeight; ++y) {
        for (int x = 110; x < kVerifierWidth; ++x) {
            p.left.view().row(y)[x] = grey();
            p.right.view().row(y)[x - 30] = grey();
        }
    }
    return p;
}

TEST(ObstacleVerifier, TheContrastAWindowNeedsFollowsTheCamerasNoise)
{
    // The same faint near surface (contrast about 2 grey levels) is decided by the ratio test, and kept at its true
    // disparity, when the camera's noise is 0.4 grey (KITTI's reads 0.40..0.64), and is undecided (invalidated)
    // when the noise is 2 grey: then a 2-grey pattern may be the noise itself.
    auto sut = ObstacleVerifier::create(config()).value();
    const DisparityPlane ground{0.0, 0.0, 30.0};

    const Pair quiet = withFlatBand(makeFaintSurface(30, 50, 4), 0.4);
    ASSERT_EQ(sut.run(quiet.left.view(), quiet.right.view(), quiet.disparity.view(), ground, kY0), VerifyStatus::Ok);
    EXPECT_NEAR(sut.noiseSigma(), 0.4F, 0.15F);
    EXPECT_NEAR(sut.requiredContrast(), 2.5F * sut.noiseSigma(), 1e-4F); // about 1 grey
    EXPECT_LT(countInvalidInBox(sut.disparity()), (kBoxX1 - kBoxX0) * kVerifierHeight / 10);

    const Pair noisy = withFlatBand(makeFaintSurface(30, 50, 4), 2.0);
    ASSERT_EQ(sut.run(noisy.left.view(), noisy.right.view(), noisy.disparity.view(), ground, kY0), VerifyStatus::Ok);
    EXPECT_FLOAT_EQ(sut.requiredContrast(), config().minContrast); // 2.5 x 2 = 5: at most minContrast (3)
    for (int y = 2; y < kVerifierHeight - 2; ++y) {
        for (int x = kBoxX0 + 3; x < kBoxX1 - 3; ++x) {
            ASSERT_EQ(sut.disparity().row(y)[x], kInvalid) << x << "," << y;
        }
    }
}

/// Left image `grey(x, y)`; the right image shows it shifted by `shift` px (right x = left x - shift); the disparity
/// claims `shift` everywhere.
template <class Grey>
Pair makeShifted(Grey grey, int shift)
{
    Pair p;
    for (int y = 0; y < kVerifierHeight; ++y) {
        for (int x = 0; x < kVerifierWidth; ++x) {
            p.left.view().row(y)[x] = static_cast<std::uint8_t>(grey(x, y));
            p.right.view().row(y)[x] = static_cast<std::uint8_t>(grey(x + shift, y));
            p.disparity.view().row(y)[x] = static_cast<std::int16_t>(16 * shift);
        }
    }
    return p;
}

/// Pixels whose disparity the verifier kept (not invalidated) among those `counted(x, y)`, where its windows fit in
/// the images at the ground's and a 14 px disparity (elsewhere it keeps the matcher's disparity untested).
template <class Counted>
int countKept(ImageView<const std::int16_t> d, Counted counted)
{
    int n = 0;
    for (int y = 3; y < kVerifierHeight - 3; ++y) {
        for (int x = 24; x < kVerifierWidth - 8; ++x) {
            n += d.row(y)[x] >= 0 && counted(x, y) ? 1 : 0;
        }
    }
    return n;
}

int countKept(ImageView<const std::int16_t> d)
{
    return countKept(d, [](int, int) { return true; });
}

/// A blurred step from 60 to 200 grey over about three rows (or columns), centred where `at` is 0.
int step(double at)
{
    return static_cast<int>(std::lround(130.0 + 70.0 * std::tanh(at / 1.5)));
}

/// The verifier without its aperture test (maxSlidePerRow 0) and with it (the default), each run once on one pair.
struct ApertureRuns {
    ObstacleVerifier without;
    ObstacleVerifier with;
};

ApertureRuns runWithAndWithoutAperture(const Pair& p, const DisparityPlane& ground)
{
    ObstacleVerifierConfig off = config();
    off.maxSlidePerRow = 0.0F;
    ApertureRuns runs{ObstacleVerifier::create(off).value(), ObstacleVerifier::create(config()).value()};
    EXPECT_EQ(runs.without.run(p.left.view(), p.right.view(), p.disparity.view(), ground, kY0), VerifyStatus::Ok);
    EXPECT_EQ(runs.with.run(p.left.view(), p.right.view(), p.disparity.view(), ground, kY0), VerifyStatus::Ok);
    return runs;
}

TEST(ObstacleVerifier, AnEdgeNearlyAlongTheRowsCannotPlaceAMatchAlongX)
{
    // A road marking's edge of slope 1/8 (rows per column). The right image shows it 4 px further than the ground's
    // 10 px: what half a row of contour shift between the cameras (their different gain on a blurred or clipped
    // edge) does to such an edge. The window at 14 px matches exactly, but an edge this flat cannot tell 14 px from
    // 10 px plus half a row, so the verifier must not keep an obstacle there (KITTI 000013_10 at half resolution).
    const auto edgeAt = [](double x) { return 12.0 + x / 8.0; };
    const Pair marking = makeShifted([&](int x, int y) { return step(y - edgeAt(x)); }, kGroundD + 4);
    const auto onTheEdge = [&](int x, int y) { return std::abs(y - edgeAt(x)) <= 2.0; }; // windows the edge fills
    const ApertureRuns runs = runWithAndWithoutAperture(marking, kGroundDisparity);

    EXPECT_GT(countKept(runs.without.disparity(), onTheEdge), 300); // what the ratio test alone keeps
    EXPECT_EQ(countKept(runs.with.disparity(), onTheEdge), 0);
}

TEST(ObstacleVerifier, BelowTheGroundAnEdgeNearlyAlongTheRowsIsNotReestimatedIntoADrop)
{
    // The same marking's edge over a far ground (30 px: re-matched below it), shown 4 px nearer the horizon's side
    // of the ground's disparity: the re-match finds 26 px exactly, but the edge cannot tell 26 px from 30 px plus
    // a fraction of a row, so no drop is kept on it (KITTI at JPEG quality 50: 2 false drop sectors -> 0).
    constexpr DisparityPlane farGround{0.0, 0.0, 30.0};
    const auto edgeAt = [](double x) { return 12.0 + x / 8.0; };
    const Pair marking = makeShifted([&](int x, int y) { return step(y - edgeAt(x)); }, 26);
    // The 15 x 3 re-match window fits in the right image at the ground's 30.5 px from column 38 on (nearer the
    // border it keeps the matcher's disparity untested); its 3 rows are filled by the edge within a row of it.
    const auto onTheEdge = [&](int x, int y) { return x >= 38 && std::abs(y - edgeAt(x)) <= 1.0; };
    const ApertureRuns runs = runWithAndWithoutAperture(marking, farGround);

    EXPECT_GT(runs.without.counts().refined, 100);
    EXPECT_GT(countKept(runs.without.disparity(), onTheEdge), 150);
    EXPECT_EQ(countKept(runs.with.disparity(), onTheEdge), 0);
}

TEST(ObstacleVerifier, AnEdgeAcrossTheRowsOrExactlyAlongThemWithTextureAcrossKeepsItsMatch)
{
    // A post's edge (across the rows) and a kerb's top seen square on (exactly along the rows, with the face's own
    // texture across them) at 14 px over a 10 px ground: both place the match along x, and the aperture leaves them
    // to the ratio test, which keeps them.
    const Pair post = makeShifted([](int x, int) { return step(x - 80.0); }, kGroundD + 4);
    const Pair kerb = makeShifted(
        [](int x, int y) {
            const int texture = ((x * 37) % 11) * 6 - 30; // a fixed pattern across the columns, +-30 grey
            return std::clamp(step(20.0 - y) + texture, 0, 255);
        },
        kGroundD + 4);
    for (const Pair* p : {&post, &kerb}) {
        const ApertureRuns runs = runWithAndWithoutAperture(*p, kGroundDisparity);
        EXPECT_GT(countKept(runs.with.disparity()), 100);
        EXPECT_EQ(countKept(runs.with.disparity()), countKept(runs.without.disparity()));
    }
}

TEST(ObstacleVerifier, BelowTheGroundTheDisparityIsReestimated)
{
    // A textured surface 3 px below the ground (a far wall); the matcher says 1.5 px lower still (its window
    // straddled the rim). The flat window re-matches it: within 1/4 px of the truth, and kept.
    auto sut = ObstacleVerifier::create(config()).value();
    const DisparityPlane ground{0.0, 0.0, 30.0};
    Pair wall = makeFaintSurface(30, 27, 60);
    for (int y = 0; y < kVerifierHeight; ++y) {
        for (int x = kBoxX0; x < kBoxX1; ++x) {
            wall.disparity.view().row(y)[x] = static_cast<std::int16_t>(16 * 27 - 24);
        }
    }
    ASSERT_EQ(sut.run(wall.left.view(), wall.right.view(), wall.disparity.view(), ground, kY0), VerifyStatus::Ok);
    EXPECT_GT(sut.counts().refined, 0);
    for (int y = 2; y < kVerifierHeight - 2; ++y) {
        for (int x = kBoxX0 + 8; x < kBoxX1 - 8; ++x) {
            ASSERT_NEAR(sut.disparity().row(y)[x], 16 * 27, 4) << x << "," << y;
        }
    }

    // The same wall where the ground is nearer than refineMaxGroundPx: not re-matched (the 7 x 5 test decides).
    ObstacleVerifierConfig nearConfig = config();
    nearConfig.refineMaxGroundPx = 29.0F;
    auto near = ObstacleVerifier::create(nearConfig).value();
    ASSERT_EQ(near.run(wall.left.view(), wall.right.view(), wall.disparity.view(), ground, kY0), VerifyStatus::Ok);
    EXPECT_EQ(near.counts().refined, 0);
}

TEST(ObstacleVerifier, BelowTheGroundDisparityTheGroundExplainsIsRejected)
{
    // All ground, but the matcher put a strip 3 px below it: no disparity in [d - 1, d_g - 1/2] explains the
    // images better than the ground, so the strip is invalid (never a drop).
    const Pair p = makePair(false);
    Image<std::int16_t> disparity(kVerifierWidth, kVerifierHeight);
    for (int y = 0; y < kVerifierHeight; ++y) {
        for (int x = 0; x < kVerifierWidth; ++x) {
            disparity.view().row(y)[x] = p.disparity.view().row(y)[x];
        }
        for (int x = kBoxX0; x < kBoxX1; ++x) {
            disparity.view().row(y)[x] = static_cast<std::int16_t>(16 * (kGroundD - 3));
        }
    }
    auto sut = ObstacleVerifier::create(config()).value();
    ASSERT_EQ(sut.run(p.left.view(), p.right.view(), disparity.view(), kGroundDisparity, kY0), VerifyStatus::Ok);
    EXPECT_EQ(sut.counts().refined, 0);
    for (int y = 2; y < kVerifierHeight - 2; ++y) {
        for (int x = kBoxX0; x < kBoxX1; ++x) {
            ASSERT_EQ(sut.disparity().row(y)[x], kInvalid) << x << "," << y;
        }
    }
}

TEST(ObstacleVerifier, BelowTheGroundOnWeakTextureTheBestOfManyCostsDoesNotBeatTheGround)
{
    // A painted floor: ground texture of +-2 grey levels, sensor noise (sigma 3) in the right image, and a matcher
    // strip 2 px below the ground. The re-match searches ~20 disparities; the least of their noisy costs often
    // beats the single cost at d_g by 15 % (480 of the 1080 pixels without the ground's search). The ground's own
    // search (+-1/2 px) keeps the test fair: (almost) nothing of the strip survives as a drop.
    Pair p = makeFaintSurface(30, 30, 2); // the "surface" lies on the ground: all of it is floor
    std::mt19937 rng(5);
    std::normal_distribution<double> noise(0.0, 3.0);
    for (int y = 0; y < kVerifierHeight; ++y) {
        std::uint8_t* r = p.right.view().row(y);
        for (int x = 0; x < kVerifierWidth; ++x) {
            r[x] = static_cast<std::uint8_t>(std::clamp(static_cast<int>(std::lround(r[x] + noise(rng))), 0, 255));
        }
        for (int x = kBoxX0; x < kBoxX1; ++x) {
            p.disparity.view().row(y)[x] = static_cast<std::int16_t>(16 * 28);
        }
    }
    auto sut = ObstacleVerifier::create(config()).value();
    ASSERT_EQ(sut.run(p.left.view(), p.right.view(), p.disparity.view(), DisparityPlane{0.0, 0.0, 30.0}, kY0),
              VerifyStatus::Ok);
    int kept = 0;
    for (int y = 2; y < kVerifierHeight - 2; ++y) {
        for (int x = kBoxX0; x < kBoxX1; ++x) {
            kept += sut.disparity().row(y)[x] >= 0 ? 1 : 0;
        }
    }
    EXPECT_LE(kept, (kBoxX1 - kBoxX0) * (kVerifierHeight - 4) / 50)
        << "of " << (kBoxX1 - kBoxX0) * (kVerifierHeight - 4);
}

TEST(ObstacleVerifier, WrongInputSizeGivesAllInvalid)
{
    const Pair p = makePair(true);
    Image<std::uint8_t> small(kVerifierWidth - 1, kVerifierHeight);
    auto sut = ObstacleVerifier::create(config()).value();

    EXPECT_EQ(sut.run(small.view(), p.right.view(), p.disparity.view(), kGroundDisparity, kY0),
              VerifyStatus::WrongInputSize);
    for (int y = 0; y < kVerifierHeight; ++y) {
        for (int x = 0; x < kVerifierWidth; ++x) {
            ASSERT_EQ(sut.disparity().row(y)[x], kInvalid);
        }
    }
    EXPECT_EQ(sut.run({}, p.right.view(), p.disparity.view(), kGroundDisparity, kY0), VerifyStatus::WrongInputSize);
}

TEST(ObstacleVerifier, RunAllocatesNothingOverHundredsOfFrames)
{
    const Pair p = makePair(true);
    auto sut = ObstacleVerifier::create(config()).value();
    (void)sut.run(p.left.view(), p.right.view(), p.disparity.view(), kGroundDisparity, kY0);

    const ugv::test::ThreadAllocationScope scope;
    for (int i = 0; i < 300; ++i) {
        (void)sut.run(p.left.view(), p.right.view(), p.disparity.view(), kGroundDisparity, kY0);
    }
    EXPECT_EQ(scope.count(), 0U);
}

} // namespace
} // namespace ugv::vision
