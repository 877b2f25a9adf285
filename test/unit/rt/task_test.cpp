#include "ugv/rt/task.hpp"

#include <pthread.h>

#include <array>
#include <string>

#include <gtest/gtest.h>

namespace {

using namespace std::chrono_literals;
using ugv::rt::SchedPolicy;
using ugv::rt::TaskSpec;

constexpr int kCpus = 4;
constexpr TaskSpec kGoodFifo{"cam", SchedPolicy::Fifo, 50, 1, 10ms, ugv::rt::kDefaultStackBytes};

std::string validateMessage(const TaskSpec& spec)
{
    const auto result = ugv::rt::validateTask(spec, kCpus);
    return result.has_value() ? std::string("ok") : result.error().message();
}

TEST(TaskTable, DefaultTableIsValidOnThisMachine)
{
    const auto result = ugv::rt::validateTaskTable(ugv::rt::kDefaultTaskTable);
    EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().message());
}

TEST(TaskTable, DefaultTableOrdersPriorities)
{
    static_assert(ugv::rt::findTask(ugv::rt::kDefaultTaskTable, "capture")->priority == 80);
    const auto capture = ugv::rt::findTask(ugv::rt::kDefaultTaskTable, "capture");
    const auto vision = ugv::rt::findTask(ugv::rt::kDefaultTaskTable, "vision");
    const auto publish = ugv::rt::findTask(ugv::rt::kDefaultTaskTable, "publish");
    const auto logger = ugv::rt::findTask(ugv::rt::kDefaultTaskTable, "logger");
    ASSERT_TRUE(capture && vision && publish && logger);
    EXPECT_GT(capture->priority, publish->priority);
    // A finished result leaves when it is made: publish preempts the next frame's detection (issue 22 item 3).
    EXPECT_GT(publish->priority, vision->priority);
    EXPECT_EQ(logger->policy, SchedPolicy::Other);
    EXPECT_EQ(capture->period, std::chrono::nanoseconds(33'333'333));
}

TEST(TaskTable, FindTaskMissesUnknownNameAndEmptyTable)
{
    EXPECT_FALSE(ugv::rt::findTask(ugv::rt::kDefaultTaskTable, "radar").has_value());
    EXPECT_FALSE(ugv::rt::findTask({}, "capture").has_value());
}

TEST(TaskTable, PolicyNames)
{
    EXPECT_STREQ(ugv::rt::toString(SchedPolicy::Fifo), "SCHED_FIFO");
    EXPECT_STREQ(ugv::rt::toString(SchedPolicy::Other), "SCHED_OTHER");
}

TEST(TaskTable, OnlineCpuCountIsPositive)
{
    EXPECT_GE(ugv::rt::onlineCpuCount(), 1);
}

TEST(ValidateTask, AcceptsBoundaries)
{
    auto spec = kGoodFifo;
    spec.priority = 1;
    EXPECT_EQ(validateMessage(spec), "ok");
    spec.priority = 99;
    spec.cpu = kCpus - 1;
    EXPECT_EQ(validateMessage(spec), "ok");
    spec.cpu = -1;
    spec.period = 0ns;
    spec.stackBytes = PTHREAD_STACK_MIN;
    EXPECT_EQ(validateMessage(spec), "ok");
}

TEST(ValidateTask, FifoPriorityOutOfRangeNamesTaskFieldValueAndRange)
{
    auto spec = kGoodFifo;
    spec.priority = 100;
    EXPECT_EQ(validateMessage(spec),
              "task table: task 'cam': field 'priority' = 100 is outside the allowed range 1..99 for SCHED_FIFO "
              "(fix: fix the task table (rt/task.hpp) or the config override)");
    spec.priority = 0;
    EXPECT_NE(validateMessage(spec).find("'priority' = 0 is outside the allowed range 1..99"), std::string::npos);
}

TEST(ValidateTask, OtherPolicyNeedsPriorityZero)
{
    auto spec = kGoodFifo;
    spec.policy = SchedPolicy::Other;
    EXPECT_NE(validateMessage(spec).find("'priority' = 50 is outside the allowed range 0 for SCHED_OTHER"),
              std::string::npos);
}

TEST(ValidateTask, CpuOutOfRange)
{
    auto spec = kGoodFifo;
    spec.cpu = kCpus;
    EXPECT_NE(validateMessage(spec).find("'cpu' = 4 is outside the allowed range -1 (any) or 0..3"), std::string::npos);
    spec.cpu = -2;
    EXPECT_NE(validateMessage(spec).find("'cpu' = -2"), std::string::npos);
}

TEST(ValidateTask, NegativePeriod)
{
    auto spec = kGoodFifo;
    spec.period = -1ns;
    EXPECT_NE(validateMessage(spec).find("'period' = -1 ns is outside the allowed range >= 0 ns"), std::string::npos);
}

TEST(ValidateTask, StackBelowMinimum)
{
    auto spec = kGoodFifo;
    spec.stackBytes = PTHREAD_STACK_MIN - 1;
    EXPECT_NE(validateMessage(spec).find("'stackBytes' = " + std::to_string(PTHREAD_STACK_MIN - 1)), std::string::npos);
}

TEST(ValidateTask, EmptyName)
{
    auto spec = kGoodFifo;
    spec.name = "";
    EXPECT_NE(validateMessage(spec).find("empty name"), std::string::npos);
}

TEST(ValidateTaskTable, DuplicateNamesAreRejected)
{
    // The middle row is valid on every target: PTHREAD_STACK_MIN is 16 KiB on x86-64 but 128 KiB on aarch64.
    const std::array<TaskSpec, 3> table{
        kGoodFifo, {"other", SchedPolicy::Other, 0, -1, 0ns, ugv::rt::kDefaultStackBytes}, kGoodFifo};
    const auto result = ugv::rt::validateTaskTable(table, kCpus);
    ASSERT_FALSE(result.has_value());
    EXPECT_EQ(result.error().where, "task table: task 'cam'");
    EXPECT_NE(result.error().what.find("rows 0 and 2"), std::string::npos);
}

TEST(ValidateTaskTable, FirstBadRowIsReportedAndEmptyTableIsValid)
{
    auto bad = kGoodFifo;
    bad.name = "bad";
    bad.cpu = kCpus;
    const std::array<TaskSpec, 2> table{kGoodFifo, bad};
    const auto result = ugv::rt::validateTaskTable(table, kCpus);
    ASSERT_FALSE(result.has_value());
    EXPECT_EQ(result.error().where, "task table: task 'bad'");
    EXPECT_TRUE(ugv::rt::validateTaskTable({}, kCpus).has_value());
}

} // namespace
