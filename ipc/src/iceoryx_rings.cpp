#include "ugv/ipc/iceoryx_rings.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <ctime>

#include "iceoryx_hoofs/log/logmanager.hpp"
#include "iceoryx_hoofs/posix_wrapper/posix_access_rights.hpp"
#include "iceoryx_posh/internal/roudi/roudi.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/untyped_publisher.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"
#include "iceoryx_posh/popo/user_trigger.hpp"
#include "iceoryx_posh/popo/wait_set.hpp"
#include "iceoryx_posh/roudi/iceoryx_roudi_components.hpp"
#include "iceoryx_posh/runtime/posh_runtime.hpp"
#include "iceoryx_posh/runtime/posh_runtime_single_process.hpp"
#include "ugv/platform/clock.hpp"

namespace ugv::ipc {

namespace {

constexpr std::uint32_t kChunkAlignment = 64;
constexpr std::uint64_t kFramePoolChunks = 16;

// ThreadSanitizer (the tsan preset) cannot see the atomics inside Debian's iceoryx, which is not instrumented, that
// hand a chunk from the publisher to its subscribers and back to the pool: without these two it reports every
// frame's pixels as a race. handOver() where our code gives a chunk away (publish, release), takeOver() where it gets
// one (loan, take); the chunk's address is the synchronisation object. Nothing in other builds.
#if defined(__SANITIZE_THREAD__)
// NOLINTBEGIN(readability-identifier-naming,cppcoreguidelines-pro-type-const-cast): TSan's
// interface, by its names; it takes the address as void* and only uses it as a key
extern "C" void __tsan_acquire(void* address);
extern "C" void __tsan_release(void* address);
void handOver(const void* chunk) noexcept
{
    __tsan_release(const_cast<void*>(chunk));
}
void takeOver(const void* chunk) noexcept
{
    __tsan_acquire(const_cast<void*>(chunk));
}
// NOLINTEND(readability-identifier-naming,cppcoreguidelines-pro-type-const-cast)
#else
void handOver(const void* /*chunk*/) noexcept {}
void takeOver(const void* /*chunk*/) noexcept {}
#endif

iox::capro::ServiceDescription describe(Topic topic)
{
    return iox::capro::ServiceDescription{iox::capro::IdString_t(iox::cxx::TruncateToCapacity, topic.service),
                                          iox::capro::IdString_t(iox::cxx::TruncateToCapacity, topic.instance),
                                          iox::capro::IdString_t(iox::cxx::TruncateToCapacity, topic.event)};
}

iox::units::Duration toDuration(std::chrono::nanoseconds timeout)
{
    return iox::units::Duration::fromNanoseconds(
        static_cast<std::uint64_t>(std::max<std::int64_t>(0, timeout.count())));
}

std::uint32_t payloadSize(const void* userPayload)
{
    return iox::mepoo::ChunkHeader::fromUserPayload(userPayload)->userPayloadSize();
}

/// Publishers never wait for a slow subscriber: its oldest chunks are dropped.
iox::popo::PublisherOptions publisherOptions()
{
    iox::popo::PublisherOptions o;
    o.historyCapacity = 0;
    o.subscriberTooSlowPolicy = iox::popo::ConsumerTooSlowPolicy::DISCARD_OLDEST_DATA;
    return o;
}

iox::popo::SubscriberOptions subscriberOptions(int queueCapacity)
{
    iox::popo::SubscriberOptions o;
    o.queueCapacity = static_cast<std::uint64_t>(queueCapacity);
    o.historyRequest = 0;
    o.queueFullPolicy = iox::popo::QueueFullPolicy::DISCARD_OLDEST_DATA;
    return o;
}

/// iceoryx logs at debug level by default: warnings and errors only (to stderr, as iceoryx does).
void quietIceoryxLog()
{
    iox::log::LogManager::GetLogManager().SetDefaultLogLevel(iox::log::LogLevel::kWarn);
}

} // namespace

// Named, not anonymous: the subscribers' Impl types (declared in the header) derive from it.
namespace detail {

/// A subscriber with the wait set that blocks on its data (attached for its whole life), and a trigger that ends a
/// wait at once (wake()). iceoryx 2.0.3 times its waits on CLOCK_REALTIME (sem_timedwait): a clock step back
/// during a wait stretches it by the step; frames still end it, and wake() does when the owner stops.
struct WaitingSubscriber {
    WaitingSubscriber(Topic topic, int queueCapacity) : subscriber(describe(topic), subscriberOptions(queueCapacity))
    {
        attached = !waitSet.attachState(subscriber, iox::popo::SubscriberState::HAS_DATA).has_error() &&
                   !waitSet.attachEvent(wakeTrigger).has_error();
    }
    ~WaitingSubscriber()
    {
        if (attached) {
            waitSet.detachState(subscriber, iox::popo::SubscriberState::HAS_DATA);
        }
    }
    WaitingSubscriber(const WaitingSubscriber&) = delete;
    WaitingSubscriber& operator=(const WaitingSubscriber&) = delete;
    WaitingSubscriber(WaitingSubscriber&&) = delete;
    WaitingSubscriber& operator=(WaitingSubscriber&&) = delete;

    /// The oldest queued chunk, after waiting up to `timeout` for one; nullptr when none came.
    const void* take(std::chrono::nanoseconds timeout) noexcept
    {
        if (!subscriber.hasData()) {
            (void)waitSet.timedWait(toDuration(timeout));
        }
        return takeNow();
    }

    /// The oldest queued chunk, or nullptr.
    const void* takeNow() noexcept
    {
        auto taken = subscriber.take();
        if (taken.has_error()) {
            return nullptr;
        }
        takeOver(taken.value());
        return taken.value();
    }

    /// Gives a taken chunk back.
    void release(const void* chunk) noexcept
    {
        handOver(chunk);
        subscriber.release(chunk);
    }

    iox::popo::UntypedSubscriber subscriber;
    iox::popo::UserTrigger wakeTrigger;
    iox::popo::WaitSet<2> waitSet; // after the trigger: destroyed first, it detaches both
    bool attached = false;
};

} // namespace detail

namespace {

std::string topicName(Topic topic)
{
    return std::string(topic.service) + "/" + topic.instance + "/" + topic.event;
}

} // namespace

// ------------------------------------------------------------------------------------------------------ runtime

bool roudiReachable() noexcept
{
    // RouDi's runtime channel is a unix datagram socket at IOX_UDS_SOCKET_PATH_PREFIX + "roudi"; connect() fails
    // (ECONNREFUSED or ENOENT) when no RouDi listens on it.
    const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        return false;
    }
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    const std::string path =
        std::string(iox::platform::IOX_UDS_SOCKET_PATH_PREFIX) + iox::roudi::IPC_CHANNEL_ROUDI_NAME;
    std::strncpy(address.sun_path, path.c_str(), sizeof(address.sun_path) - 1);
    const bool connected = ::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) == 0;
    ::close(fd);
    return connected;
}

Result<void, Error> startRuntime(const std::string& appName)
{
    if (!roudiReachable()) {
        return Unexpected(Error{"iceoryx", "no RouDi is running on this machine (nothing answers on /tmp/roudi)",
                                "start it first: `iox-roudi -c /etc/ugvsense/roudi.toml -m off` (the ugvsense-roudi "
                                "systemd unit), or run ugvsensed --embedded-roudi"});
    }
    quietIceoryxLog();
    iox::runtime::PoshRuntime::initRuntime(iox::RuntimeName_t(iox::cxx::TruncateToCapacity, appName.c_str()));
    return {};
}

struct EmbeddedRouDi::Impl {
    iox::RouDiConfig_t config;
    std::unique_ptr<iox::roudi::IceOryxRouDiComponents> components;
    std::unique_ptr<iox::roudi::RouDi> roudi;
    std::unique_ptr<iox::runtime::PoshRuntimeSingleProcess> runtime;
};

EmbeddedRouDi::EmbeddedRouDi(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

EmbeddedRouDi::~EmbeddedRouDi()
{
    if (impl_) {
        impl_->runtime.reset();
        impl_->roudi.reset();
        impl_->components.reset();
    }
}

Result<std::unique_ptr<EmbeddedRouDi>, Error> EmbeddedRouDi::start(const std::string& appName,
                                                                   std::size_t maxFrameBytes)
{
    if (roudiReachable()) {
        return Unexpected(Error{"iceoryx", "a RouDi already runs on this machine",
                                "use it (leave out --embedded-roudi) or stop it first"});
    }
    quietIceoryxLog();
    auto impl = std::make_unique<Impl>();
    impl->config.setDefaults();
    iox::mepoo::MePooConfig mepoo;
    // Small pools for iceoryx's own use and the sectors (a SectorsMessage is ~4.5 KB), one for frames.
    mepoo.addMemPool({128, 1000});
    mepoo.addMemPool({1024, 1000});
    mepoo.addMemPool({16384, 256});
    const auto frameChunk = static_cast<std::uint32_t>((maxFrameBytes + 4096 + 65535) / 65536 * 65536);
    mepoo.addMemPool({frameChunk, kFramePoolChunks});
    const auto group = iox::posix::PosixGroup::getGroupOfCurrentProcess().getName();
    impl->config.m_sharedMemorySegments.clear();
    impl->config.m_sharedMemorySegments.push_back({group, group, mepoo});
    impl->components = std::make_unique<iox::roudi::IceOryxRouDiComponents>(impl->config);
    impl->roudi = std::make_unique<iox::roudi::RouDi>(
        impl->components->rouDiMemoryManager, impl->components->portManager,
        iox::roudi::RouDi::RoudiStartupParameters{iox::roudi::MonitoringMode::OFF, false});
    impl->runtime = std::make_unique<iox::runtime::PoshRuntimeSingleProcess>(
        iox::RuntimeName_t(iox::cxx::TruncateToCapacity, appName.c_str()));
    return std::unique_ptr<EmbeddedRouDi>(new EmbeddedRouDi(std::move(impl)));
}

// ------------------------------------------------------------------------------------------------------- frames

struct FramePublisher::Impl {
    explicit Impl(Topic topic) : publisher(describe(topic), publisherOptions()) {}
    iox::popo::UntypedPublisher publisher;
};

FramePublisher::FramePublisher(std::unique_ptr<Impl> impl, PixelFormat format, int width, int height)
    : impl_(std::move(impl)), format_(format), width_(width), height_(height)
{
}
FramePublisher::~FramePublisher() = default;

Result<std::unique_ptr<FramePublisher>, Error> FramePublisher::create(PixelFormat format, int width, int height,
                                                                      Topic topic)
{
    if (bytesPerPixel(format) == 0) {
        return Unexpected(Error{topicName(topic), "unknown pixel format " + std::to_string(static_cast<int>(format)),
                                "publish Grey8 or Bgr8 frames"});
    }
    if (width <= 0 || height <= 0 || width > static_cast<int>(kMaxFrameSide) ||
        height > static_cast<int>(kMaxFrameSide)) {
        return Unexpected(Error{topicName(topic),
                                "frame size " + std::to_string(width) + "x" + std::to_string(height) + " out of range",
                                "configure a real camera size"});
    }
    return std::unique_ptr<FramePublisher>(new FramePublisher(std::make_unique<Impl>(topic), format, width, height));
}

bool FramePublisher::publish(std::uint64_t sequence, std::int64_t leftStampNs, std::int64_t rightStampNs,
                             const StereoViews& images, std::atomic<std::int64_t>* publishStampNs) noexcept
{
    if (images.format != format_ || !images.fits(width_, height_)) {
        ++loanFailures_;
        return false;
    }
    const std::size_t bytes =
        packedFrameBytes(format_, static_cast<std::uint32_t>(width_), static_cast<std::uint32_t>(height_));
    auto loaned = impl_->publisher.loan(static_cast<std::uint32_t>(bytes), kChunkAlignment);
    if (loaned.has_error()) {
        ++loanFailures_;
        return false;
    }
    auto* chunk = static_cast<std::byte*>(loaned.value());
    takeOver(chunk);
    (void)packFrame(chunk, static_cast<std::uint32_t>(width_), static_cast<std::uint32_t>(height_), sequence,
                    leftStampNs, rightStampNs, images); // the format and sizes were checked above
    if (publishStampNs != nullptr) {
        publishStampNs->store(MonotonicClock::nowNs(), std::memory_order_release);
    }
    handOver(chunk);
    impl_->publisher.publish(chunk);
    ++published_;
    return true;
}

bool FramePublisher::hasSubscribers() const noexcept
{
    return impl_->publisher.hasSubscribers();
}

struct FrameSubscriber::Impl : detail::WaitingSubscriber {
    using WaitingSubscriber::WaitingSubscriber;
};

FrameSubscriber::FrameSubscriber(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FrameSubscriber::~FrameSubscriber() = default;

Result<std::unique_ptr<FrameSubscriber>, Error> FrameSubscriber::create(int queueCapacity, Topic topic)
{
    if (queueCapacity < 1 || queueCapacity > 16) {
        return Unexpected(Error{topicName(topic), "queue capacity " + std::to_string(queueCapacity) + " not in 1..16",
                                "1 for the latest frame only"});
    }
    auto impl = std::make_unique<Impl>(topic, queueCapacity);
    if (!impl->attached) {
        return Unexpected(Error{topicName(topic), "cannot attach the subscriber to a wait set", "a bug"});
    }
    return std::unique_ptr<FrameSubscriber>(new FrameSubscriber(std::move(impl)));
}

TakeStatus FrameSubscriber::take(TakenFrame& out, std::chrono::nanoseconds timeout) noexcept
{
    return takeFrame(out, timeout, true);
}

TakeStatus FrameSubscriber::takeOldest(TakenFrame& out, std::chrono::nanoseconds timeout) noexcept
{
    return takeFrame(out, timeout, false);
}

bool FrameSubscriber::hasData() const noexcept
{
    return impl_->subscriber.hasData();
}

void FrameSubscriber::wake() noexcept
{
    impl_->wakeTrigger.trigger();
}

TakeStatus FrameSubscriber::takeFrame(TakenFrame& out, std::chrono::nanoseconds timeout, bool newest) noexcept
{
    const void* payload = impl_->take(timeout);
    if (payload == nullptr) {
        return TakeStatus::Timeout;
    }
    // Latest frame wins: anything newer already queued replaces it.
    while (newest && impl_->subscriber.hasData()) {
        const void* newer = impl_->takeNow();
        if (newer == nullptr) {
            break;
        }
        impl_->release(payload);
        payload = newer;
    }
    const std::size_t bytes = payloadSize(payload);
    const auto* chunk = static_cast<const std::byte*>(payload);
    auto views = viewFrame(chunk, bytes);
    if (!views) {
        impl_->release(payload);
        ++malformed_;
        return TakeStatus::Malformed;
    }
    out.chunk = chunk;
    out.bytes = bytes;
    std::memcpy(&out.header, chunk, sizeof(out.header));
    out.views = *views;
    return TakeStatus::Frame;
}

void FrameSubscriber::release(TakenFrame& frame) noexcept
{
    if (frame.chunk != nullptr) {
        impl_->release(frame.chunk);
        frame = TakenFrame{};
    }
}

// ------------------------------------------------------------------------------------------------------ sectors

struct SectorsPublisher::Impl {
    explicit Impl(Topic topic) : publisher(describe(topic), publisherOptions()) {}
    iox::popo::UntypedPublisher publisher;
};

SectorsPublisher::SectorsPublisher(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SectorsPublisher::~SectorsPublisher() = default;

Result<std::unique_ptr<SectorsPublisher>, Error> SectorsPublisher::create(Topic topic)
{
    return std::unique_ptr<SectorsPublisher>(new SectorsPublisher(std::make_unique<Impl>(topic)));
}

bool SectorsPublisher::publish(const SectorsMessage& message) noexcept
{
    auto loaned = impl_->publisher.loan(sizeof(SectorsMessage), alignof(SectorsMessage));
    if (loaned.has_error()) {
        ++loanFailures_;
        return false;
    }
    takeOver(loaned.value());
    std::memcpy(loaned.value(), &message, sizeof(message));
    handOver(loaned.value());
    impl_->publisher.publish(loaned.value());
    return true;
}

struct SectorsSubscriber::Impl : detail::WaitingSubscriber {
    using WaitingSubscriber::WaitingSubscriber;
};

SectorsSubscriber::SectorsSubscriber(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SectorsSubscriber::~SectorsSubscriber() = default;

Result<std::unique_ptr<SectorsSubscriber>, Error> SectorsSubscriber::create(int queueCapacity, Topic topic)
{
    if (queueCapacity < 1 || queueCapacity > 256) {
        return Unexpected(
            Error{topicName(topic), "queue capacity " + std::to_string(queueCapacity) + " not in 1..256", "e.g. 16"});
    }
    auto impl = std::make_unique<Impl>(topic, queueCapacity);
    if (!impl->attached) {
        return Unexpected(Error{topicName(topic), "cannot attach the subscriber to a wait set", "a bug"});
    }
    return std::unique_ptr<SectorsSubscriber>(new SectorsSubscriber(std::move(impl)));
}

TakeStatus SectorsSubscriber::take(SectorsMessage& out, std::chrono::nanoseconds timeout) noexcept
{
    const void* payload = impl_->take(timeout);
    if (payload == nullptr) {
        return TakeStatus::Timeout;
    }
    const std::size_t bytes = payloadSize(payload);
    TakeStatus status = TakeStatus::Malformed;
    if (bytes >= sizeof(SectorsMessage)) {
        SectorsMessage copy;
        std::memcpy(&copy, payload, sizeof(copy));
        if (validate(copy, bytes)) {
            out = copy;
            status = TakeStatus::Frame;
        }
    }
    impl_->release(payload);
    if (status == TakeStatus::Malformed) {
        ++malformed_;
    }
    return status;
}

} // namespace ugv::ipc
