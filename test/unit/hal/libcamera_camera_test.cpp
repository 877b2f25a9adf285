// The libcamera backend on a machine without cameras: a clear error, no crash, no hang. (With cameras present the
// test skips: the streaming path is checked on the vehicle.)

#include "ugv/hal/libcamera_camera.hpp"

#include <gtest/gtest.h>

namespace ugv::hal {
namespace {

TEST(LibcameraCamera, NoCameraIsAClearError)
{
    auto camera = LibcameraStereoCamera::open(LibcameraOptions{});
    if (camera.has_value()) {
        GTEST_SKIP() << "this machine has cameras (" << (*camera)->description()
                     << "): the error path is not reachable";
    }
    const std::string message = camera.error().message();
    EXPECT_NE(message.find("libcamera"), std::string::npos) << message;
    EXPECT_NE(message.find("no camera found"), std::string::npos) << message;
    EXPECT_NE(message.find("cam --list"), std::string::npos) << message;
}

TEST(LibcameraCamera, SideBySideWithoutACameraAndBadOptionsAreErrors)
{
    LibcameraOptions sbs;
    sbs.sideBySide = true;
    auto camera = LibcameraStereoCamera::open(sbs);
    if (camera.has_value()) {
        GTEST_SKIP() << "this machine has a camera";
    }
    EXPECT_NE(camera.error().message().find("no camera found"), std::string::npos) << camera.error().message();

    LibcameraOptions bad;
    bad.fps = 0.0;
    auto refused = LibcameraStereoCamera::open(bad);
    ASSERT_FALSE(refused.has_value());
    EXPECT_NE(refused.error().message().find("out of range"), std::string::npos);

    LibcameraOptions oddColour;
    oddColour.colour = true;
    oddColour.width = 641;
    auto odd = LibcameraStereoCamera::open(oddColour);
    ASSERT_FALSE(odd.has_value());
    EXPECT_NE(odd.error().message().find("colour frames need an even width and height"), std::string::npos)
        << odd.error().message();
}

} // namespace
} // namespace ugv::hal
