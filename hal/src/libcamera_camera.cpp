#include "ugv/hal/libcamera_camera.hpp"

#include <semaphore.h>
#include <sys/mman.h>

#include <libcamera/libcamera.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>
#include <optional>
#include <vector>

#include "ugv/hal/sys_call.hpp"
#include "ugv/hal/yuv420.hpp"
#include "ugv/platform/clock.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/spsc_ring.hpp"

namespace ugv::hal {

namespace {

constexpr unsigned kBuffers = 4;
constexpr std::size_t kPlanes = 3; // YUV420: Y, U, V

} // namespace

/// One camera of the pair.
struct Side {
    std::shared_ptr<libcamera::Camera> camera;
    std::unique_ptr<libcamera::CameraConfiguration> config;
    libcamera::Stream* stream = nullptr;
    std::unique_ptr<libcamera::FrameBufferAllocator> allocator;
    std::vector<std::unique_ptr<libcamera::Request>> requests;
    /// A buffer's planes mapped (the Y plane only for grey frames): each from the start of its dmabuf.
    struct Mapping {
        std::array<void*, kPlanes> address{};
        std::array<std::size_t, kPlanes> length{};
        std::array<const std::uint8_t*, kPlanes> plane{}; ///< address + the plane's offset
    };
    std::map<const libcamera::FrameBuffer*, Mapping> maps;
    SpscRing<libcamera::Request*, 16> completed; ///< libcamera's thread -> capture thread
    libcamera::Request* pending = nullptr;       ///< popped, not yet delivered
    libcamera::Request* delivered = nullptr;     ///< its buffer backs the last frame's copy: requeued next grab
    unsigned stride = 0;                         ///< of the Y plane; U and V rows are half as long (libcamera's YUV420)
    bool acquired = false;
    bool started = false;
    std::atomic<bool> failed{false};
    bool haveSequence = false;
    unsigned lastSequence = 0;
};

struct LibcameraStereoCamera::Impl {
    std::unique_ptr<libcamera::CameraManager> manager;
    Side left;
    Side right;
    sem_t ready{};
    bool semaphore = false;
    Image<std::uint8_t> leftGrey;
    Image<std::uint8_t> rightGrey;
    Image<BgrPixel> leftBgr; ///< colour: the frames (empty otherwise)
    Image<BgrPixel> rightBgr;
    std::optional<Yuv420ToBgr> toBgr;

    Impl(int width, int height, bool colour)
        : leftGrey(width, height), rightGrey(width, height), leftBgr(colour ? width : 0, colour ? height : 0),
          rightBgr(colour ? width : 0, colour ? height : 0)
    {
        if (colour) {
            toBgr.emplace(width, height);
        }
        semaphore = ::sem_init(&ready, 0, 0) == 0;
    }
    ~Impl()
    {
        if (semaphore) {
            ::sem_destroy(&ready);
        }
    }
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;
    Impl(Impl&&) = delete;
    Impl& operator=(Impl&&) = delete;

    void complete(Side& side, libcamera::Request* request)
    {
        if (request->status() == libcamera::Request::RequestCancelled) {
            return; // stopping
        }
        if (request->status() != libcamera::Request::RequestComplete || !side.completed.tryPush(request)) {
            side.failed.store(true);
        }
        ::sem_post(&ready);
    }
    void onLeft(libcamera::Request* request) { complete(left, request); }
    void onRight(libcamera::Request* request) { complete(right, request); }
    /// The side's request, columns [x0, x0 + width), into the left or right image: grey (the Y plane) or BGR.
    void copy(const Side& side, const libcamera::Request* request, int x0, bool intoRight) noexcept;
    [[nodiscard]] StereoViews images(bool leftOnly) const noexcept;
};

namespace {

/// Acquires `cam` and configures its stream: frameWidth x height YUV420 (the Y plane is used), kBuffers buffers.
Result<void, Error> configureSide(Side& side, const std::shared_ptr<libcamera::Camera>& cam, const std::string& name,
                                  int frameWidth, int height)
{
    side.camera = cam;
    if (cam->acquire() != 0) {
        return Unexpected(Error{name, "the camera is in use by another process", "stop the other user"});
    }
    side.acquired = true;
    side.config = cam->generateConfiguration({libcamera::StreamRole::Viewfinder});
    if (!side.config || side.config->empty()) {
        return Unexpected(Error{name, "cannot generate a stream configuration", "check the camera"});
    }
    libcamera::StreamConfiguration& stream = side.config->at(0);
    stream.pixelFormat = libcamera::formats::YUV420;
    stream.size = libcamera::Size(static_cast<unsigned>(frameWidth), static_cast<unsigned>(height));
    stream.bufferCount = kBuffers;
    if (side.config->validate() == libcamera::CameraConfiguration::Invalid ||
        stream.size.width != static_cast<unsigned>(frameWidth) || stream.size.height != static_cast<unsigned>(height) ||
        stream.pixelFormat != libcamera::formats::YUV420) {
        return Unexpected(Error{name,
                                "cannot deliver " + std::to_string(frameWidth) + "x" + std::to_string(height) +
                                    " YUV420 (it offers " + stream.toString() + ")",
                                "set camera.width/height to a mode the camera has"});
    }
    if (cam->configure(side.config.get()) != 0) {
        return Unexpected(Error{name, "configure failed", "check the camera"});
    }
    side.stream = stream.stream();
    side.stride = stream.stride;
    return {};
}

/// Maps the first `planes` planes of `buffer`, each from the start of its dmabuf (a plane's offset need not be
/// page-aligned); what was mapped stays in `mapping` for stop() to unmap, also on failure.
bool mapPlanes(const libcamera::FrameBuffer& buffer, std::size_t planes, Side::Mapping& mapping)
{
    if (buffer.planes().size() < planes) {
        return false;
    }
    for (std::size_t i = 0; i < planes; ++i) {
        const libcamera::FrameBuffer::Plane& plane = buffer.planes()[i];
        const std::size_t length = plane.offset + plane.length;
        void* address = ::mmap(nullptr, length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
        if (address == MAP_FAILED) {
            return false;
        }
        mapping.address[i] = address;
        mapping.length[i] = length;
        mapping.plane[i] = static_cast<const std::uint8_t*>(address) + plane.offset;
    }
    return true;
}

/// Allocates the side's frame buffers, maps their Y planes (all three for colour) and makes one capture request per
/// buffer.
Result<void, Error> mapBuffers(Side& side, const std::string& name, bool colour)
{
    side.allocator = std::make_unique<libcamera::FrameBufferAllocator>(side.camera);
    if (side.allocator->allocate(side.stream) < 0) {
        return Unexpected(Error{name, "cannot allocate frame buffers", "check the memory limits"});
    }
    for (const std::unique_ptr<libcamera::FrameBuffer>& buffer : side.allocator->buffers(side.stream)) {
        if (!mapPlanes(*buffer, colour ? kPlanes : 1, side.maps[buffer.get()])) {
            return Unexpected(
                Error{name, colour ? "cannot map a frame buffer's Y, U and V planes" : "cannot map a frame buffer",
                      "check the memory limits"});
        }
        std::unique_ptr<libcamera::Request> request = side.camera->createRequest();
        if (!request || request->addBuffer(side.stream, buffer.get()) != 0) {
            return Unexpected(Error{name, "cannot create a capture request", "check the camera"});
        }
        side.requests.push_back(std::move(request));
    }
    return {};
}

/// Starts the side's camera at `fps` and queues its requests.
Result<void, Error> startSide(Side& side, const std::string& name, double fps)
{
    libcamera::ControlList controls;
    const auto frameUs = static_cast<std::int64_t>(std::llround(1e6 / fps));
    controls.set(libcamera::controls::FrameDurationLimits, {frameUs, frameUs});
    if (side.camera->start(&controls) != 0) {
        return Unexpected(Error{name, "start failed", "check the camera"});
    }
    side.started = true;
    for (const std::unique_ptr<libcamera::Request>& request : side.requests) {
        if (side.camera->queueRequest(request.get()) != 0) {
            return Unexpected(Error{name, "cannot queue a capture request", "check the camera"});
        }
    }
    return {};
}

std::string describe(const LibcameraOptions& options)
{
    const std::string first = "libcamera " + (options.leftId.empty() ? "first camera" : options.leftId);
    return options.oneCamera    ? first + " (one camera)"
           : options.sideBySide ? first + " (side by side)"
                                : "libcamera " + (options.leftId.empty() ? "camera 0" : options.leftId) + " + " +
                                      (options.rightId.empty() ? "camera 1" : options.rightId);
}

} // namespace

LibcameraStereoCamera::LibcameraStereoCamera(const LibcameraOptions& options)
    : DeviceStereoCamera(options.colour, options.width, options.height, options.fps, describe(options)),
      options_(options)
{
    options_.sideBySide = options.sideBySide && !options.oneCamera;
}

LibcameraStereoCamera::~LibcameraStereoCamera()
{
    stop();
}

Result<std::unique_ptr<LibcameraStereoCamera>, Error> LibcameraStereoCamera::open(const LibcameraOptions& options)
{
    if (options.width <= 0 || options.height <= 0 || !(options.fps > 0.0) || !(options.maxPairSkewMs > 0.0)) {
        return Unexpected(Error{"libcamera", "size, rate or skew out of range", "check camera.width/height/fps"});
    }
    if (options.colour && (options.width % 2 != 0 || options.height % 2 != 0)) {
        return Unexpected(Error{"libcamera",
                                "colour frames need an even width and height (a YUV420 chroma sample covers 2 x 2 "
                                "pixels)",
                                "set camera.width/height to even numbers, or camera.colour: false"});
    }
    // libcamera is chatty at INFO. Set here, not in start(): open() runs while the program starts, before its threads
    // (reopen() after a lost camera calls start() only), and setenv races with any thread that reads the environment.
    // NOLINTNEXTLINE(concurrency-mt-unsafe): before the program's threads start (above)
    ::setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0);
    std::unique_ptr<LibcameraStereoCamera> camera(new LibcameraStereoCamera(options));
    if (auto started = camera->start(); !started) {
        return Unexpected(started.error());
    }
    return camera;
}

Result<void, Error> LibcameraStereoCamera::start()
{
    impl_ = std::make_unique<Impl>(options_.width, options_.height, options_.colour);
    if (!impl_->semaphore) {
        return Unexpected(Error{"libcamera", "sem_init failed", "check the system"});
    }
    impl_->manager = std::make_unique<libcamera::CameraManager>();
    if (const int rc = impl_->manager->start(); rc != 0) {
        return Unexpected(Error{"libcamera", std::string("CameraManager::start failed: ") + SysError{-rc}.text(),
                                "check that libcamera can access /dev/media* and /dev/video*"});
    }
    const auto cameras = impl_->manager->cameras();
    const bool pair = !options_.sideBySide && !options_.oneCamera;
    const std::size_t needed = pair ? 2 : 1;
    if (cameras.size() < needed) {
        return Unexpected(Error{"libcamera",
                                cameras.empty()
                                    ? std::string("no camera found")
                                    : "found " + std::to_string(cameras.size()) + " camera, a stereo pair needs 2",
                                "connect the cameras (libcamera's `cam --list` shows what it sees), set "
                                "camera.side_by_side for a one-sensor stereo camera, or use camera.backend v4l2"});
    }
    const auto pick = [&](const std::string& id, std::size_t index) -> std::shared_ptr<libcamera::Camera> {
        return id.empty() ? cameras[index] : impl_->manager->get(id);
    };
    const int frameWidth = options_.sideBySide ? 2 * options_.width : options_.width;
    const auto setUp = [&](Side& side, const std::shared_ptr<libcamera::Camera>& cam, const std::string& id,
                           void (Impl::*handler)(libcamera::Request*)) -> Result<void, Error> {
        const std::string name = "libcamera " + (cam ? cam->id() : id);
        if (!cam) {
            return Unexpected(Error{name, "no camera with this id", "list the ids with `cam --list`"});
        }
        if (auto configured = configureSide(side, cam, name, frameWidth, options_.height); !configured) {
            return configured;
        }
        if (auto mapped = mapBuffers(side, name, options_.colour); !mapped) {
            return mapped;
        }
        cam->requestCompleted.connect(impl_.get(), handler);
        return startSide(side, name, options_.fps);
    };
    if (auto left = setUp(impl_->left, pick(options_.leftId, 0), options_.leftId, &Impl::onLeft); !left) {
        stop();
        return left;
    }
    if (pair) {
        if (auto right = setUp(impl_->right, pick(options_.rightId, 1), options_.rightId, &Impl::onRight); !right) {
            stop();
            return right;
        }
    }
    return {};
}

void LibcameraStereoCamera::stop() noexcept
{
    if (!impl_) {
        return;
    }
    for (Side* side : {&impl_->left, &impl_->right}) {
        if (side->started) {
            side->camera->stop();
            side->started = false;
        }
        if (side->camera) {
            side->camera->requestCompleted.disconnect(impl_.get());
        }
        for (auto& [buffer, mapping] : side->maps) {
            (void)buffer;
            for (std::size_t i = 0; i < kPlanes; ++i) {
                if (mapping.address[i] != nullptr) {
                    ::munmap(mapping.address[i], mapping.length[i]);
                }
            }
        }
        side->maps.clear();
        side->requests.clear();
        if (side->allocator && side->stream != nullptr) {
            side->allocator->free(side->stream);
        }
        side->allocator.reset();
        if (side->acquired) {
            side->camera->release();
            side->acquired = false;
        }
        side->camera.reset();
    }
    if (impl_->manager) {
        impl_->manager->stop();
    }
    impl_.reset();
}

namespace {

void requeue(Side& side, libcamera::Request*& request) noexcept
{
    if (request != nullptr && side.started) {
        request->reuse(libcamera::Request::ReuseBuffers);
        (void)side.camera->queueRequest(request);
    }
    request = nullptr;
}

std::int64_t sensorStamp(const Side& side, const libcamera::Request* request) noexcept
{
    const libcamera::FrameBuffer* buffer = request->findBuffer(side.stream);
    return buffer != nullptr ? static_cast<std::int64_t>(buffer->metadata().timestamp) : 0;
}

const Side::Mapping* mappingOf(const Side& side, const libcamera::Request* request) noexcept
{
    const auto it = side.maps.find(request->findBuffer(side.stream));
    return it == side.maps.end() ? nullptr : &it->second;
}

/// Copies the Y plane columns [x0, x0 + width) of the request's buffer into `out`.
void copyY(const Side& side, const libcamera::Request* request, int x0, ImageViewU8 out) noexcept
{
    const Side::Mapping* mapping = mappingOf(side, request);
    if (mapping == nullptr) {
        return;
    }
    for (int y = 0; y < out.height(); ++y) {
        std::memcpy(out.row(y), mapping->plane[0] + static_cast<std::size_t>(y) * side.stride + x0,
                    static_cast<std::size_t>(out.width()));
    }
}

/// Converts the columns [x0, x0 + width) of the request's YUV420 buffer into `out`.
void copyBgr(const Side& side, const libcamera::Request* request, int x0, Yuv420ToBgr& toBgr, BgrView out) noexcept
{
    const Side::Mapping* mapping = mappingOf(side, request);
    if (mapping == nullptr) {
        return;
    }
    const Yuv420View yuv{mapping->plane[0], mapping->plane[1], mapping->plane[2], side.stride, side.stride / 2U};
    (void)toBgr.convert(yuv, x0, out);
}

} // namespace

void LibcameraStereoCamera::Impl::copy(const Side& side, const libcamera::Request* request, int x0,
                                       bool intoRight) noexcept
{
    if (toBgr) {
        copyBgr(side, request, x0, *toBgr, intoRight ? rightBgr.view() : leftBgr.view());
    } else {
        copyY(side, request, x0, intoRight ? rightGrey.view() : leftGrey.view());
    }
}

StereoViews LibcameraStereoCamera::Impl::images(bool leftOnly) const noexcept
{
    if (toBgr) {
        return bgrViews(leftBgr.view(), leftOnly ? ConstBgrView() : rightBgr.view());
    }
    return greyViews(leftGrey.view(), leftOnly ? ConstImageViewU8() : rightGrey.view());
}

GrabStatus LibcameraStereoCamera::grab(CameraFrame& out, std::chrono::nanoseconds timeout) noexcept
{
    if (!impl_) {
        return GrabStatus::Disconnected;
    }
    Impl& im = *impl_;
    requeue(im.left, im.left.delivered);
    requeue(im.right, im.right.delivered);
    const std::int64_t deadline = MonotonicClock::nowNs() + timeout.count();
    const bool stereo = !options_.sideBySide && !options_.oneCamera;
    const auto skewNs = static_cast<std::int64_t>(options_.maxPairSkewMs * 1e6);
    for (;;) {
        if (im.left.failed.load() || (stereo && im.right.failed.load())) {
            ++counters().disconnects;
            return GrabStatus::Disconnected;
        }
        if (im.left.pending == nullptr) {
            (void)im.left.completed.tryPop(im.left.pending);
        }
        if (stereo && im.right.pending == nullptr) {
            (void)im.right.completed.tryPop(im.right.pending);
        }
        const bool haveAll = im.left.pending != nullptr && (!stereo || im.right.pending != nullptr);
        if (haveAll && stereo) {
            const std::int64_t dt = sensorStamp(im.left, im.left.pending) - sensorStamp(im.right, im.right.pending);
            if (std::llabs(dt) > skewNs) {
                Side& older = dt < 0 ? im.left : im.right;
                requeue(older, older.pending); // the older frame has no partner: drop it, wait for the next
                continue;
            }
        }
        if (haveAll) {
            break;
        }
        const std::int64_t left = deadline - MonotonicClock::nowNs();
        if (left <= 0) {
            return GrabStatus::Timeout;
        }
        // On CLOCK_MONOTONIC, like `deadline`: a wall-clock step at boot (chrony, GPS) cannot stretch the wait.
        const timespec until = MonotonicClock::toTimespec(deadline);
        (void)::sem_clockwait(&im.ready, CLOCK_MONOTONIC, &until);
    }
    const libcamera::FrameBuffer* leftBuffer = im.left.pending->findBuffer(im.left.stream);
    const unsigned sequence = leftBuffer != nullptr ? leftBuffer->metadata().sequence : 0U;
    if (im.left.haveSequence && sequence > im.left.lastSequence + 1) {
        counters().sequenceGaps += sequence - im.left.lastSequence - 1;
    }
    im.left.haveSequence = true;
    im.left.lastSequence = sequence;
    im.copy(im.left, im.left.pending, 0, false);
    if (stereo) {
        im.copy(im.right, im.right.pending, 0, true);
        out.rightStampNs = sensorStamp(im.right, im.right.pending);
    } else if (options_.sideBySide) {
        im.copy(im.left, im.left.pending, options_.width, true);
        out.rightStampNs = sensorStamp(im.left, im.left.pending);
    } else {
        out.rightStampNs = 0; // one camera: a left-only frame
        ++counters().leftOnlyFrames;
    }
    out.leftStampNs = sensorStamp(im.left, im.left.pending);
    out.sequence = sequence;
    out.images = im.images(options_.oneCamera);
    im.left.delivered = im.left.pending;
    im.left.pending = nullptr;
    im.right.delivered = im.right.pending;
    im.right.pending = nullptr;
    ++counters().frames;
    return GrabStatus::Frame;
}

bool LibcameraStereoCamera::reconnect() noexcept
{
    stop();
    return static_cast<bool>(start());
}

} // namespace ugv::hal
