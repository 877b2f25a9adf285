#pragma once

/// @file
/// `ugv::rt::ThreadRunner`: creates one pthread per task (stack size, SCHED_FIFO priority, CPU affinity from its
/// TaskSpec), holds every thread at a start gate until startAll(), and stops them with a flag and a join.
///
/// Life cycle (one-shot): addTask()* -> createAll() -> startAll() -> stopAll(). No task body runs before every
/// thread exists, so tasks may assume that their peers are ready.
///
/// When the OS refuses SCHED_FIFO or the affinity (EPERM without CAP_SYS_NICE), the runner keeps the thread
/// with the default (SCHED_OTHER, any CPU) and adds ONE warning per refused setting to the report (and to the
/// log), naming the tasks, the errno text and the fix. The report says what was applied to each task.
///
/// Exception guard: a body that throws (our code never throws, but Fast DDS, OpenCV and std::bad_alloc can) is
/// caught in its thread instead of ending the process (std::terminate). The runner logs the task's name and the
/// exception's what(), waits a back-off (doubling from RestartPolicy::firstBackoff) while polling the stop flag,
/// and runs the body again; after RestartPolicy::maxRestarts restarts it disables the task (logged once). Why
/// restart then disable: a transient failure (one bad_alloc, a DDS hiccup) recovers without the operator, while a
/// task that fails every time stops spending CPU and log lines; the other tasks run on either way. The guard costs
/// nothing on the path that does not throw (table-based unwinding: no allocation, no lock); the catch branch
/// allocates and writes a log line, which is acceptable only because the task has already failed.
///
/// Thread-safety: thread-compatible: one owner thread calls all member functions, except failureCount() and
/// disabled(), which any thread may call. RT-safe: no (init/stop only); the task bodies get a stop flag they may
/// poll RT-safely.

#include <pthread.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "ugv/platform/error.hpp"
#include "ugv/platform/fixed_vector.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/rt/sys_ops.hpp"
#include "ugv/rt/task.hpp"

namespace ugv::rt {

inline constexpr std::size_t kMaxTasks = 8;

/// A task body: runs until `stopRequested` becomes true (poll it with memory_order_relaxed or acquire).
/// A plain function pointer and a context pointer: nothing allocates when the task starts.
using TaskBody = void (*)(void* context, const std::atomic<bool>& stopRequested);

/// What createAll() applied to one task.
struct AppliedTask {
    TaskSpec spec;                ///< what was requested
    bool schedApplied = false;    ///< SCHED_FIFO + priority in effect (always true for SCHED_OTHER tasks)
    bool affinityApplied = false; ///< pinned to spec.cpu (true when spec.cpu == -1: nothing to apply)
};

/// What the exception guard does when a task body throws (see the file comment).
struct RestartPolicy {
    int maxRestarts = 5;                          ///< restarts before the task is disabled
    std::chrono::milliseconds firstBackoff{100};  ///< wait before the first restart, doubled each time
    std::chrono::milliseconds maxBackoff{10'000}; ///< cap of the doubled wait
};

struct StartReport {
    FixedVector<AppliedTask, kMaxTasks> tasks;
    std::vector<std::string> warnings; ///< at most one per refused setting (SCHED_FIFO, affinity)
};

/// One line per task, e.g. "capture: SCHED_FIFO 80 applied, cpu any, stack 262144 B, period 33333333 ns".
/// Thread-safety: reentrant. RT-safe: no.
[[nodiscard]] std::string formatReport(const StartReport& report);

class ThreadRunner {
public:
    /// @param[in] ops the OS calls used for scheduling and affinity (tests inject failures).
    explicit ThreadRunner(SysOps ops = realSysOps()) noexcept;
    ~ThreadRunner(); ///< stopAll()
    ThreadRunner(const ThreadRunner&) = delete;
    ThreadRunner& operator=(const ThreadRunner&) = delete;
    ThreadRunner(ThreadRunner&&) = delete;
    ThreadRunner& operator=(ThreadRunner&&) = delete;

    /// @brief Set what the exception guard does; call before createAll().
    void setRestartPolicy(const RestartPolicy& policy) noexcept { restartPolicy_ = policy; }

    /// @brief Register a task; `context` must outlive the runner.
    /// @return an error for an invalid spec (validateTask), a duplicate name, a null body, more than
    /// kMaxTasks tasks, or a call after createAll().
    [[nodiscard]] Result<void, Error> addTask(const TaskSpec& spec, TaskBody body, void* context);

    /// @brief Create every thread (each waits at the start gate) and apply its settings, degrading with
    /// warnings where the OS refuses. On a pthread_create failure the threads made so far are stopped.
    /// @return an error when called twice, with no tasks, or when a thread cannot be created.
    [[nodiscard]] Result<void, Error> createAll();

    /// @brief Open the start gate: all task bodies begin. Does nothing before createAll() or after stopAll().
    void startAll() noexcept;

    /// @brief Set the stop flag only (the bodies see it at their next look); the owner can then wake bodies that
    /// wait on something of its own before stopAll() joins them. Any thread.
    void requestStop() noexcept { stopRequested_.store(true, std::memory_order_release); }

    /// @brief Set the stop flag, open the gate (bodies not yet started are skipped) and join every thread.
    /// Idempotent.
    void stopAll() noexcept;

    [[nodiscard]] const StartReport& report() const noexcept { return report_; }
    [[nodiscard]] std::size_t taskCount() const noexcept { return count_; }

    /// @brief How many times the body of task `index` (order of addTask) threw. Thread-safety: any thread.
    [[nodiscard]] std::uint32_t failureCount(std::size_t index) const noexcept
    {
        return index < kMaxTasks ? failures_[index].load(std::memory_order_relaxed) : 0U;
    }
    /// @brief True once task `index` threw more than RestartPolicy::maxRestarts times and no longer runs.
    /// Thread-safety: any thread.
    [[nodiscard]] bool disabled(std::size_t index) const noexcept
    {
        return index < kMaxTasks && disabled_[index].load(std::memory_order_acquire);
    }

private:
    struct Slot {
        ThreadRunner* owner = nullptr;
        TaskSpec spec;
        TaskBody body = nullptr;
        void* context = nullptr;
        pthread_t thread{};
    };
    static void* threadMain(void* slot) noexcept;
    /// Runs the body once; false when it threw (logged). Defined in the .cpp next to threadMain.
    bool runGuarded(const Slot& slot) noexcept;
    /// Sleeps `d` in short slices; returns early when stop is requested.
    void backoff(std::chrono::milliseconds d) const noexcept;
    void applySettings(Slot& slot, std::string& fifoRefused, int& fifoError, std::string& cpuRefused, int& cpuError);

    SysOps ops_;
    std::array<Slot, kMaxTasks> slots_{};
    std::size_t count_ = 0;
    std::size_t created_ = 0;
    bool createCalled_ = false;
    std::atomic<bool> startGate_{false};
    std::atomic<bool> stopRequested_{false};
    StartReport report_;
    RestartPolicy restartPolicy_{};
    std::array<std::atomic<std::uint32_t>, kMaxTasks> failures_{};
    std::array<std::atomic<bool>, kMaxTasks> disabled_{};
};

} // namespace ugv::rt
