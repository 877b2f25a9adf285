// bench-dds: the sectors' way onto the bus, on one host.
// - BM_FramePathHandover: what the publish thread (the frame path) pays to hand a frame to the bus task: the copy
//   into the wait-free ring and the semaphore post (a consumer thread drains it). Target: under 10 us.
// - BM_SectorsHandoverToSubscriber: a child process (this program again, --child-bridge) runs the service's bus side at
// 100 Hz (a thread pushing frames
//   into the ring as the publish thread does, the bus task popping them into the real DdsBridge); this process
//   subscribes to ugvsense/sectors and measures hand-over -> received (the sample's publish stamp is the hand-over
//   time). Target: p99 under 1 ms. Baseline in the same run, BM_RawWriteToSubscriber: the same sample written
//   directly by a Fast DDS writer in a child process (no ring, no task, no conversion).
// - BM_SectorsHandoverToSubscriberSecured / BM_RawWriteToSubscriberSecured: the same two on a secured bus (DDS
//   Security: PKI-DH, Access-Permissions, AES-GCM; the files made once per run by
//   bringup/deploy/security/make_security.sh in a temporary folder): the cost of security against the open bus in the
//   same run. Target: p99 at most 1.5x the open bus's (issue 22 item 4).
// - BM_SectorsHandoverOpenAndSecuredInTurns / BM_RawWriteOpenAndSecuredInTurns: both buses in one run, taking turns
//   of 0.12 s (a writer's process each, the idle one paused), so that the machine's busy spells fall on both alike;
//   the counters hold both buses' p50/p99 and the secured/open ratios.
// The latency benchmarks report p50/p99/max counters [us] over the iterations (manual time = the latency).
#include <fcntl.h>
#include <semaphore.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "ugv/ipc/dds_convert.hpp"
#include "ugv/platform/clock.hpp"
#include "ugv/platform/spsc_ring.hpp"
#include "ugv/service/dds_bridge.hpp"
#include "ugv/service/service.hpp"

namespace {

using namespace ugv;
namespace dds = ugv::ipc::dds;

constexpr int kDomain = 201;
constexpr const char* kWriterIdentity = "bench";        ///< the child's certificate (the service's vehicle_id)
constexpr const char* kReaderIdentity = "bench-reader"; ///< this process's

/// Where this run's secured team lives (removed at the end of main).
std::filesystem::path securityFolderPath()
{
    return std::filesystem::temp_directory_path() / ("ugv-bench-dds-security-" + std::to_string(::getpid()));
}

/// The secured variants' team: a CA, the child's and this process's files (folder/<identity>/), made once per run.
/// Empty when make_security.sh failed (the secured benchmarks then skip).
const std::string& securityFolder(const std::string& partition)
{
    static const std::string folder = [&partition] {
        const std::string dir = securityFolderPath().string();
        const pid_t maker = ::fork(); // and exec at once (no Fast DDS in the copy)
        if (maker == 0) {
            const int quiet = ::open("/dev/null", O_WRONLY);
            ::dup2(quiet, STDOUT_FILENO);
            ::execl("/bin/bash", "bash", UGV_SOURCE_DIR "/bringup/deploy/security/make_security.sh", dir.c_str(),
                    "--partition", partition.c_str(), kWriterIdentity, kReaderIdentity, nullptr);
            ::_exit(127);
        }
        int status = 0;
        const bool made =
            maker > 0 && ::waitpid(maker, &status, 0) == maker && WIFEXITED(status) && WEXITSTATUS(status) == 0;
        return made ? dir : std::string();
    }();
    return folder;
}

/// `bc` secured as `identity` with the files in `folder`, or as is when `folder` is empty (the open bus). With
/// UGV_BENCH_DDS_UDP=1 in the environment (the children inherit it), UDP only, as between vehicles: the team bus
/// crosses the network, so that is the transport its cost of security is about.
dds::BusConfig secured(dds::BusConfig bc, const std::string& folder, const char* identity)
{
    const char* udp = std::getenv("UGV_BENCH_DDS_UDP");
    if (udp != nullptr && std::string(udp) == "1") {
        bc.sharedMemory = false;
    }
    if (!folder.empty()) {
        bc.security = dds::securityFromFolder(folder + "/" + identity, identity);
    }
    return bc;
}

service::BusFrame sampleFrame()
{
    service::BusFrame f;
    initSectors(f.message.sectors, 64, 90.0F);
    for (int i = 0; i < 64; ++i) {
        Sector& s = f.message.sectors.sectors[static_cast<std::size_t>(i)];
        s.state = i % 3 == 0 ? SectorState::Obstacle : SectorState::Clear;
        s.kind = i % 3 == 0 ? (i % 2 == 0 ? ObstacleKind::Positive : ObstacleKind::Negative) : ObstacleKind::None;
        s.rangeM = i % 3 == 0 ? 2.0F + 0.1F * static_cast<float>(i) : INFINITY;
        s.heightM = 0.2F;
        s.confidence = 0.9F;
        s.danger = i % 3 == 0 ? DangerClass::Blue : DangerClass::Green;
    }
    return f;
}

adapters::ServiceConfig benchConfig()
{
    adapters::ServiceConfig c;
    c.vehicleId = "bench";
    c.dds.domainId = kDomain;
    c.dds.partition = "bench-" + std::to_string(::getpid());
    return c;
}

void handover(benchmark::State& state, bool post)
{
    // As in the service: the bus task sleeps in sem_wait when a frame comes, so the post wakes it (a futex call).
    // Each iteration times the push and the post only, then waits (untimed) for the consumer to sleep again.
    SpscRing<service::BusFrame, 8> ring;
    sem_t ready;
    ::sem_init(&ready, 0, 0);
    std::atomic<bool> stop{false};
    std::atomic<std::uint64_t> taken{0};
    std::thread consumer([&] {
        service::BusFrame f;
        while (!stop.load(std::memory_order_relaxed)) {
            ::sem_wait(&ready);
            while (ring.tryPop(f)) {
                taken.fetch_add(1, std::memory_order_release);
            }
        }
    });
    service::BusFrame frame = sampleFrame();
    std::uint64_t pushed = 0;
    for (auto _ : state) {
        const std::int64_t t0 = MonotonicClock::nowNs();
        frame.message.publishStampNs = t0;
        if (ring.tryPush(frame)) {
            if (post) {
                ::sem_post(&ready);
            }
            ++pushed;
        }
        const std::int64_t t1 = MonotonicClock::nowNs();
        if (!post) {
            ::sem_post(&ready);
        }
        state.SetIterationTime(static_cast<double>(t1 - t0) * 1e-9);
        while (taken.load(std::memory_order_acquire) < pushed) {
        }
        ::usleep(50); // let the consumer get back into sem_wait
    }
    stop.store(true);
    ::sem_post(&ready);
    consumer.join();
    ::sem_destroy(&ready);
    state.counters["frame_bytes"] = sizeof(service::BusFrame);
}
/// The whole hand-over (the service's).
void BM_FramePathHandover(benchmark::State& state)
{
    handover(state, true);
}
/// Its parts: the copy into the ring alone (the post, untimed, after it).
void BM_FramePathRingPushOnly(benchmark::State& state)
{
    handover(state, false);
}
BENCHMARK(BM_FramePathRingPushOnly)->UseManualTime()->Iterations(20000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FramePathHandover)->UseManualTime()->Iterations(20000)->Unit(benchmark::kMicrosecond);

/// A writer's child writes nothing between SIGUSR1 and SIGUSR2 (measurePaired takes turns) and returns at SIGTERM,
/// so that its participant is deleted and Fast DDS removes its shared-memory segment (a killed one leaves about
/// 0.5 MB in /dev/shm until `fastdds shm clean`).
volatile std::sig_atomic_t gPaused = 0;
volatile std::sig_atomic_t gStop = 0;

void installChildSignals()
{
    ::signal(SIGUSR1, [](int) { gPaused = 1; });
    ::signal(SIGUSR2, [](int) { gPaused = 0; });
    ::signal(SIGTERM, [](int) { gStop = 1; });
}

/// The child's side: the service's ring and bus task feeding the real DdsBridge, 100 frames per second.
void runBridgeChild(const std::string& partition, const std::string& security)
{
    adapters::ServiceConfig config = benchConfig();
    config.dds.partition = partition;
    auto bus = dds::Bus::create(secured(service::busConfig(config), security, kWriterIdentity));
    auto bridge = service::DdsBridge::create(**bus, config, std::chrono::milliseconds(10));
    SpscRing<service::BusFrame, 8> ring;
    sem_t ready;
    ::sem_init(&ready, 0, 0);
    std::thread busTask([&] {
        service::BusFrame f;
        while (gStop == 0) {
            ::sem_wait(&ready);
            while (ring.tryPop(f)) {
                (*bridge)->onFrame(f);
            }
        }
    });
    service::BusFrame frame = sampleFrame();
    installChildSignals();
    for (std::uint64_t seq = 1; gStop == 0; ++seq) {
        ::usleep(10000);
        if (gPaused != 0) {
            continue;
        }
        frame.message.sectors.sequence = seq;
        frame.message.sectors.captureStampNs = MonotonicClock::nowNs() - 30'000'000;
        frame.message.publishStampNs = MonotonicClock::nowNs(); // the hand-over
        if (ring.tryPush(frame)) {
            ::sem_post(&ready);
        }
    }
    ::sem_post(&ready); // the bus task sees the stop
    busTask.join();
}

/// The baseline's child: the same sample straight from a Fast DDS writer, 100 per second.
void runRawChild(const std::string& partition, const std::string& security)
{
    dds::BusConfig bc;
    bc.domainId = kDomain;
    bc.partitions = {partition};
    auto bus = dds::Bus::create(secured(bc, security, kWriterIdentity));
    auto writer = (*bus)->writer<dds::msg::ObstacleSectors>();
    dds::msg::ObstacleSectors sample;
    const service::BusFrame frame = sampleFrame();
    dds::toDds(frame.message.sectors, {}, "bench", 0, 0, sample);
    installChildSignals();
    while (gStop == 0) {
        ::usleep(10000);
        if (gPaused != 0) {
            continue;
        }
        sample.publish_stamp_ns(dds::realtimeNowNs());
        writer->write(sample);
    }
}

/// This run's partition of a variant. The secured variants share one (the files name it), so that one team of
/// files serves them all.
std::string partitionOf(bool raw, bool secure, const char* suffix = "")
{
    return "bench-" + std::to_string(::getpid()) +
           (secure ? std::string("-secured")
            : raw  ? std::string("-raw")
                   : std::string("-bridge")) +
           suffix;
}

/// Starts the writer's side in a fresh process (fork + exec of this program): a forked copy of a process that
/// already ran Fast DDS inherits its factory without its threads and hangs.
pid_t startChild(bool raw, const std::string& partition, const std::string& security)
{
    const pid_t child = ::fork();
    if (child == 0) {
        ::execl("/proc/self/exe", "bench-dds", raw ? "--child-raw" : "--child-bridge", partition.c_str(),
                security.c_str(), nullptr);
        ::_exit(127);
    }
    return child;
}

/// Asks the child to end (its participant deleted, its shared memory removed) and kills it if it has not within 5 s.
void stopChild(pid_t child)
{
    ::kill(child, SIGTERM);
    for (int waited = 0; waited < 500; ++waited) {
        if (::waitpid(child, nullptr, WNOHANG) == child) {
            return;
        }
        ::usleep(10000);
    }
    ::kill(child, SIGKILL);
    ::waitpid(child, nullptr, 0);
}

/// A subscriber of one bus: latency [us] of each sample from its publish stamp (the hand-over's monotonic time on
/// the bus's real-time clock) to its take.
class LatencyReader {
public:
    LatencyReader(const std::string& partition, const std::string& security)
    {
        dds::BusConfig bc;
        bc.domainId = kDomain;
        bc.partitions = {partition};
        auto bus = dds::Bus::create(secured(bc, security, kReaderIdentity));
        bus_ = std::move(bus.value());
        reader_ = *bus_->reader<dds::msg::ObstacleSectors>();
    }
    /// Waits for the writer and 20 samples (discovery, first touch).
    void warmUp()
    {
        while (reader_.matched() == 0) {
            ::usleep(1000);
        }
        for (int warm = 0; warm < 20;) {
            warm += takeOne() ? 1 : 0;
        }
    }
    /// The next sample's latency [s].
    double next()
    {
        skip();
        const double latencyS = static_cast<double>(dds::realtimeNowNs() - sample_.publish_stamp_ns()) * 1e-9;
        us_.push_back(latencyS * 1e6);
        return latencyS;
    }
    /// Waits for the next sample and drops it.
    void skip()
    {
        while (!takeOne()) {
        }
    }
    /// Takes what is queued, unrecorded.
    void drain()
    {
        while (reader_.take(sample_)) {
        }
    }
    /// The p-quantile [us] of the latencies so far.
    [[nodiscard]] double quantile(double p)
    {
        std::sort(us_.begin(), us_.end());
        return us_[std::min(us_.size() - 1, static_cast<std::size_t>(p * static_cast<double>(us_.size())))];
    }

private:
    bool takeOne() { return reader_.wait(std::chrono::milliseconds(100)) && reader_.take(sample_); }

    std::unique_ptr<dds::Bus> bus_;
    dds::Reader<dds::msg::ObstacleSectors> reader_;
    dds::msg::ObstacleSectors sample_;
    std::vector<double> us_;
};

void measure(benchmark::State& state, bool raw, bool secure)
{
    const std::string partition = partitionOf(raw, secure);
    const std::string security = secure ? securityFolder(partition) : std::string();
    if (secure && security.empty()) {
        state.SkipWithError("bringup/deploy/security/make_security.sh failed (openssl missing?)");
        return;
    }
    const pid_t child = startChild(raw, partition, security);
    LatencyReader reader(partition, security);
    reader.warmUp();
    for (auto _ : state) {
        state.SetIterationTime(reader.next());
    }
    stopChild(child);
    state.counters["p50_us"] = reader.quantile(0.50);
    state.counters["p99_us"] = reader.quantile(0.99);
    state.counters["max_us"] = reader.quantile(1.0);
}

/// The open and the secured bus in turns of 0.12 s (12 samples; the first 2 after the resume are not recorded: the
/// writer's threads wake from idle), a writer's process each: the machine's busy spells fall on both alike (on a
/// shared machine a spell inside one 10 s run decides that run's p99), and only one bus writes at a time (the other's
/// child is paused), so neither loads the other. Samples in flight at a switch are dropped. One iteration: 1000 samples
/// of each; its time is the secured bus's p99, the counters give both buses' quantiles and their ratios.
void measurePaired(benchmark::State& state, bool raw)
{
    const std::string securedPartition = partitionOf(raw, true);
    const std::string openPartition = partitionOf(raw, false, "-paired");
    const std::string security = securityFolder(securedPartition);
    if (security.empty()) {
        state.SkipWithError("bringup/deploy/security/make_security.sh failed (openssl missing?)");
        return;
    }
    const std::array<pid_t, 2> child{startChild(raw, openPartition, std::string()),
                                     startChild(raw, securedPartition, security)};
    std::array<LatencyReader, 2> bus{LatencyReader(openPartition, std::string()),
                                     LatencyReader(securedPartition, security)};
    bus[0].warmUp();
    bus[1].warmUp();
    constexpr int kSamples = 1000;
    constexpr int kTurn = 10;  // samples recorded per turn
    constexpr int kWakeUp = 2; // and the first ones after a resume, not recorded (threads woken from idle)
    for (auto _ : state) {
        for (int turn = 0; turn < 2 * kSamples / kTurn; ++turn) {
            const int on = turn % 2;
            ::kill(child[static_cast<std::size_t>(1 - on)], SIGUSR1);
            ::kill(child[static_cast<std::size_t>(on)], SIGUSR2);
            ::usleep(30000); // what was in flight arrives
            bus[0].drain();
            bus[1].drain();
            for (int i = 0; i < kWakeUp; ++i) {
                bus[static_cast<std::size_t>(on)].skip();
            }
            for (int i = 0; i < kTurn; ++i) {
                (void)bus[static_cast<std::size_t>(on)].next();
            }
        }
        state.SetIterationTime(bus[1].quantile(0.99) * 1e-6);
    }
    for (const pid_t c : child) {
        stopChild(c);
    }
    state.counters["open_p50_us"] = bus[0].quantile(0.50);
    state.counters["open_p99_us"] = bus[0].quantile(0.99);
    state.counters["secured_p50_us"] = bus[1].quantile(0.50);
    state.counters["secured_p99_us"] = bus[1].quantile(0.99);
    state.counters["ratio_p50"] = bus[1].quantile(0.50) / bus[0].quantile(0.50);
    state.counters["ratio_p99"] = bus[1].quantile(0.99) / bus[0].quantile(0.99);
}

void BM_SectorsHandoverToSubscriber(benchmark::State& state)
{
    measure(state, false, false);
}
void BM_RawWriteToSubscriber(benchmark::State& state)
{
    measure(state, true, false);
}
void BM_SectorsHandoverToSubscriberSecured(benchmark::State& state)
{
    measure(state, false, true);
}
void BM_RawWriteToSubscriberSecured(benchmark::State& state)
{
    measure(state, true, true);
}
BENCHMARK(BM_SectorsHandoverToSubscriber)->UseManualTime()->Iterations(1000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RawWriteToSubscriber)->UseManualTime()->Iterations(1000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SectorsHandoverToSubscriberSecured)->UseManualTime()->Iterations(1000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RawWriteToSubscriberSecured)->UseManualTime()->Iterations(1000)->Unit(benchmark::kMicrosecond);
void BM_SectorsHandoverOpenAndSecuredInTurns(benchmark::State& state)
{
    measurePaired(state, false);
}
void BM_RawWriteOpenAndSecuredInTurns(benchmark::State& state)
{
    measurePaired(state, true);
}
BENCHMARK(BM_SectorsHandoverOpenAndSecuredInTurns)->UseManualTime()->Iterations(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RawWriteOpenAndSecuredInTurns)->UseManualTime()->Iterations(1)->Unit(benchmark::kMicrosecond);

} // namespace

int main(int argc, char** argv)
{
    if (argc == 4 && std::string(argv[1]) == "--child-raw") {
        runRawChild(argv[2], argv[3]);
        return 0;
    }
    if (argc == 4 && std::string(argv[1]) == "--child-bridge") {
        runBridgeChild(argv[2], argv[3]);
        return 0;
    }
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    std::error_code ec;
    std::filesystem::remove_all(securityFolderPath(), ec); // the private keys too
    return 0;
}
