// The V4L2 backend against a fake device that speaks the V4L2 protocol through the V4l2Ops seam (no camera or
// kernel module on our machines): formats, MMAP buffer ring, pairing by timestamp, sequence gaps, EAGAIN, unplug
// and reconnect, open errors, and no allocation per frame.

#include "ugv/hal/v4l2_camera.hpp"

#include <poll.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"

namespace ugv::hal {
namespace {

using std::chrono::milliseconds;

/// A frame the fake camera will deliver: every Y (or grey) byte of column x is value + (x >= split ? 100 : 0).
struct Pending {
    std::uint8_t value = 0;
    std::uint32_t sequence = 0;
    std::int64_t stampUs = 0;
    bool monotonic = true; ///< the driver's V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC
    std::uint8_t u = 128;  ///< YUYV chroma of every pixel pair (128, 128: grey)
    std::uint8_t v = 128;
};

struct FakeDevice {
    std::string path;
    bool present = true;
    bool unplugged = false;
    bool captureCapable = true;
    int eagain = 0;          ///< DQBUF fails with EAGAIN this many times first
    int shrinkWidth = 0;     ///< S_FMT answers with a width this much smaller
    std::uint32_t width = 0; ///< as set by S_FMT
    std::uint32_t height = 0;
    std::uint32_t pixfmt = 0;
    std::uint32_t stride = 0;
    std::vector<std::vector<std::uint8_t>> buffers;
    /// Buffers queued by the application, a fixed ring (no allocation in the fake's frame path either).
    struct Ring {
        std::uint32_t slots[16] = {};
        int head = 0;
        int size = 0;
        void clear() { head = size = 0; }
        bool empty() const { return size == 0; }
        void push_back(std::uint32_t v) { slots[(head + size++) % 16] = v; }
        std::uint32_t front() const { return slots[head]; }
        void pop_front()
        {
            head = (head + 1) % 16;
            --size;
        }
    } queued;
    std::deque<Pending> pending;
    int split = 1 << 30; ///< side-by-side: columns >= split are the right image
};

class FakeV4l2 {
public:
    FakeDevice& add(const std::string& path)
    {
        devices_[path].path = path;
        return devices_[path];
    }
    FakeDevice& device(const std::string& path) { return devices_[path]; }
    V4l2Ops ops() { return V4l2Ops{open, close, ioctl, mmap, munmap, poll, this}; }

private:
    static FakeV4l2& self(void* c) { return *static_cast<FakeV4l2*>(c); }
    FakeDevice* byFd(int fd)
    {
        auto it = fds_.find(fd);
        return it == fds_.end() ? nullptr : it->second;
    }
    static int open(void* c, const char* path, int /*flags*/)
    {
        auto& f = self(c);
        auto it = f.devices_.find(path);
        if (it == f.devices_.end() || !it->second.present) {
            errno = ENOENT;
            return -1;
        }
        if (it->second.unplugged) {
            errno = ENODEV;
            return -1;
        }
        const int fd = f.nextFd_++;
        f.fds_[fd] = &it->second;
        return fd;
    }
    static int close(void* c, int fd)
    {
        self(c).fds_.erase(fd);
        return 0;
    }
    static int ioctl(void* c, int fd, unsigned long request, void* arg)
    {
        FakeDevice* d = self(c).byFd(fd);
        if (d == nullptr) {
            errno = EBADF;
            return -1;
        }
        if (d->unplugged && request != VIDIOC_STREAMOFF) {
            errno = ENODEV;
            return -1;
        }
        switch (request) {
        case VIDIOC_QUERYCAP: {
            auto* cap = static_cast<v4l2_capability*>(arg);
            std::memset(cap, 0, sizeof(*cap));
            cap->capabilities =
                d->captureCapable ? (V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING) : V4L2_CAP_VIDEO_OUTPUT;
            return 0;
        }
        case VIDIOC_S_FMT: {
            auto* fmt = static_cast<v4l2_format*>(arg);
            fmt->fmt.pix.width -= static_cast<std::uint32_t>(d->shrinkWidth);
            d->width = fmt->fmt.pix.width;
            d->height = fmt->fmt.pix.height;
            d->pixfmt = fmt->fmt.pix.pixelformat;
            d->stride = d->width * (d->pixfmt == V4L2_PIX_FMT_YUYV ? 2 : 1) + 16; // padded lines
            fmt->fmt.pix.bytesperline = d->stride;
            return 0;
        }
        case VIDIOC_S_PARM:
            return 0;
        case VIDIOC_REQBUFS: {
            auto* req = static_cast<v4l2_requestbuffers*>(arg);
            d->buffers.assign(req->count, std::vector<std::uint8_t>(static_cast<std::size_t>(d->stride) * d->height));
            d->queued.clear();
            return 0;
        }
        case VIDIOC_QUERYBUF: {
            auto* buf = static_cast<v4l2_buffer*>(arg);
            buf->length = static_cast<std::uint32_t>(d->buffers[buf->index].size());
            buf->m.offset = buf->index;
            return 0;
        }
        case VIDIOC_QBUF:
            d->queued.push_back(static_cast<v4l2_buffer*>(arg)->index);
            return 0;
        case VIDIOC_STREAMON:
        case VIDIOC_STREAMOFF:
            return 0;
        case VIDIOC_DQBUF: {
            if (d->eagain > 0) {
                --d->eagain;
                errno = EAGAIN;
                return -1;
            }
            if (d->pending.empty() || d->queued.empty()) {
                errno = EAGAIN;
                return -1;
            }
            auto* buf = static_cast<v4l2_buffer*>(arg);
            const Pending p = d->pending.front();
            d->pending.pop_front();
            buf->index = d->queued.front();
            d->queued.pop_front();
            std::vector<std::uint8_t>& pixels = d->buffers[buf->index];
            const int bpp = d->pixfmt == V4L2_PIX_FMT_YUYV ? 2 : 1;
            for (std::uint32_t y = 0; y < d->height; ++y) {
                for (std::uint32_t x = 0; x < d->width; ++x) {
                    const auto v = static_cast<std::uint8_t>(p.value + (static_cast<int>(x) >= d->split ? 100 : 0));
                    pixels[y * d->stride + x * static_cast<std::uint32_t>(bpp)] = v;
                    if (bpp == 2) {
                        pixels[y * d->stride + x * 2 + 1] = x % 2 == 0 ? p.u : p.v; // Y0 U Y1 V
                    }
                }
            }
            buf->sequence = p.sequence;
            buf->timestamp.tv_sec = p.stampUs / 1'000'000;
            buf->timestamp.tv_usec = p.stampUs % 1'000'000;
            buf->bytesused = static_cast<std::uint32_t>(pixels.size());
            buf->flags = p.monotonic ? V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC : V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN;
            return 0;
        }
        default:
            errno = EINVAL;
            return -1;
        }
    }
    static void* mmap(void* c, std::size_t /*length*/, int fd, std::int64_t offset)
    {
        FakeDevice* d = self(c).byFd(fd);
        return d == nullptr ? MAP_FAILED : d->buffers[static_cast<std::size_t>(offset)].data();
    }
    static int munmap(void* /*c*/, void* /*address*/, std::size_t /*length*/) { return 0; }
    static int poll(void* c, pollfd* fds, unsigned count, int /*timeoutMs*/)
    {
        int ready = 0;
        for (unsigned i = 0; i < count; ++i) {
            FakeDevice* d = self(c).byFd(fds[i].fd);
            fds[i].revents = 0;
            if (d == nullptr || d->unplugged) {
                fds[i].revents = POLLERR;
                ++ready;
            } else if (d->eagain > 0 || (!d->pending.empty() && !d->queued.empty())) {
                fds[i].revents = POLLIN;
                ++ready;
            }
        }
        return ready;
    }

    std::map<std::string, FakeDevice> devices_;
    std::map<int, FakeDevice*> fds_;
    int nextFd_ = 100;
};

V4l2Options stereo(V4l2Format format = V4l2Format::Yuyv)
{
    V4l2Options o;
    o.leftDevice = "/dev/video0";
    o.rightDevice = "/dev/video1";
    o.width = 32;
    o.height = 8;
    o.format = format;
    return o;
}

/// A pair of fake devices, opened, its first pair grabbed.
Result<std::unique_ptr<V4l2StereoCamera>, Error> streamingPair(FakeV4l2& fake)
{
    fake.add("/dev/video0").pending = {{1, 0, 0}};
    fake.add("/dev/video1").pending = {{1, 0, 0}};
    auto camera = V4l2StereoCamera::open(stereo(), fake.ops());
    CameraFrame f;
    if (camera && (*camera)->grab(f, milliseconds(50)) != GrabStatus::Frame) {
        return Unexpected(Error{"fake pair", "no first frame", "a bug in the fake"});
    }
    return camera;
}

/// After a reconnect: one more frame on each device (sequence 9) comes out as a whole pair.
void expectAPairAgain(FakeV4l2& fake, StereoCamera& camera)
{
    fake.device("/dev/video0").pending = {{5, 9, 300'000}};
    fake.device("/dev/video1").pending = {{6, 9, 300'000}};
    CameraFrame f;
    ASSERT_EQ(camera.grab(f, milliseconds(50)), GrabStatus::Frame);
    EXPECT_EQ(f.images.left.at(0, 0), 5);
    ASSERT_FALSE(f.images.right.empty());
    EXPECT_EQ(f.images.right.at(0, 0), 6);
    EXPECT_EQ(f.sequence, 9U);
}

TEST(V4l2Camera, TwoDevicesDeliverGreyPairsWithDriverStampsAndSequences)
{
    FakeV4l2 fake;
    fake.add("/dev/video0").pending = {{10, 0, 1'000'000}, {11, 1, 1'033'333}};
    fake.add("/dev/video1").pending = {{20, 0, 1'000'400}, {21, 1, 1'033'700}};
    auto camera = V4l2StereoCamera::open(stereo(), fake.ops());
    ASSERT_TRUE(camera.has_value()) << camera.error().message();
    EXPECT_EQ((*camera)->width(), 32);

    CameraFrame f;
    ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);
    EXPECT_EQ(f.sequence, 0U);
    EXPECT_EQ(f.leftStampNs, 1'000'000'000);
    EXPECT_EQ(f.rightStampNs, 1'000'400'000);
    EXPECT_EQ(f.images.left.at(5, 3), 10); // the Y bytes of YUYV
    EXPECT_EQ(f.images.right.at(31, 7), 20);
    ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);
    EXPECT_EQ(f.sequence, 1U);
    EXPECT_EQ(f.images.left.at(0, 0), 11);
    EXPECT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Timeout); // nothing more
    EXPECT_EQ((*camera)->stats().frames, 2U);
}

TEST(V4l2Camera, StampsThatAreNotMonotonicAreReplacedByTheDequeueTime)
{
    FakeV4l2 fake;
    FakeDevice& d = fake.add("/dev/video0");
    d.pending = {{1, 0, 42, false}}; // 42 us on an unknown clock
    V4l2Options o = stereo(V4l2Format::Grey);
    o.rightDevice.clear();
    auto camera = V4l2StereoCamera::open(o, fake.ops());
    ASSERT_TRUE(camera.has_value());
    timespec before{};
    ::clock_gettime(CLOCK_MONOTONIC, &before);
    CameraFrame f;
    ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);
    const std::int64_t beforeNs = static_cast<std::int64_t>(before.tv_sec) * 1'000'000'000 + before.tv_nsec;
    EXPECT_GE(f.leftStampNs, beforeNs - 1000); // microsecond resolution
    EXPECT_NE(f.leftStampNs, 42'000);
}

TEST(V4l2Camera, SideBySideDeviceIsSplitIntoLeftAndRight)
{
    FakeV4l2 fake;
    FakeDevice& d = fake.add("/dev/video0");
    d.split = 32;
    d.pending = {{40, 7, 5'000'000}};
    V4l2Options o = stereo(V4l2Format::Grey);
    o.rightDevice.clear();
    auto camera = V4l2StereoCamera::open(o, fake.ops());
    ASSERT_TRUE(camera.has_value()) << camera.error().message();
    EXPECT_EQ(fake.device("/dev/video0").width, 64U); // one 2w x h image

    CameraFrame f;
    ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);
    EXPECT_EQ(f.images.left.at(31, 0), 40);
    EXPECT_EQ(f.images.right.at(0, 0), 140);
    EXPECT_EQ(f.sequence, 7U);
    EXPECT_EQ(f.leftStampNs, f.rightStampNs);
}

TEST(V4l2Camera, FramesTooFarApartAreNotPairedAndTheOlderIsDropped)
{
    FakeV4l2 fake;
    fake.add("/dev/video0").pending = {{1, 0, 1'000'000}, {2, 1, 1'033'000}};
    fake.add("/dev/video1").pending = {{3, 0, 1'033'500}};
    auto camera = V4l2StereoCamera::open(stereo(), fake.ops());
    ASSERT_TRUE(camera.has_value());
    CameraFrame f;
    ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);
    EXPECT_EQ(f.images.left.at(0, 0), 2); // left frame 0 (33 ms before the right one) was dropped
    EXPECT_EQ(f.images.right.at(0, 0), 3);
    EXPECT_EQ((*camera)->unpaired(), 1U);
}

TEST(V4l2Camera, SequenceGapsAreCountedAndEagainIsATimeout)
{
    FakeV4l2 fake;
    FakeDevice& left = fake.add("/dev/video0");
    left.pending = {{1, 0, 0}, {1, 1, 33'000}, {1, 4, 133'000}};
    left.eagain = 1;
    fake.add("/dev/video1").pending = {{1, 0, 0}, {1, 1, 33'000}, {1, 4, 133'000}};
    auto camera = V4l2StereoCamera::open(stereo(), fake.ops());
    ASSERT_TRUE(camera.has_value());
    CameraFrame f;
    EXPECT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Timeout); // EAGAIN
    for (int k = 0; k < 3; ++k) {
        ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);
    }
    EXPECT_EQ(f.sequence, 4U);
    EXPECT_EQ((*camera)->stats().sequenceGaps, 4U); // 2 per device
}

TEST(V4l2Camera, LeftUnplugIsDisconnectedAndReconnectWorksOnceTheCameraIsBack)
{
    FakeV4l2 fake;
    const auto camera = streamingPair(fake);
    ASSERT_TRUE(camera.has_value()) << camera.error().message();
    CameraFrame f;

    fake.device("/dev/video1").pending = {{2, 1, 33'000}}; // the right camera still streams
    fake.device("/dev/video0").unplugged = true;
    EXPECT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Disconnected);
    EXPECT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Disconnected);
    EXPECT_EQ((*camera)->stats().disconnects, 1U);
    EXPECT_FALSE((*camera)->reconnect()); // still gone: ENODEV at open

    fake.device("/dev/video0").unplugged = false;
    ASSERT_TRUE((*camera)->reconnect());
    expectAPairAgain(fake, **camera);
}

TEST(V4l2Camera, ARightCameraThatVanishesLeavesLeftOnlyFramesUntilReconnectBringsItBack)
{
    FakeV4l2 fake;
    const auto camera = streamingPair(fake);
    ASSERT_TRUE(camera.has_value()) << camera.error().message();
    CameraFrame f;
    EXPECT_FALSE((*camera)->rightLost());

    fake.device("/dev/video0").pending = {{2, 1, 33'000}, {3, 2, 66'000}};
    fake.device("/dev/video1").unplugged = true;
    ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);
    EXPECT_EQ(f.images.left.at(0, 0), 2);
    EXPECT_TRUE(f.images.right.empty());
    EXPECT_EQ(f.sequence, 1U);
    EXPECT_TRUE((*camera)->rightLost());
    EXPECT_FALSE((*camera)->reconnect());                               // still gone
    ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame); // the left camera streams on
    EXPECT_EQ(f.images.left.at(0, 0), 3);
    EXPECT_TRUE(f.images.right.empty());
    EXPECT_EQ((*camera)->stats().leftOnlyFrames, 2U);
    EXPECT_EQ((*camera)->stats().disconnects, 0U); // the camera as a whole never went away

    fake.device("/dev/video1").unplugged = false;
    ASSERT_TRUE((*camera)->reconnect());
    EXPECT_FALSE((*camera)->rightLost());
    expectAPairAgain(fake, **camera);
}

TEST(V4l2Camera, ARightCameraThatStallsIsLostAfterThreeMissedFramesAndEveryLeftFrameGoesOut)
{
    FakeV4l2 fake;
    FakeDevice& left = fake.add("/dev/video0");
    fake.add("/dev/video1");
    for (std::uint32_t k = 0; k < 5; ++k) {
        left.pending.push_back({static_cast<std::uint8_t>(k), k, 33'333 * static_cast<std::int64_t>(k)});
    }
    auto camera = V4l2StereoCamera::open(stereo(), fake.ops());
    ASSERT_TRUE(camera.has_value());
    CameraFrame f;
    const ugv::test::ThreadAllocationScope scope;
    for (int k = 0; k < 5; ++k) {
        ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame) << k;
        EXPECT_EQ(f.images.left.at(0, 0), k);
        EXPECT_TRUE(f.images.right.empty());
        EXPECT_EQ((*camera)->rightLost(), k >= V4l2StereoCamera::kRightMissesToLose - 1) << k;
    }
    EXPECT_EQ(scope.count(), 0U);        // the fallback allocates nothing either
    ASSERT_TRUE((*camera)->reconnect()); // restarts the right stream
    expectAPairAgain(fake, **camera);
}

TEST(V4l2Camera, OneCameraDeliversLeftOnlyFramesAndNeverOpensASecondDevice)
{
    FakeV4l2 fake;
    fake.add("/dev/video0").pending = {{9, 4, 1'000}};
    V4l2Options o = stereo(V4l2Format::Grey);
    o.oneCamera = true;
    auto camera = V4l2StereoCamera::open(o, fake.ops()); // no /dev/video1 exists
    ASSERT_TRUE(camera.has_value()) << camera.error().message();
    EXPECT_STREQ((*camera)->description(), "v4l2 /dev/video0 (one camera)");
    CameraFrame f;
    ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);
    EXPECT_EQ(f.images.left.at(3, 3), 9);
    EXPECT_TRUE(f.images.right.empty());
    EXPECT_FALSE((*camera)->rightLost()); // one camera is what the rig is, not a loss
    EXPECT_EQ(fake.device("/dev/video0").width, 32U);
}

TEST(V4l2Camera, OpenErrorsNameTheDeviceWhatAndTheFix)
{
    FakeV4l2 fake;
    fake.add("/dev/video0");
    auto missing = V4l2StereoCamera::open(stereo(), fake.ops()); // no /dev/video1
    ASSERT_FALSE(missing.has_value());
    EXPECT_NE(missing.error().message().find("/dev/video1: cannot open the camera"), std::string::npos)
        << missing.error().message();
    EXPECT_NE(missing.error().message().find("ENOENT"), std::string::npos);

    fake.add("/dev/video1").shrinkWidth = 16;
    auto wrongSize = V4l2StereoCamera::open(stereo(V4l2Format::Grey), fake.ops());
    ASSERT_FALSE(wrongSize.has_value());
    EXPECT_NE(wrongSize.error().message().find("offers 16x8 GREY instead of 32x8 GREY"), std::string::npos)
        << wrongSize.error().message();

    fake.device("/dev/video1").shrinkWidth = 0;
    fake.device("/dev/video1").captureCapable = false;
    auto notCapture = V4l2StereoCamera::open(stereo(), fake.ops());
    ASSERT_FALSE(notCapture.has_value());
    EXPECT_NE(notCapture.error().message().find("not a streaming video capture device"), std::string::npos);

    V4l2Options bad = stereo();
    bad.buffers = 1;
    EXPECT_FALSE(V4l2StereoCamera::open(bad, fake.ops()).has_value());
}

/// The BGR pixel OpenCV makes of a YUYV pair with luma y (both pixels) and chroma u, v.
cv::Vec3b bgrOf(std::uint8_t y, std::uint8_t u, std::uint8_t v)
{
    cv::Mat yuyv(1, 2, CV_8UC2, cv::Scalar(0));
    yuyv.at<cv::Vec2b>(0, 0) = cv::Vec2b(y, u);
    yuyv.at<cv::Vec2b>(0, 1) = cv::Vec2b(y, v);
    cv::Mat bgr;
    cv::cvtColor(yuyv, bgr, cv::COLOR_YUV2BGR_YUYV);
    return bgr.at<cv::Vec3b>(0, 0);
}

TEST(V4l2Camera, AColourCameraDeliversBgrPairsConvertedFromYuyvWithoutAllocating)
{
    FakeV4l2 fake;
    FakeDevice& l = fake.add("/dev/video0");
    FakeDevice& r = fake.add("/dev/video1");
    for (std::uint32_t k = 0; k < 110; ++k) {
        // Left reddish (V high, U low), right bluish: the channels must not come out swapped.
        l.pending.push_back({100, k, 33'333 * static_cast<std::int64_t>(k), true, 100, 200});
        r.pending.push_back({120, k, 33'333 * static_cast<std::int64_t>(k) + 100, true, 200, 100});
    }
    V4l2Options o = stereo();
    o.colour = true;
    auto camera = V4l2StereoCamera::open(o, fake.ops());
    ASSERT_TRUE(camera.has_value()) << camera.error().message();
    EXPECT_EQ((*camera)->format(), PixelFormat::Bgr8);
    CameraFrame f;
    ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);

    ASSERT_EQ(f.images.format, PixelFormat::Bgr8);
    EXPECT_TRUE(f.images.left.empty());
    ASSERT_EQ(f.images.width(), 32);
    const cv::Vec3b red = bgrOf(100, 100, 200);
    const cv::Vec3b blue = bgrOf(120, 200, 100);
    EXPECT_GT(red[2], red[1]);
    EXPECT_GT(red[1], red[0]);
    EXPECT_GT(blue[0], blue[2]);
    for (const auto& [x, y] : {std::pair{0, 0}, std::pair{31, 7}, std::pair{5, 3}}) {
        const BgrPixel left = f.images.leftBgr.at(x, y);
        const BgrPixel right = f.images.rightBgr.at(x, y);
        EXPECT_EQ(cv::Vec3b(left.b, left.g, left.r), red) << x << "," << y;
        EXPECT_EQ(cv::Vec3b(right.b, right.g, right.r), blue) << x << "," << y;
    }

    const ugv::test::ThreadAllocationScope scope;
    for (int k = 0; k < 100; ++k) {
        ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);
    }
    EXPECT_EQ(scope.count(), 0U);
}

TEST(V4l2Camera, ASideBySideColourCameraIsSplitOnAWholePixelPair)
{
    FakeV4l2 fake;
    FakeDevice& d = fake.add("/dev/video0");
    d.split = 32; // the right half is 100 grey levels brighter
    d.pending = {{40, 7, 5'000'000, true, 90, 170}};
    V4l2Options o = stereo();
    o.rightDevice.clear();
    o.colour = true;
    auto camera = V4l2StereoCamera::open(o, fake.ops());
    ASSERT_TRUE(camera.has_value()) << camera.error().message();
    CameraFrame f;
    ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);

    const BgrPixel left = f.images.leftBgr.at(31, 0);
    const BgrPixel right = f.images.rightBgr.at(0, 0);
    EXPECT_EQ(cv::Vec3b(left.b, left.g, left.r), bgrOf(40, 90, 170));
    EXPECT_EQ(cv::Vec3b(right.b, right.g, right.r), bgrOf(140, 90, 170));
}

TEST(V4l2Camera, ColourNeedsTheYuyvFormat)
{
    FakeV4l2 fake;
    fake.add("/dev/video0");
    fake.add("/dev/video1");
    V4l2Options o = stereo(V4l2Format::Grey);
    o.colour = true;

    const auto sut = V4l2StereoCamera::open(o, fake.ops());

    ASSERT_FALSE(sut.has_value());
    EXPECT_NE(sut.error().message().find("colour frames need the YUYV format"), std::string::npos);
    EXPECT_NE(sut.error().message().find("set camera.format: yuyv"), std::string::npos);
}

TEST(V4l2Camera, GrabAllocatesNothingOverHundredsOfFrames)
{
    FakeV4l2 fake;
    FakeDevice& l = fake.add("/dev/video0");
    FakeDevice& r = fake.add("/dev/video1");
    for (std::uint32_t k = 0; k < 310; ++k) {
        l.pending.push_back({static_cast<std::uint8_t>(k), k, 33'333 * static_cast<std::int64_t>(k)});
        r.pending.push_back({static_cast<std::uint8_t>(k), k, 33'333 * static_cast<std::int64_t>(k) + 100});
    }
    auto camera = V4l2StereoCamera::open(stereo(), fake.ops());
    ASSERT_TRUE(camera.has_value());
    CameraFrame f;
    ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);

    const ugv::test::ThreadAllocationScope scope;
    for (int k = 0; k < 300; ++k) {
        ASSERT_EQ((*camera)->grab(f, milliseconds(50)), GrabStatus::Frame);
    }
    EXPECT_EQ(scope.count(), 0U);
    EXPECT_EQ((*camera)->stats().frames, 301U);
}

} // namespace
} // namespace ugv::hal
