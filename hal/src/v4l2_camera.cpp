#include "ugv/hal/v4l2_camera.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <utility>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "ugv/hal/sys_call.hpp"

namespace ugv::hal {

namespace {

int realOpen(void* /*context*/, const char* path, int flags)
{
    return ::open(path, flags);
}
int realClose(void* /*context*/, int fd)
{
    return ::close(fd);
}
// ioctl(2)'s request type is unsigned long
int realIoctl(void* /*context*/, int fd, unsigned long request, void* arg)
{
    return ::ioctl(fd, request, arg);
}
void* realMmap(void* /*context*/, std::size_t length, int fd, std::int64_t offset)
{
    return ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, static_cast<off_t>(offset));
}
int realMunmap(void* /*context*/, void* address, std::size_t length)
{
    return ::munmap(address, length);
}
int realPoll(void* /*context*/, pollfd* fds, unsigned count, int timeoutMs)
{
    return ::poll(fds, count, timeoutMs);
}

std::uint32_t fourcc(V4l2Format format)
{
    return format == V4l2Format::Grey ? V4L2_PIX_FMT_GREY : V4L2_PIX_FMT_YUYV;
}

std::string fourccText(std::uint32_t f)
{
    std::string s(4, ' ');
    for (int i = 0; i < 4; ++i) {
        s[static_cast<std::size_t>(i)] = static_cast<char>((f >> (8 * i)) & 0xFF);
    }
    return s;
}

std::int64_t stampNs(const v4l2_buffer& b)
{
    return static_cast<std::int64_t>(b.timestamp.tv_sec) * 1'000'000'000 +
           static_cast<std::int64_t>(b.timestamp.tv_usec) * 1000;
}

bool disconnectError(int code)
{
    return code == ENODEV || code == EIO || code == ENXIO || code == EBADF;
}

std::string describe(const V4l2Options& options)
{
    const bool sideBySide = !options.oneCamera && options.rightDevice.empty();
    return options.oneCamera ? "v4l2 " + options.leftDevice + " (one camera)"
           : sideBySide      ? "v4l2 " + options.leftDevice + " (side by side)"
                             : "v4l2 " + options.leftDevice + " + " + options.rightDevice;
}

} // namespace

V4l2Ops realV4l2Ops() noexcept
{
    return V4l2Ops{realOpen, realClose, realIoctl, realMmap, realMunmap, realPoll, nullptr};
}

V4l2StereoCamera::V4l2StereoCamera(const V4l2Options& options, V4l2Ops ops)
    : DeviceStereoCamera(options.colour, options.width, options.height, options.fps, describe(options)),
      options_(options), ops_(ops)
{
    if (options.colour) {
        leftBgr_ = Image<BgrPixel>(options.width, options.height);
        rightBgr_ = Image<BgrPixel>(options.width, options.height);
    } else {
        leftGrey_ = Image<std::uint8_t>(options.width, options.height);
        rightGrey_ = Image<std::uint8_t>(options.width, options.height);
    }
    sideBySide_ = !options.oneCamera && options.rightDevice.empty();
}

V4l2StereoCamera::~V4l2StereoCamera()
{
    stop(left_);
    stop(right_);
}

Result<std::unique_ptr<V4l2StereoCamera>, Error> V4l2StereoCamera::open(const V4l2Options& options, V4l2Ops ops)
{
    if (ops.open == nullptr || ops.close == nullptr || ops.ioctl == nullptr || ops.mmap == nullptr ||
        ops.munmap == nullptr || ops.poll == nullptr) {
        return Unexpected(Error{"v4l2", "incomplete V4l2Ops", "a bug: give every call"});
    }
    if (options.width <= 0 || options.height <= 0 || options.width > 8192 || options.height > 8192 ||
        !(options.fps > 0.0) || options.buffers < 2 || options.buffers > kMaxBuffers ||
        !(options.maxPairSkewMs > 0.0)) {
        return Unexpected(Error{"v4l2 " + options.leftDevice, "size, rate, buffer count or skew out of range",
                                "camera.width/height in 1..8192, fps > 0, 2..8 buffers, max_pair_skew_ms > 0"});
    }
    if (options.colour && (options.format != V4l2Format::Yuyv || options.width % 2 != 0)) {
        return Unexpected(Error{"v4l2 " + options.leftDevice, "colour frames need the YUYV format and an even width",
                                "set camera.format: yuyv (a grey camera has no colour), or camera.colour: false"});
    }
    std::unique_ptr<V4l2StereoCamera> camera(new V4l2StereoCamera(options, ops));
    camera->left_.path = options.leftDevice;
    camera->right_.path = options.rightDevice;
    if (auto started = camera->start(camera->left_, camera->sideBySide_ ? 2 * options.width : options.width);
        !started) {
        return Unexpected(started.error());
    }
    if (camera->hasRightDevice()) {
        if (auto started = camera->start(camera->right_, options.width); !started) {
            camera->stop(camera->left_);
            return Unexpected(started.error());
        }
    }
    camera->connected_ = true;
    return camera;
}

namespace {

/// An error of one camera device: what failed, with errno's text when `code` is not 0.
Error deviceError(const V4l2StereoCamera::Device& device, const std::string& what, int code, const std::string& fix)
{
    const SysError e{code};
    return Error{device.path, what + (code != 0 ? std::string(": ") + e.text() + " (" + e.name() + ")" : ""), fix};
}

} // namespace

Result<void, Error> V4l2StereoCamera::openDevice(Device& device)
{
    device.fd = ops_.open(ops_.context, device.path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (device.fd < 0) {
        return Unexpected(deviceError(device, "cannot open the camera", errno,
                                      errno == EACCES
                                          ? "add the service user to group video"
                                          : "check camera.left_device/right_device and that the camera is plugged in"));
    }
    v4l2_capability cap{};
    if (ops_.ioctl(ops_.context, device.fd, VIDIOC_QUERYCAP, &cap) != 0) {
        return Unexpected(deviceError(device, "VIDIOC_QUERYCAP failed: not a V4L2 device?", errno,
                                      "give a /dev/videoN capture node"));
    }
    const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
    if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0 || (caps & V4L2_CAP_STREAMING) == 0) {
        return Unexpected(deviceError(device, "is not a streaming video capture device", 0,
                                      "give the capture node of the camera (v4l2-ctl --list-devices)"));
    }
    return {};
}

Result<void, Error> V4l2StereoCamera::setFormat(Device& device, int frameWidth)
{
    v4l2_format fmt{};
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    fmt.fmt.pix.width = static_cast<std::uint32_t>(frameWidth);
    fmt.fmt.pix.height = static_cast<std::uint32_t>(options_.height);
    fmt.fmt.pix.pixelformat = fourcc(options_.format);
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
    if (ops_.ioctl(ops_.context, device.fd, VIDIOC_S_FMT, &fmt) != 0) {
        return Unexpected(deviceError(device, "VIDIOC_S_FMT failed", errno,
                                      "check camera.width/height against v4l2-ctl --list-formats-ext"));
    }
    if (fmt.fmt.pix.width != static_cast<std::uint32_t>(frameWidth) ||
        fmt.fmt.pix.height != static_cast<std::uint32_t>(options_.height) ||
        fmt.fmt.pix.pixelformat != fourcc(options_.format)) {
        return Unexpected(
            deviceError(device,
                        "offers " + std::to_string(fmt.fmt.pix.width) + "x" + std::to_string(fmt.fmt.pix.height) + " " +
                            fourccText(fmt.fmt.pix.pixelformat) + " instead of " + std::to_string(frameWidth) + "x" +
                            std::to_string(options_.height) + " " + fourccText(fourcc(options_.format)),
                        0, "set camera.width/height/format to a mode the camera has (v4l2-ctl --list-formats-ext)"));
    }
    const std::uint32_t bytesPerPixel = options_.format == V4l2Format::Yuyv ? 2 : 1;
    if (fmt.fmt.pix.bytesperline < static_cast<std::uint32_t>(frameWidth) * bytesPerPixel) {
        return Unexpected(
            deviceError(device, "reports a line shorter than its width", 0, "a driver bug: try another format"));
    }
    device.stride = fmt.fmt.pix.bytesperline;
    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    parm.parm.capture.timeperframe.numerator = 1000;
    parm.parm.capture.timeperframe.denominator = static_cast<std::uint32_t>(std::lround(options_.fps * 1000.0));
    (void)ops_.ioctl(ops_.context, device.fd, VIDIOC_S_PARM, &parm); // a fixed-rate camera may refuse: fine
    return {};
}

Result<void, Error> V4l2StereoCamera::mapBuffers(Device& device)
{
    v4l2_requestbuffers req{};
    req.count = static_cast<std::uint32_t>(options_.buffers);
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (ops_.ioctl(ops_.context, device.fd, VIDIOC_REQBUFS, &req) != 0 || req.count < 2) {
        return Unexpected(
            deviceError(device, "VIDIOC_REQBUFS (MMAP) failed", errno, "the driver must support MMAP streaming"));
    }
    device.buffers = static_cast<int>(std::min<std::uint32_t>(req.count, kMaxBuffers));
    for (int i = 0; i < device.buffers; ++i) {
        v4l2_buffer buf{};
        buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        buf.memory = V4L2_MEMORY_MMAP;
        buf.index = static_cast<std::uint32_t>(i);
        if (ops_.ioctl(ops_.context, device.fd, VIDIOC_QUERYBUF, &buf) != 0) {
            return Unexpected(deviceError(device, "VIDIOC_QUERYBUF failed", errno, "check the driver"));
        }
        void* map = ops_.mmap(ops_.context, buf.length, device.fd, buf.m.offset);
        if (map == MAP_FAILED) {
            return Unexpected(deviceError(device, "mmap of a capture buffer failed", errno,
                                          "check the driver and the memory limits"));
        }
        device.maps[static_cast<std::size_t>(i)] = map;
        device.lengths[static_cast<std::size_t>(i)] = buf.length;
        if (ops_.ioctl(ops_.context, device.fd, VIDIOC_QBUF, &buf) != 0) {
            return Unexpected(deviceError(device, "VIDIOC_QBUF failed", errno, "check the driver"));
        }
    }
    return {};
}

Result<void, Error> V4l2StereoCamera::start(Device& device, int frameWidth)
{
    device.frameWidth = frameWidth;
    if (auto opened = openDevice(device); !opened) {
        stop(device);
        return opened;
    }
    if (auto formatted = setFormat(device, frameWidth); !formatted) {
        stop(device);
        return formatted;
    }
    if (auto mapped = mapBuffers(device); !mapped) {
        stop(device);
        return mapped;
    }
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (ops_.ioctl(ops_.context, device.fd, VIDIOC_STREAMON, &type) != 0) {
        Error e = deviceError(device, "VIDIOC_STREAMON failed", errno, "another process may hold the camera");
        stop(device);
        return Unexpected(std::move(e));
    }
    device.haveSequence = false;
    device.held = -1;
    return {};
}

void V4l2StereoCamera::stop(Device& device) noexcept
{
    if (device.fd < 0) {
        return;
    }
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    (void)ops_.ioctl(ops_.context, device.fd, VIDIOC_STREAMOFF, &type);
    for (int i = 0; i < device.buffers; ++i) {
        if (device.maps[static_cast<std::size_t>(i)] != nullptr) {
            (void)ops_.munmap(ops_.context, device.maps[static_cast<std::size_t>(i)],
                              device.lengths[static_cast<std::size_t>(i)]);
            device.maps[static_cast<std::size_t>(i)] = nullptr;
        }
    }
    (void)ops_.close(ops_.context, device.fd);
    device.fd = -1;
    device.buffers = 0;
    device.held = -1;
}

GrabStatus V4l2StereoCamera::dequeue(Device& device, int timeoutMs) noexcept
{
    pollfd p{device.fd, POLLIN, 0};
    const int ready = ops_.poll(ops_.context, &p, 1, timeoutMs);
    if (ready == 0 || (ready < 0 && errno == EINTR)) {
        return GrabStatus::Timeout;
    }
    if (ready < 0 || (p.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) {
        return GrabStatus::Disconnected;
    }
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    if (ops_.ioctl(ops_.context, device.fd, VIDIOC_DQBUF, &buf) != 0) {
        if (errno == EAGAIN || errno == EINTR) {
            return GrabStatus::Timeout;
        }
        return disconnectError(errno) ? GrabStatus::Disconnected : GrabStatus::BadFrame;
    }
    if (buf.index >= static_cast<std::uint32_t>(device.buffers)) {
        return GrabStatus::BadFrame; // a driver bug: nothing to give back
    }
    if ((buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) != V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
        // A driver without monotonic stamps (or with unknown ones): the dequeue time is the best we have, on the
        // clock the rest of the service uses.
        timespec now{};
        ::clock_gettime(CLOCK_MONOTONIC, &now);
        buf.timestamp.tv_sec = now.tv_sec;
        buf.timestamp.tv_usec = now.tv_nsec / 1000;
    }
    device.held = static_cast<int>(buf.index);
    if (device.haveSequence && buf.sequence > device.lastSequence + 1) {
        counters().sequenceGaps += buf.sequence - device.lastSequence - 1;
    }
    device.haveSequence = true;
    device.lastSequence = buf.sequence;
    device.last = buf;
    const std::size_t needed = static_cast<std::size_t>(device.stride) * static_cast<std::size_t>(options_.height);
    if ((buf.flags & V4L2_BUF_FLAG_ERROR) != 0 || buf.bytesused < needed) {
        requeue(device);
        ++counters().badFrames;
        return GrabStatus::BadFrame;
    }
    return GrabStatus::Frame;
}

void V4l2StereoCamera::requeue(Device& device) noexcept
{
    if (device.held < 0 || device.fd < 0) {
        return;
    }
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = static_cast<std::uint32_t>(device.held);
    (void)ops_.ioctl(ops_.context, device.fd, VIDIOC_QBUF, &buf);
    device.held = -1;
}

bool V4l2StereoCamera::copyImage(const Device& device, int x0, bool right) noexcept
{
    if (device.held < 0) {
        return false;
    }
    const auto* base = static_cast<const std::uint8_t*>(device.maps[static_cast<std::size_t>(device.held)]);
    if (options_.colour) {
        // YUYV 4:2:2 to BGR, OpenCV's BT.601 conversion; x0 is even (a whole Y0 U Y1 V pair). The sizes were fixed at
        // open(), so cvtColor writes into the BGR image without allocating.
        const BgrView out = right ? rightBgr_.view() : leftBgr_.view();
        // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): cv::Mat takes no const data; yuyv is only read
        const cv::Mat yuyv(out.height(), out.width(), CV_8UC2, const_cast<std::uint8_t*>(base) + 2 * x0, device.stride);
        cv::Mat bgr(out.height(), out.width(), CV_8UC3, out.data(), static_cast<std::size_t>(out.strideBytes()));
        cv::cvtColor(yuyv, bgr, cv::COLOR_YUV2BGR_YUYV);
        return true;
    }
    const ImageViewU8 out = right ? rightGrey_.view() : leftGrey_.view();
    for (int y = 0; y < out.height(); ++y) {
        const std::uint8_t* row = base + static_cast<std::size_t>(y) * device.stride;
        std::uint8_t* dst = out.row(y);
        if (options_.format == V4l2Format::Grey) {
            std::memcpy(dst, row + x0, static_cast<std::size_t>(out.width()));
        } else {
            for (int x = 0; x < out.width(); ++x) {
                dst[x] = row[2 * static_cast<std::ptrdiff_t>(x0 + x)]; // YUYV: Y0 U Y1 V
            }
        }
    }
    return true;
}

StereoViews V4l2StereoCamera::images(bool leftOnly) const noexcept
{
    if (options_.colour) {
        return bgrViews(leftBgr_.view(), leftOnly ? ConstBgrView() : rightBgr_.view());
    }
    return greyViews(leftGrey_.view(), leftOnly ? ConstImageViewU8() : rightGrey_.view());
}

GrabStatus V4l2StereoCamera::grab(CameraFrame& out, std::chrono::nanoseconds timeout) noexcept
{
    if (!connected_) {
        return GrabStatus::Disconnected;
    }
    requeue(left_);
    requeue(right_);
    const int timeoutMs = static_cast<int>(std::max<std::int64_t>(1, timeout.count() / 1'000'000));
    // The left camera is the one the one-camera mode runs on: without it there is no frame at all.
    if (const GrabStatus s = dequeue(left_, timeoutMs); s != GrabStatus::Frame) {
        if (s == GrabStatus::Disconnected) {
            connected_ = false;
            ++counters().disconnects;
        }
        return s;
    }
    bool leftOnly = options_.oneCamera || rightLost_;
    if (sideBySide_) {
        copyImage(left_, options_.width, true);
        out.rightStampNs = stampNs(left_.last);
    } else if (!leftOnly) {
        // The right frame is due within a period (and the skew) of the left one.
        const auto periodMs = static_cast<int>(period().count() / 1'000'000);
        const int pairWaitMs = std::min(timeoutMs, periodMs + static_cast<int>(std::ceil(options_.maxPairSkewMs)));
        const GrabStatus s = pairRight(pairWaitMs);
        if (s == GrabStatus::BadFrame || left_.held < 0) {
            requeue(left_);
            requeue(right_);
            return s == GrabStatus::Frame ? GrabStatus::BadFrame : s; // left lost while pairing: as above
        }
        leftOnly = s != GrabStatus::Frame && rightMissing(s);
        if (!leftOnly) {
            rightMisses_ = 0;
            copyImage(right_, 0, true);
            out.rightStampNs = stampNs(right_.last);
        }
    }
    copyImage(left_, 0, false);
    out.sequence = left_.last.sequence;
    out.leftStampNs = stampNs(left_.last);
    out.images = images(leftOnly);
    if (leftOnly) {
        out.rightStampNs = 0;
        ++counters().leftOnlyFrames;
    }
    ++counters().frames;
    return GrabStatus::Frame;
}

GrabStatus V4l2StereoCamera::pairRight(int timeoutMs) noexcept
{
    GrabStatus s = dequeue(right_, timeoutMs);
    if (s != GrabStatus::Frame) {
        return s;
    }
    // Pair by timestamp: drop the older frame and take that camera's next one, a few times at most.
    const auto skewNs = static_cast<std::int64_t>(options_.maxPairSkewMs * 1e6);
    for (int attempt = 0; attempt < 4; ++attempt) {
        const std::int64_t dt = stampNs(left_.last) - stampNs(right_.last);
        if (std::llabs(dt) <= skewNs) {
            return GrabStatus::Frame;
        }
        Device& older = dt < 0 ? left_ : right_;
        requeue(older);
        ++unpaired_;
        s = dequeue(older, timeoutMs);
        if (s != GrabStatus::Frame) {
            if (&older == &left_) {
                requeue(right_);
                if (s == GrabStatus::Disconnected) {
                    connected_ = false;
                    ++counters().disconnects;
                }
            }
            return s; // the left camera's failure leaves left_.held < 0
        }
    }
    if (std::llabs(stampNs(left_.last) - stampNs(right_.last)) > skewNs) {
        ++counters().badFrames;
        return GrabStatus::BadFrame;
    }
    return GrabStatus::Frame;
}

bool V4l2StereoCamera::rightMissing(GrabStatus s) noexcept
{
    if (s == GrabStatus::Disconnected) {
        stop(right_);
        rightLost_ = true;
    } else if (s == GrabStatus::Timeout && ++rightMisses_ >= kRightMissesToLose) {
        rightLost_ = true; // stalled: stop waiting for it; reconnect() restarts its stream
    }
    return s == GrabStatus::Disconnected || s == GrabStatus::Timeout;
}

bool V4l2StereoCamera::reconnect() noexcept
{
    if (connected_ && rightLost_) {
        // The left camera streams on: bring back only the right one.
        stop(right_);
        if (!start(right_, options_.width)) {
            return false;
        }
        rightLost_ = false;
        rightMisses_ = 0;
        return true;
    }
    stop(left_);
    stop(right_);
    if (!start(left_, sideBySide_ ? 2 * options_.width : options_.width)) {
        return false;
    }
    if (hasRightDevice() && !start(right_, options_.width)) {
        stop(left_);
        return false;
    }
    rightLost_ = false;
    rightMisses_ = 0;
    connected_ = true;
    return true;
}

} // namespace ugv::hal
