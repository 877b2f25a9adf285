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
/// Thread-safety: thread-compatible: one owner thread calls all member functions. RT-safe: no (init/stop only);
/// the task bodies get a stop flag they may poll RT-safely.

#include <pthread.h>

#include <array>
#include <atomic>
#include <cstddef>
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

    /// @brief Set the stop flag, open the gate (bodies not yet started are skipped) and join every thread.
    /// Idempotent.
    void stopAll() noexcept;

    [[nodiscard]] const StartReport& report() const noexcept { return report_; }
    [[nodiscard]] std::size_t taskCount() const noexcept { return count_; }

private:
    struct Slot {
        ThreadRunner* owner = nullptr;
        TaskSpec spec;
        TaskBody body = nullptr;
        void* context = nullptr;
        pthread_t thread{};
    };
    static void* threadMain(void* slot) noexcept;
    void applySettings(Slot& slot, std::string& fifoRefused, int& fifoError, std::string& cpuRefused, int& cpuError);

    SysOps ops_;
    std::array<Slot, kMaxTasks> slots_{};
    std::size_t count_ = 0;
    std::size_t created_ = 0;
    bool createCalled_ = false;
    std::atomic<bool> startGate_{false};
    std::atomic<bool> stopRequested_{false};
    StartReport report_;
};

} // namespace ugv::rt
