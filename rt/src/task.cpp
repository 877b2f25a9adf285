#include "ugv/rt/task.hpp"

#include <pthread.h>
#include <unistd.h>

#include <string>

namespace ugv::rt {
namespace {

Error fieldError(const TaskSpec& spec, std::string_view field, const std::string& value, const std::string& range)
{
    return Error{"task table: task '" + std::string(spec.name) + "'",
                 "field '" + std::string(field) + "' = " + value + " is outside the allowed range " + range,
                 "fix the task table (rt/task.hpp) or the config override"};
}

} // namespace

const char* toString(SchedPolicy policy) noexcept
{
    return policy == SchedPolicy::Fifo ? "SCHED_FIFO" : "SCHED_OTHER";
}

int onlineCpuCount() noexcept
{
    return static_cast<int>(::sysconf(_SC_NPROCESSORS_ONLN));
}

Result<void, Error> validateTask(const TaskSpec& spec, int cpuCount)
{
    if (spec.name.empty()) {
        return Unexpected(Error{"task table", "a task has an empty name", "give every task a unique name"});
    }
    if (spec.policy == SchedPolicy::Fifo && (spec.priority < kMinFifoPriority || spec.priority > kMaxFifoPriority)) {
        return Unexpected(fieldError(spec, "priority", std::to_string(spec.priority), "1..99 for SCHED_FIFO"));
    }
    if (spec.policy == SchedPolicy::Other && spec.priority != 0) {
        return Unexpected(fieldError(spec, "priority", std::to_string(spec.priority), "0 for SCHED_OTHER"));
    }
    if (spec.cpu < -1 || spec.cpu >= cpuCount) {
        return Unexpected(fieldError(spec, "cpu", std::to_string(spec.cpu),
                                     "-1 (any) or 0.." + std::to_string(cpuCount - 1) + " on this machine"));
    }
    if (spec.period.count() < 0) {
        return Unexpected(
            fieldError(spec, "period", std::to_string(spec.period.count()) + " ns", ">= 0 ns (0 = event-driven)"));
    }
    const auto minStack = static_cast<std::size_t>(PTHREAD_STACK_MIN);
    if (spec.stackBytes < minStack) {
        return Unexpected(fieldError(spec, "stackBytes", std::to_string(spec.stackBytes),
                                     ">= " + std::to_string(minStack) + " (PTHREAD_STACK_MIN)"));
    }
    return {};
}

Result<void, Error> validateTaskTable(std::span<const TaskSpec> table, int cpuCount)
{
    for (std::size_t i = 0; i < table.size(); ++i) {
        if (auto valid = validateTask(table[i], cpuCount); !valid) {
            return valid;
        }
        for (std::size_t j = 0; j < i; ++j) {
            if (table[j].name == table[i].name) {
                return Unexpected(Error{"task table: task '" + std::string(table[i].name) + "'",
                                        "field 'name' is used by rows " + std::to_string(j) + " and " +
                                            std::to_string(i) + "; names must be unique",
                                        "rename one of them"});
            }
        }
    }
    return {};
}

Result<void, Error> validateTaskTable(std::span<const TaskSpec> table)
{
    return validateTaskTable(table, onlineCpuCount());
}

} // namespace ugv::rt
