#include "ugv/rt/thread_runner.hpp"

#include <sched.h>

#include <algorithm>
#include <cstring>
#include <exception>

#include "ugv/platform/clock.hpp"
#include "ugv/platform/log.hpp"

namespace ugv::rt {
namespace {

constexpr std::size_t kThreadNameMax = 15; // pthread_setname_np limit without the terminator

std::string refusalWarning(const char* what, const std::string& tasks, int error, const char* consequence)
{
    return std::string("could not apply ") + what + " to task(s) " + tasks + ": " + errnoText(error) + "; " +
           consequence + ". Fix: " + schedFixHint(error);
}

void appendName(std::string& list, std::string_view name)
{
    if (!list.empty()) {
        list += ", ";
    }
    list += name;
}

} // namespace

std::string formatReport(const StartReport& report)
{
    std::string text;
    for (const AppliedTask& task : report.tasks) {
        text += std::string(task.spec.name) + ": " + toString(task.spec.policy);
        if (task.spec.policy == SchedPolicy::Fifo) {
            text += " " + std::to_string(task.spec.priority) + (task.schedApplied ? " applied" : " REFUSED");
        }
        text += ", cpu ";
        text += task.spec.cpu < 0 ? std::string("any")
                                  : std::to_string(task.spec.cpu) + (task.affinityApplied ? "" : " REFUSED");
        text += ", stack " + std::to_string(task.spec.stackBytes) + " B, period " +
                std::to_string(task.spec.period.count()) + " ns\n";
    }
    return text;
}

ThreadRunner::ThreadRunner(SysOps ops) noexcept : ops_(ops) {}

ThreadRunner::~ThreadRunner()
{
    stopAll();
}

Result<void, Error> ThreadRunner::addTask(const TaskSpec& spec, TaskBody body, void* context)
{
    const std::string where = "ThreadRunner: task '" + std::string(spec.name) + "'";
    if (createCalled_) {
        return Unexpected(Error{where, "addTask() after createAll()", "add every task before createAll()"});
    }
    if (body == nullptr) {
        return Unexpected(Error{where, "the task body is null", "pass the function the thread runs"});
    }
    if (count_ == kMaxTasks) {
        return Unexpected(Error{where, "more than " + std::to_string(kMaxTasks) + " tasks",
                                "raise kMaxTasks in rt/thread_runner.hpp"});
    }
    for (std::size_t i = 0; i < count_; ++i) {
        if (slots_[i].spec.name == spec.name) {
            return Unexpected(Error{where, "a task of that name is already added", "task names must be unique"});
        }
    }
    if (auto valid = validateTask(spec, onlineCpuCount()); !valid) {
        return valid;
    }
    slots_[count_++] = Slot{this, spec, body, context, {}};
    return {};
}

Result<void, Error> ThreadRunner::createAll()
{
    if (createCalled_) {
        return Unexpected(Error{"ThreadRunner", "createAll() called twice", "create the threads once"});
    }
    if (count_ == 0) {
        return Unexpected(Error{"ThreadRunner", "createAll() with no tasks", "addTask() first"});
    }
    createCalled_ = true;
    std::string fifoRefused;
    std::string cpuRefused;
    int fifoError = 0;
    int cpuError = 0;
    for (std::size_t i = 0; i < count_; ++i) {
        Slot& slot = slots_[i];
        pthread_attr_t attr;
        ::pthread_attr_init(&attr);
        ::pthread_attr_setstacksize(&attr, slot.spec.stackBytes);
        // Start as SCHED_OTHER whatever the creator runs as; SCHED_FIFO is applied afterwards (seam, degrade).
        ::pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
        ::pthread_attr_setschedpolicy(&attr, SCHED_OTHER);
        const sched_param normal{};
        ::pthread_attr_setschedparam(&attr, &normal);
        const int error = ::pthread_create(&slot.thread, &attr, &ThreadRunner::threadMain, &slot);
        ::pthread_attr_destroy(&attr);
        if (error != 0) {
            stopAll();
            return Unexpected(Error{"ThreadRunner: task '" + std::string(slot.spec.name) + "'",
                                    "pthread_create failed: " + errnoText(error),
                                    "check memory and thread limits (ulimit -u, systemd TasksMax=)"});
        }
        ++created_;
        std::array<char, kThreadNameMax + 1> name{};
        const std::size_t length = std::min(slot.spec.name.size(), kThreadNameMax);
        std::memcpy(name.data(), slot.spec.name.data(), length);
        static_cast<void>(::pthread_setname_np(slot.thread, name.data())); // cosmetic (ps, top, gdb)
        applySettings(slot, fifoRefused, fifoError, cpuRefused, cpuError);
    }
    if (!fifoRefused.empty()) {
        report_.warnings.push_back(
            refusalWarning("SCHED_FIFO", fifoRefused, fifoError, "they run as SCHED_OTHER (no real-time guarantee)"));
    }
    if (!cpuRefused.empty()) {
        report_.warnings.push_back(refusalWarning("CPU affinity", cpuRefused, cpuError, "they may run on any CPU"));
    }
    for (const std::string& warning : report_.warnings) {
        UGV_LOG(Rt, Warn) << warning;
    }
    return {};
}

void ThreadRunner::applySettings(Slot& slot, std::string& fifoRefused, int& fifoError, std::string& cpuRefused,
                                 int& cpuError)
{
    AppliedTask applied{slot.spec, true, true};
    if (slot.spec.policy == SchedPolicy::Fifo) {
        sched_param param{};
        param.sched_priority = slot.spec.priority;
        const int error = ops_.setSchedParam(slot.thread, SCHED_FIFO, &param);
        if (error != 0) {
            applied.schedApplied = false;
            appendName(fifoRefused, slot.spec.name);
            fifoError = fifoError == 0 ? error : fifoError;
        }
    }
    if (slot.spec.cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(static_cast<std::size_t>(slot.spec.cpu), &set);
        const int error = ops_.setAffinity(slot.thread, sizeof(set), &set);
        if (error != 0) {
            applied.affinityApplied = false;
            appendName(cpuRefused, slot.spec.name);
            cpuError = cpuError == 0 ? error : cpuError;
        }
    }
    static_cast<void>(report_.tasks.push_back(applied)); // capacity kMaxTasks == slots_.size()
}

void ThreadRunner::startAll() noexcept
{
    if (created_ == 0 || stopRequested_.load()) {
        return;
    }
    startGate_.store(true, std::memory_order_release);
    startGate_.notify_all();
}

void ThreadRunner::stopAll() noexcept
{
    stopRequested_.store(true, std::memory_order_release);
    startGate_.store(true, std::memory_order_release);
    startGate_.notify_all();
    for (std::size_t i = 0; i < created_; ++i) {
        ::pthread_join(slots_[i].thread, nullptr);
    }
    created_ = 0;
}

void* ThreadRunner::threadMain(void* slotPtr) noexcept
{
    const Slot& slot = *static_cast<const Slot*>(slotPtr);
    ThreadRunner& owner = *slot.owner;
    owner.startGate_.wait(false, std::memory_order_acquire);
    const auto index = static_cast<std::size_t>(&slot - owner.slots_.data());
    std::chrono::milliseconds wait = owner.restartPolicy_.firstBackoff;
    for (int restarts = 0; !owner.stopRequested_.load(std::memory_order_acquire); ++restarts) {
        if (owner.runGuarded(slot)) {
            break; // the body returned: it saw the stop flag (or had nothing more to do)
        }
        owner.failures_[index].fetch_add(1, std::memory_order_relaxed);
        if (restarts >= owner.restartPolicy_.maxRestarts) {
            UGV_LOG(Rt, Error) << "task '" << slot.spec.name << "' disabled after " << restarts + 1
                               << " failures; the other tasks go on. Fix: see the errors above, then restart the "
                                  "service";
            owner.disabled_[index].store(true, std::memory_order_release);
            break;
        }
        UGV_LOG(Rt, Warn) << "task '" << slot.spec.name << "' restarts in " << wait.count() << " ms (restart "
                          << restarts + 1 << " of " << owner.restartPolicy_.maxRestarts << ")";
        owner.backoff(wait);
        wait = std::min(wait * 2, owner.restartPolicy_.maxBackoff);
    }
    return nullptr;
}

// No task is ever cancelled (stopAll() sets a flag), so catch (...) never swallows a pthread_cancel unwind.
bool ThreadRunner::runGuarded(const Slot& slot) noexcept
{
    try {
        slot.body(slot.context, stopRequested_);
        return true;
    } catch (const std::exception& e) {
        UGV_LOG(Rt, Error) << "task '" << slot.spec.name << "' threw: " << e.what();
    } catch (...) {
        UGV_LOG(Rt, Error) << "task '" << slot.spec.name << "' threw an exception not derived from std::exception";
    }
    return false;
}

void ThreadRunner::backoff(std::chrono::milliseconds d) const noexcept
{
    constexpr std::chrono::milliseconds kSlice{10}; // how soon stopAll() ends a back-off
    const std::chrono::nanoseconds end = MonotonicClock::now() + d;
    while (!stopRequested_.load(std::memory_order_acquire) && MonotonicClock::now() < end) {
        const timespec slice{0, std::chrono::nanoseconds(kSlice).count()};
        static_cast<void>(::clock_nanosleep(CLOCK_MONOTONIC, 0, &slice, nullptr)); // EINTR: the loop re-checks
    }
}

} // namespace ugv::rt
