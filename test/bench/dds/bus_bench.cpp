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
// The latency benchmarks report p50/p99/max counters [us] over the iterations (manual time = the latency).
#include <fcntl.h>
#include <semaphore.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
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

/// The child's side: the service's ring and bus task feeding the real DdsBridge, 100 frames per second.
[[noreturn]] void runBridgeChild(const std::string& partition, const std::string& security)
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
        for (;;) {
            ::sem_wait(&ready);
            while (ring.tryPop(f)) {
                (*bridge)->onFrame(f);
            }
        }
    });
    service::BusFrame frame = sampleFrame();
    for (std::uint64_t seq = 1;; ++seq) {
        ::usleep(10000);
        frame.message.sectors.sequence = seq;
        frame.message.sectors.captureStampNs = MonotonicClock::nowNs() - 30'000'000;
        frame.message.publishStampNs = MonotonicClock::nowNs(); // the hand-over
        if (ring.tryPush(frame)) {
            ::sem_post(&ready);
        }
    }
}

/// The baseline's child: the same sample straight from a Fast DDS writer, 100 per second.
[[noreturn]] void runRawChild(const std::string& partition, const std::string& security)
{
    dds::BusConfig bc;
    bc.domainId = kDomain;
    bc.partitions = {partition};
    auto bus = dds::Bus::create(secured(bc, security, kWriterIdentity));
    auto writer = (*bus)->writer<dds::msg::ObstacleSectors>();
    dds::msg::ObstacleSectors sample;
    const service::BusFrame frame = sampleFrame();
    dds::toDds(frame.message.sectors, {}, "bench", 0, 0, sample);
    for (;;) {
        ::usleep(10000);
        sample.publish_stamp_ns(dds::realtimeNowNs());
        writer->write(sample);
    }
}

void measure(benchmark::State& state, bool raw, bool secure)
{
    // One secured team per run (the files name the partition); the open variants each have their own.
    const std::string partition = "bench-" + std::to_string(::getpid()) +
                                  (secure ? std::string("-secured")
                                   : raw  ? std::string("-raw")
                                          : std::string("-bridge"));
    const std::string security = secure ? securityFolder(partition) : std::string();
    if (secure && security.empty()) {
        state.SkipWithError("bringup/deploy/security/make_security.sh failed (openssl missing?)");
        return;
    }
    // A fresh process (fork + exec of this program): a forked copy of a process that already ran Fast DDS inherits
    // its factory without its threads and hangs.
    const pid_t child = ::fork();
    if (child == 0) {
        ::execl("/proc/self/exe", "bench-dds", raw ? "--child-raw" : "--child-bridge", partition.c_str(),
                security.c_str(), nullptr);
        ::_exit(127);
    }
    dds::BusConfig bc;
    bc.domainId = kDomain;
    bc.partitions = {partition};
    auto bus = dds::Bus::create(secured(bc, security, kReaderIdentity));
    auto reader = (*bus)->reader<dds::msg::ObstacleSectors>();
    dds::msg::ObstacleSectors s;
    // The bridge's publish stamp is the hand-over's monotonic time on the bus's real-time clock.
    std::vector<double> us;
    while (reader->matched() == 0) {
        ::usleep(1000);
    }
    for (int warm = 0; warm < 20;) { // discovery, first-touch
        if (reader->wait(std::chrono::milliseconds(100)) && reader->take(s)) {
            ++warm;
        }
    }
    for (auto _ : state) {
        while (!(reader->wait(std::chrono::milliseconds(100)) && reader->take(s))) {
        }
        const double latencyS = static_cast<double>(dds::realtimeNowNs() - s.publish_stamp_ns()) * 1e-9;
        state.SetIterationTime(latencyS);
        us.push_back(latencyS * 1e6);
    }
    ::kill(child, SIGKILL);
    ::waitpid(child, nullptr, 0);
    std::sort(us.begin(), us.end());
    const auto at = [&us](double p) { return us[std::min(us.size() - 1, static_cast<std::size_t>(p * us.size()))]; };
    state.counters["p50_us"] = at(0.50);
    state.counters["p99_us"] = at(0.99);
    state.counters["max_us"] = us.back();
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

} // namespace

int main(int argc, char** argv)
{
    if (argc == 4 && std::string(argv[1]) == "--child-raw") {
        runRawChild(argv[2], argv[3]);
    }
    if (argc == 4 && std::string(argv[1]) == "--child-bridge") {
        runBridgeChild(argv[2], argv[3]);
    }
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    std::error_code ec;
    std::filesystem::remove_all(securityFolderPath(), ec); // the private keys too
    return 0;
}
