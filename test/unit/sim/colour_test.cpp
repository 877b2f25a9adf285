// The simulator's colour image (RenderResult::leftColour): its luminance is the grey image, the grey image does not
// depend on it, and the materials have the documented colours.

#include <cmath>
#include <cstdint>
#include <cstdlib>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "sim_test_helpers.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"

namespace ugv::sim {
namespace {

/// The pixels where no channel of the colour image clips (0 or 255): there the luminance must match.
struct LumaCheck {
    int compared = 0;
    int worst = 0; ///< [grey levels] largest |luma(colour) - grey|
};
LumaCheck compareLuma(const RenderResult& r)
{
    cv::Mat luma;
    cv::cvtColor(r.leftColour, luma, cv::COLOR_BGR2GRAY);
    LumaCheck check;
    for (int y = 0; y < r.left.rows; ++y) {
        for (int x = 0; x < r.left.cols; ++x) {
            const cv::Vec3b c = r.leftColour.at<cv::Vec3b>(y, x);
            if (c[0] == 0 || c[1] == 0 || c[2] == 0 || c[0] == 255 || c[1] == 255 || c[2] == 255) {
                continue;
            }
            ++check.compared;
            check.worst =
                std::max(check.worst, std::abs(int(luma.at<std::uint8_t>(y, x)) - r.left.at<std::uint8_t>(y, x)));
        }
    }
    return check;
}

/// Mean B, G, R of the bottom quarter of the colour image (ground only in an empty scene).
cv::Scalar groundMean(const RenderResult& r)
{
    const int rows = r.leftColour.rows / 4;
    return cv::mean(r.leftColour.rowRange(r.leftColour.rows - rows, r.leftColour.rows));
}

/// HSV saturation 0..255 of a mean colour.
double saturation(const cv::Scalar& bgr)
{
    const double hi = std::max({bgr[0], bgr[1], bgr[2]});
    const double lo = std::min({bgr[0], bgr[1], bgr[2]});
    return hi > 0.0 ? 255.0 * (hi - lo) / hi : 0.0;
}

Scene emptyOn(GroundTexture texture)
{
    Scene scene = sceneWith(smallRig(4), {});
    scene.texture = texture;
    return scene;
}

TEST(SimColour, LuminanceOfTheColourImageIsTheGreyImageWithinOneLevel)
{
    Scene scene = sceneWith(smallRig(4), {pole(3.0, 10.0), box(4.0, -10.0), barrier(6.0, 0.0), person(5.0, 20.0),
                                          hole(5.0, -8.0, 1.0, 0.5), meshFence(7.0, 0.0, 3.0)});
    scene.texture = GroundTexture::Grass;
    scene.background.type = BackgroundType::Walls;
    ASSERT_TRUE(applyCondition(scene, "paint").has_value());
    ASSERT_TRUE(applyCondition(scene, "shadow").has_value());
    ASSERT_TRUE(applyCondition(scene, "glossy").has_value());

    const RenderResult sut = renderOk(scene);

    ASSERT_EQ(sut.leftColour.type(), CV_8UC3);
    ASSERT_EQ(sut.leftColour.size(), sut.left.size());
    const LumaCheck check = compareLuma(sut);
    EXPECT_GT(check.compared, sut.left.rows * sut.left.cols / 2); // the sky clips in blue; the rest does not
    EXPECT_LE(check.worst, 1);
}

TEST(SimColour, GreyImagesDoNotDependOnTheColours)
{
    Scene scene = sceneWith(smallRig(4), {pole(3.0, 10.0), box(4.0, -10.0)});
    const RenderResult before = renderOk(scene);
    scene.obstacles[0].chroma = chromaOf(0.0, 0.0, 255.0);
    scene.obstacles[1].chroma = chromaOf(255.0, 0.0, 0.0);
    scene.markings.yellowLines = true;

    const RenderResult sut = renderOk(scene);

    EXPECT_EQ(cv::norm(sut.left, before.left, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(sut.right, before.right, cv::NORM_INF), 0.0);
    EXPECT_GT(cv::norm(sut.leftColour, before.leftColour, cv::NORM_INF), 0.0);
}

TEST(SimColour, ChromaOfHasUnitLuminance)
{
    const Chroma sut = chromaOf(40.0, 190.0, 230.0);

    EXPECT_NEAR(0.114 * sut.b + 0.587 * sut.g + 0.299 * sut.r, 1.0, 1e-12);
    EXPECT_GT(sut.r, sut.b);
}

TEST(SimColour, GrassIsGreenerAndMoreSaturatedThanAsphalt)
{
    const cv::Scalar grass = groundMean(renderOk(emptyOn(GroundTexture::Grass)));
    const cv::Scalar asphalt = groundMean(renderOk(emptyOn(GroundTexture::Asphalt)));

    EXPECT_GT(grass[1] - (grass[0] + grass[2]) / 2.0, asphalt[1] - (asphalt[0] + asphalt[2]) / 2.0 + 20.0);
    EXPECT_GT(saturation(grass), 80.0);
    EXPECT_LT(saturation(asphalt), 30.0); // asphalt is nearly grey
}

TEST(SimColour, FloorIsGreenAndGravelIsWarm)
{
    const cv::Scalar floor = groundMean(renderOk(emptyOn(GroundTexture::PaintedFloor)));
    const cv::Scalar gravel = groundMean(renderOk(emptyOn(GroundTexture::Gravel)));

    EXPECT_GT(floor[1], floor[0]); // green epoxy: G above B and R
    EXPECT_GT(floor[1], floor[2]);
    EXPECT_GT(gravel[2], gravel[0]); // grey-brown: R above B
}

TEST(SimColour, BarrierHasRedAndWhiteStripes)
{
    // A 4 m wide, 1.5 m high barrier at 2 m fills the centre row; its stripes run diagonally.
    const RenderResult sut = renderOk(sceneWith(smallRig(4), {barrier(2.0, 0.0, 4.0, 1.5)}));
    const int y = sut.left.rows / 2 + 5;
    int red = 0;
    int neutral = 0;
    for (int x = sut.left.cols / 4; x < 3 * sut.left.cols / 4; ++x) {
        const cv::Vec3b c = sut.leftColour.at<cv::Vec3b>(y, x);
        red += c[2] > c[0] + 40 ? 1 : 0;
        neutral += std::abs(c[2] - c[0]) < 12 ? 1 : 0;
    }

    EXPECT_GT(red, 5);
    EXPECT_GT(neutral, 5);
    EXPECT_GT(defaultChroma(ObstacleType::Person).b, 2.0 * defaultChroma(ObstacleType::Person).r); // blue clothes
}

TEST(SimColour, ShadowsDarkenTheGroundWithoutChangingItsHue)
{
    Scene lit = emptyOn(GroundTexture::Grass);
    Scene shaded = lit;
    shaded.shadows.push_back(Shadow{{{0.0, -20.0}, {30.0, -20.0}, {30.0, 20.0}, {0.0, 20.0}}, 0.4});

    const cv::Scalar a = groundMean(renderOk(lit));
    const cv::Scalar b = groundMean(renderOk(shaded));

    EXPECT_LT(b[1], 0.6 * a[1]);
    EXPECT_NEAR(b[1] / b[2], a[1] / a[2], 0.15);
}

} // namespace
} // namespace ugv::sim
