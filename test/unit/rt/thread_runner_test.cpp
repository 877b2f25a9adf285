#include "ugv/rt/thread_runner.hpp"

#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "captured_log.hpp"

namespace {

using namespace std::chrono_literals;
using ugv::rt::SchedPolicy;
using ugv::rt::TaskSpec;
using ugv::rt::ThreadRunner;

constexpr std::size_t kStack = 128UL * 1024UL;
constexpr TaskSpec kFifoA{"fifo-a", SchedPolicy::Fifo, 10, -1, 0ns, kStack};
constexpr TaskSpec kFifoB{"fifo-b", SchedPolicy::Fifo, 11, 0, 0ns, kStack};
constexpr TaskSpec kOther{"other", SchedPolicy::Other, 0, 0, 0ns, kStack};

std::atomic<int> gSchedCalls{0};
std::atomic<int> gAffinityCalls{0};

int refuseSched(pthread_t /*thread*/, int /*policy*/, const sched_param* /*param*/)
{
    ++gSchedCalls;
    return EPERM;
}
int refuseAffinity(pthread_t /*thread*/, std::size_t /*size*/, const cpu_set_t* /*set*/)
{
    ++gAffinityCalls;
    return EPERM;
}
int acceptSched(pthread_t /*thread*/, int /*policy*/, const sched_param* /*param*/)
{
    ++gSchedCalls;
    return 0;
}
int acceptAffinity(pthread_t /*thread*/, std::size_t /*size*/, const cpu_set_t* /*set*/)
{
    ++gAffinityCalls;
    return 0;
}

ugv::rt::SysOps fakeOps(bool schedOk, bool affinityOk)
{
    auto ops = ugv::rt::realSysOps();
    ops.setSchedParam = schedOk ? &acceptSched : &refuseSched;
    ops.setAffinity = affinityOk ? &acceptAffinity : &refuseAffinity;
    return ops;
}

/// Counts its runs and loops until stopped; records the policy it ran with.
struct Probe {
    std::atomic<int> runs{0};
    std::atomic<int> policy{-1};
    std::atomic<int> priority{-1};
};

void probeBody(void* context, const std::atomic<bool>& stopRequested)
{
    auto& probe = *static_cast<Probe*>(context);
    int policy = 0;
    sched_param param{};
    ::pthread_getschedparam(::pthread_self(), &policy, &param);
    probe.policy = policy;
    probe.priority = param.sched_priority;
    ++probe.runs;
    while (!stopRequested.load(std::memory_order_acquire)) {
        std::this_thread::sleep_for(1ms);
    }
}

void resetCalls()
{
    gSchedCalls = 0;
    gAffinityCalls = 0;
}

TEST(ThreadRunner, NoBodyRunsBeforeStartAllThenAllRun)
{
    resetCalls();
    Probe a;
    Probe b;
    ThreadRunner sut(fakeOps(true, true));
    ASSERT_TRUE(sut.addTask(kFifoA, &probeBody, &a).has_value());
    ASSERT_TRUE(sut.addTask(kOther, &probeBody, &b).has_value());
    ASSERT_TRUE(sut.createAll().has_value());
    std::this_thread::sleep_for(20ms);
    EXPECT_EQ(a.runs + b.runs, 0);

    sut.startAll();
    for (int i = 0; i < 1000 && a.runs + b.runs < 2; ++i) {
        std::this_thread::sleep_for(1ms);
    }
    sut.stopAll();

    EXPECT_EQ(a.runs, 1);
    EXPECT_EQ(b.runs, 1);
    EXPECT_EQ(sut.taskCount(), 2U);
    EXPECT_EQ(gSchedCalls, 1);    // only the FIFO task
    EXPECT_EQ(gAffinityCalls, 1); // only the pinned task
    EXPECT_EQ(b.policy, SCHED_OTHER);
    EXPECT_TRUE(sut.report().warnings.empty());
    ASSERT_EQ(sut.report().tasks.size(), 2U);
    EXPECT_TRUE(sut.report().tasks[0].schedApplied);
    EXPECT_TRUE(sut.report().tasks[1].affinityApplied);
}

TEST(ThreadRunner, StopBeforeStartSkipsBodies)
{
    Probe a;
    ThreadRunner sut(fakeOps(true, true));
    ASSERT_TRUE(sut.addTask(kOther, &probeBody, &a).has_value());
    ASSERT_TRUE(sut.createAll().has_value());
    sut.stopAll();
    sut.startAll(); // after stop: nothing
    sut.stopAll();  // idempotent
    EXPECT_EQ(a.runs, 0);
}

TEST(ThreadRunner, RefusedFifoAndAffinityDegradeToOneWarningEach)
{
    resetCalls();
    Probe a;
    Probe b;
    Probe c;
    ThreadRunner sut(fakeOps(false, false));
    ASSERT_TRUE(sut.addTask(kFifoA, &probeBody, &a).has_value());
    ASSERT_TRUE(sut.addTask(kFifoB, &probeBody, &b).has_value());
    ASSERT_TRUE(sut.addTask(kOther, &probeBody, &c).has_value());

    ASSERT_TRUE(sut.createAll().has_value());
    sut.startAll();
    for (int i = 0; i < 1000 && a.runs + b.runs + c.runs < 3; ++i) {
        std::this_thread::sleep_for(1ms);
    }
    sut.stopAll();

    EXPECT_EQ(a.runs + b.runs + c.runs, 3); // kept running with defaults
    EXPECT_EQ(gSchedCalls, 2);
    EXPECT_EQ(gAffinityCalls, 2);
    const auto& report = sut.report();
    ASSERT_EQ(report.warnings.size(), 2U);
    EXPECT_EQ(report.warnings[0],
              "could not apply SCHED_FIFO to task(s) fifo-a, fifo-b: Operation not permitted (EPERM); they run as "
              "SCHED_OTHER (no real-time guarantee). Fix: run as root or grant CAP_SYS_NICE (systemd: "
              "AmbientCapabilities=CAP_SYS_NICE, LimitRTPRIO=99)");
    EXPECT_NE(report.warnings[1].find("could not apply CPU affinity to task(s) fifo-b, other: Operation not "
                                      "permitted"),
              std::string::npos)
        << report.warnings[1];
    ASSERT_EQ(report.tasks.size(), 3U);
    EXPECT_FALSE(report.tasks[0].schedApplied);
    EXPECT_TRUE(report.tasks[0].affinityApplied); // cpu -1: nothing to apply
    EXPECT_FALSE(report.tasks[1].affinityApplied);
    EXPECT_EQ(a.policy, SCHED_OTHER);
    const std::string text = ugv::rt::formatReport(report);
    EXPECT_NE(text.find("fifo-a: SCHED_FIFO 10 REFUSED, cpu any, stack 131072 B, period 0 ns\n"), std::string::npos)
        << text;
    EXPECT_NE(text.find("other: SCHED_OTHER, cpu 0 REFUSED"), std::string::npos) << text;
}

TEST(ThreadRunner, OtherErrnoGetsAGenericHint)
{
    EXPECT_NE(std::string(ugv::rt::schedFixHint(EINVAL)).find("check the task table"), std::string::npos);
    EXPECT_EQ(ugv::rt::errnoText(EINVAL), "Invalid argument (EINVAL)");
    EXPECT_NE(ugv::rt::errnoText(100000).find("unknown error"), std::string::npos);
}

TEST(ThreadRunner, RealSchedulingAppliesOrDegradesButAlwaysRuns)
{
    Probe a;
    ThreadRunner sut; // real OS calls: root here grants SCHED_FIFO; CI without CAP_SYS_NICE degrades
    ASSERT_TRUE(sut.addTask(kFifoB, &probeBody, &a).has_value());
    ASSERT_TRUE(sut.createAll().has_value());
    sut.startAll();
    for (int i = 0; i < 1000 && a.runs < 1; ++i) {
        std::this_thread::sleep_for(1ms);
    }
    sut.stopAll();
    ASSERT_EQ(a.runs, 1);
    ASSERT_EQ(sut.report().tasks.size(), 1U);
    if (sut.report().tasks[0].schedApplied) {
        EXPECT_EQ(a.policy, SCHED_FIFO);
        EXPECT_EQ(a.priority, kFifoB.priority);
        EXPECT_TRUE(sut.report().warnings.empty());
    } else {
        EXPECT_EQ(a.policy, SCHED_OTHER);
        ASSERT_FALSE(sut.report().warnings.empty());
        EXPECT_NE(sut.report().warnings[0].find("SCHED_FIFO"), std::string::npos);
    }
}

TEST(ThreadRunner, AddTaskRejectsBadInput)
{
    Probe probe;
    ThreadRunner sut(fakeOps(true, true));
    auto bad = kFifoA;
    bad.priority = 0;
    EXPECT_FALSE(sut.addTask(bad, &probeBody, &probe).has_value());
    const auto nullBody = sut.addTask(kFifoA, nullptr, &probe);
    ASSERT_FALSE(nullBody.has_value());
    EXPECT_NE(nullBody.error().what.find("null"), std::string::npos);
    ASSERT_TRUE(sut.addTask(kFifoA, &probeBody, &probe).has_value());
    const auto duplicate = sut.addTask(kFifoA, &probeBody, &probe);
    ASSERT_FALSE(duplicate.has_value());
    EXPECT_NE(duplicate.error().what.find("already added"), std::string::npos);
    EXPECT_EQ(sut.taskCount(), 1U);
}

TEST(ThreadRunner, AddTaskRejectsMoreThanMaxTasks)
{
    static const std::array<std::string, ugv::rt::kMaxTasks + 1> kNames{"t0", "t1", "t2", "t3", "t4",
                                                                        "t5", "t6", "t7", "t8"};
    Probe probe;
    ThreadRunner sut(fakeOps(true, true));
    for (std::size_t i = 0; i < ugv::rt::kMaxTasks; ++i) {
        ASSERT_TRUE(sut.addTask({kNames[i], SchedPolicy::Other, 0, -1, 0ns, kStack}, &probeBody, &probe));
    }
    const auto result = sut.addTask({kNames.back(), SchedPolicy::Other, 0, -1, 0ns, kStack}, &probeBody, &probe);
    ASSERT_FALSE(result.has_value());
    EXPECT_NE(result.error().what.find("more than 8 tasks"), std::string::npos);
}

TEST(ThreadRunner, CreateAllErrorsAndAddAfterCreate)
{
    Probe probe;
    ThreadRunner sut(fakeOps(true, true));
    const auto empty = sut.createAll();
    ASSERT_FALSE(empty.has_value());
    EXPECT_NE(empty.error().what.find("no tasks"), std::string::npos);

    ASSERT_TRUE(sut.addTask(kOther, &probeBody, &probe).has_value());
    ASSERT_TRUE(sut.createAll().has_value());
    EXPECT_FALSE(sut.createAll().has_value());
    const auto late = sut.addTask(kFifoA, &probeBody, &probe);
    ASSERT_FALSE(late.has_value());
    EXPECT_NE(late.error().what.find("after createAll"), std::string::npos);
}

TEST(ThreadRunner, ThreadCreationFailureIsReportedAndEarlierThreadsStopped)
{
    Probe a;
    Probe b;
    ThreadRunner sut(fakeOps(true, true));
    ASSERT_TRUE(sut.addTask(kOther, &probeBody, &a).has_value());
    auto huge = kFifoA;
    huge.stackBytes = std::size_t{1} << 60; // no address space for this stack: pthread_create fails
    ASSERT_TRUE(sut.addTask(huge, &probeBody, &b).has_value());

    const auto result = sut.createAll();

    ASSERT_FALSE(result.has_value());
    EXPECT_EQ(result.error().where, "ThreadRunner: task 'fifo-a'");
    EXPECT_NE(result.error().what.find("pthread_create failed"), std::string::npos);
    sut.startAll(); // no effect: everything was stopped
    EXPECT_EQ(a.runs + b.runs, 0);
}

} // namespace

namespace guard {

/// Throws on its first `throwsLeft` runs, then loops until stopped.
struct Thrower {
    std::atomic<int> runs{0};
    std::atomic<int> throwsLeft{0};
};

void throwerBody(void* context, const std::atomic<bool>& stopRequested)
{
    auto& thrower = *static_cast<Thrower*>(context);
    ++thrower.runs;
    if (thrower.throwsLeft.fetch_sub(1) > 0) {
        throw std::runtime_error("injected failure");
    }
    while (!stopRequested.load(std::memory_order_acquire)) {
        std::this_thread::sleep_for(1ms);
    }
}

/// Counts loop iterations until stopped: proves a task runs on while its peer fails.
void tickerBody(void* context, const std::atomic<bool>& stopRequested)
{
    auto& ticks = *static_cast<std::atomic<int>*>(context);
    while (!stopRequested.load(std::memory_order_acquire)) {
        ++ticks;
        std::this_thread::sleep_for(1ms);
    }
}

constexpr TaskSpec kFaulty{"faulty", SchedPolicy::Other, 0, -1, 0ns, kStack};
constexpr TaskSpec kTicker{"ticker", SchedPolicy::Other, 0, -1, 0ns, kStack};
constexpr ugv::rt::RestartPolicy kFastRestart{2, 1ms, 4ms};

template <typename Predicate>
bool eventually(Predicate predicate)
{
    for (int i = 0; i < 5000 && !predicate(); ++i) { // 5 s at most: a sanity bound, not a timing assertion
        std::this_thread::sleep_for(1ms);
    }
    return predicate();
}

} // namespace guard

/// A faulty task (throws its first `throws` runs) beside a ticker, with a restart policy of milliseconds.
class ThreadRunnerGuard : public ::testing::Test {
protected:
    void startFaultyAndTicker(int throws)
    {
        thrower_.throwsLeft = throws;
        sut_.setRestartPolicy(guard::kFastRestart);
        ASSERT_TRUE(sut_.addTask(guard::kFaulty, &guard::throwerBody, &thrower_));
        ASSERT_TRUE(sut_.addTask(guard::kTicker, &guard::tickerBody, &ticks_));
        ASSERT_TRUE(sut_.createAll());
        sut_.startAll();
    }
    /// True once the ticker has ticked again: the peer of the faulty task runs on.
    bool tickerRunsOn()
    {
        const int before = ticks_.load();
        return guard::eventually([&] { return ticks_.load() > before; });
    }

    ugv::test::CapturedLog log_;
    guard::Thrower thrower_;
    std::atomic<int> ticks_{0};
    ThreadRunner sut_{fakeOps(true, true)};
};

TEST_F(ThreadRunnerGuard, ThrowingBodyIsLoggedAndRestartedWhileThePeerRunsOn)
{
    startFaultyAndTicker(1);

    ASSERT_TRUE(guard::eventually([&] { return thrower_.runs.load() == 2; }));
    ASSERT_TRUE(tickerRunsOn());
    sut_.stopAll();

    EXPECT_EQ(sut_.failureCount(0), 1U);
    EXPECT_FALSE(sut_.disabled(0));
    EXPECT_EQ(sut_.failureCount(1), 0U);
    const std::string text = log_.text();
    EXPECT_NE(text.find("task 'faulty' threw: injected failure"), std::string::npos) << text;
    EXPECT_NE(text.find("task 'faulty' restarts in 1 ms"), std::string::npos) << text;
}

TEST_F(ThreadRunnerGuard, BodyThatAlwaysThrowsIsDisabledAfterMaxRestartsAndThePeerRunsOn)
{
    startFaultyAndTicker(1000);

    ASSERT_TRUE(guard::eventually([&] { return sut_.disabled(0); }));
    ASSERT_TRUE(tickerRunsOn());
    sut_.stopAll();

    constexpr int kExpectedRuns = 1 + guard::kFastRestart.maxRestarts;
    EXPECT_EQ(thrower_.runs.load(), kExpectedRuns);
    EXPECT_EQ(sut_.failureCount(0), static_cast<std::uint32_t>(kExpectedRuns));
    EXPECT_NE(log_.text().find("task 'faulty' disabled after 3 failures"), std::string::npos) << log_.text();
}

TEST_F(ThreadRunnerGuard, StopEndsABackoffEarly)
{
    thrower_.throwsLeft = 1;
    sut_.setRestartPolicy(ugv::rt::RestartPolicy{1, std::chrono::hours(1), std::chrono::hours(1)});
    ASSERT_TRUE(sut_.addTask(guard::kFaulty, &guard::throwerBody, &thrower_));
    ASSERT_TRUE(sut_.createAll());
    sut_.startAll();
    ASSERT_TRUE(guard::eventually([&] { return sut_.failureCount(0) == 1U; }));

    sut_.stopAll(); // would hang for an hour if the back-off ignored the stop flag (ctest timeout fails it)

    EXPECT_EQ(thrower_.runs.load(), 1);
}
