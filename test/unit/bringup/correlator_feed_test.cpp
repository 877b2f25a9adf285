// CorrelatorFeed: late messages put in their place (re-sequencing) give the state of the time order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "ugv/adapters/correlate_io.hpp"
#include "ugv/correlator/correlator_feed.hpp"
#include "ugv/correlator/scenario.hpp"

namespace ugv::adapters {
namespace {

using correlator::CorrelatorFeed;
using correlator::Message;

std::vector<Message> scenario()
{
    correlator::ScenarioConfig config = correlator::scenarioPreset(correlator::ScenarioSetting::Bias);
    config.durationS = 300.0;
    config.poseCorrections = true;
    auto s = correlator::generateScenario(config);
    EXPECT_TRUE(s.has_value());
    return s ? s->messages : std::vector<Message>{};
}

double timeOf(const Message& m)
{
    return std::visit([](const auto& x) { return x.t; }, m);
}

bool fromLateUgv(const Message& m, double from, double until)
{
    const auto* o = std::get_if<correlator::Observation>(&m);
    return o != nullptr && o->ugv == "ugv-2" && o->t >= from && o->t < until;
}

/// The messages as a link that was down for [from, until) delivers them: ugv-2's observations of that time come
/// when the first message at or after `deliverAt` does (its history repaired), all at once.
std::vector<std::vector<Message>> arrivals(const std::vector<Message>& sorted, double from, double until,
                                           double deliverAt)
{
    std::vector<std::vector<Message>> out;
    std::vector<Message> held;
    bool delivered = false;
    for (const Message& m : sorted) {
        if (!delivered && timeOf(m) >= deliverAt) {
            out.push_back(held);
            delivered = true;
        }
        if (fromLateUgv(m, from, until)) {
            held.push_back(m);
        } else {
            out.push_back({m});
        }
    }
    return out;
}

struct FeedRun {
    std::vector<std::string> snapshots; ///< given out, as JSON lines
    std::size_t applied = 0;
    std::size_t refused = 0;
};

FeedRun feedAll(CorrelatorFeed& feed, const std::vector<std::vector<Message>>& batches)
{
    FeedRun run;
    const auto give = [&run](const correlator::Snapshot& s) { run.snapshots.push_back(toJsonLine(s)); };
    for (const auto& batch : batches) {
        run.applied += feed.add(batch, give, [&run](const Message&, const Error&) { ++run.refused; });
    }
    feed.finish(give);
    return run;
}

/// The arrival order stably sorted by time: what the feed must equal.
std::vector<std::vector<Message>> timeOrder(const std::vector<std::vector<Message>>& batches)
{
    std::vector<Message> all;
    for (const auto& b : batches) {
        all.insert(all.end(), b.begin(), b.end());
    }
    std::stable_sort(all.begin(), all.end(), [](const Message& a, const Message& b) { return timeOf(a) < timeOf(b); });
    std::vector<std::vector<Message>> out;
    for (const Message& m : all) {
        out.push_back({m});
    }
    return out;
}

TEST(CorrelatorFeed, LateMessagesInTheWindowGiveTheStateOfTheTimeOrder)
{
    const std::vector<Message> sorted = scenario();
    ASSERT_GT(sorted.size(), 1000U);
    const auto late = arrivals(sorted, 100.0, 160.0, 200.0); // up to 100 s late
    std::size_t lateCount = 0;
    for (const Message& m : sorted) {
        lateCount += fromLateUgv(m, 100.0, 160.0) ? 1U : 0U;
    }
    ASSERT_GT(lateCount, 50U);

    CorrelatorFeed reference(correlator::Mode::PoseCorrected, 1.0, 0.0);
    const FeedRun want = feedAll(reference, timeOrder(late));
    CorrelatorFeed feed(correlator::Mode::PoseCorrected, 1.0, 120.0);
    const FeedRun got = feedAll(feed, late);

    EXPECT_EQ(got.refused, want.refused);
    EXPECT_EQ(got.applied, want.applied);
    EXPECT_EQ(feed.applied(), reference.applied());
    EXPECT_EQ(feed.resequenced(), lateCount);
    EXPECT_GT(feed.replayed(), 0U);
    // The boundaries before the delivery were given out once, without the late observations; every one from the
    // delivery on is the time order's, byte for byte (the final snapshot included).
    ASSERT_EQ(got.snapshots.size(), want.snapshots.size());
    std::size_t equalFromDelivery = 0;
    for (std::size_t k = 200; k < want.snapshots.size(); ++k) {
        EXPECT_EQ(got.snapshots[k], want.snapshots[k]) << "snapshot " << k;
        ++equalFromDelivery;
    }
    EXPECT_GT(equalFromDelivery, 90U);
    // ... and the late observations changed something before it (else this test proves nothing).
    std::size_t differentBefore = 0;
    for (std::size_t k = 100; k < 200; ++k) {
        differentBefore += got.snapshots[k] != want.snapshots[k] ? 1U : 0U;
    }
    EXPECT_GT(differentBefore, 0U);
}

TEST(CorrelatorFeed, OneByOneEqualsOneBatch)
{
    const std::vector<Message> sorted = scenario();
    const auto batches = arrivals(sorted, 100.0, 160.0, 200.0);
    std::vector<std::vector<Message>> single;
    for (const auto& b : batches) {
        for (const Message& m : b) {
            single.push_back({m});
        }
    }
    CorrelatorFeed a(correlator::Mode::PoseCorrected, 1.0, 120.0);
    CorrelatorFeed b(correlator::Mode::PoseCorrected, 1.0, 120.0);
    const FeedRun batched = feedAll(a, batches);
    const FeedRun oneByOne = feedAll(b, single);
    EXPECT_EQ(batched.snapshots, oneByOne.snapshots);
    EXPECT_LT(a.replayed(), b.replayed()); // the batch replays once
}

TEST(CorrelatorFeed, OlderThanTheWindowIsRefusedAndChangesNothing)
{
    const std::vector<Message> sorted = scenario();
    std::vector<Message> lateOne;
    std::vector<Message> rest;
    for (const Message& m : sorted) {
        (lateOne.empty() && fromLateUgv(m, 100.0, 160.0) ? lateOne : rest).push_back(m);
    }
    ASSERT_EQ(lateOne.size(), 1U);
    const auto give = [](const correlator::Snapshot&) {};
    CorrelatorFeed without(correlator::Mode::PoseCorrected, 1.0, 30.0);
    CorrelatorFeed with(correlator::Mode::PoseCorrected, 1.0, 30.0);
    for (const Message& m : rest) {
        ASSERT_TRUE(without.add(m, give));
        ASSERT_TRUE(with.add(m, give));
        if (timeOf(m) >= 140.0 && !lateOne.empty()) { // 40 s late: beyond the 30 s window
            const auto refused = with.add(lateOne.front(), give);
            ASSERT_FALSE(refused);
            EXPECT_NE(refused.error().message().find("more than the late window (30"), std::string::npos)
                << refused.error().message();
            EXPECT_NE(refused.error().fix.find("correlator.late_window_s"), std::string::npos);
            lateOne.clear();
        }
    }
    EXPECT_TRUE(lateOne.empty());
    EXPECT_EQ(with.applied(), without.applied());
    EXPECT_EQ(with.resequenced(), 0U);
    std::string a;
    std::string b;
    without.finish([&a](const correlator::Snapshot& s) { a = toJsonLine(s); });
    with.finish([&b](const correlator::Snapshot& s) { b = toJsonLine(s); });
    EXPECT_EQ(a, b);
}

TEST(CorrelatorFeed, BusyTimesComeFromTheCallersStopwatchOnly)
{
    constexpr double kTickS = 0.25;
    const std::vector<Message> messages = scenario();
    ASSERT_GE(messages.size(), 2U);
    double fakeNowS = 0.0;
    CorrelatorFeed timed(correlator::Mode::PoseCorrected, 1.0, 0.0, [&fakeNowS] { return fakeNowS += kTickS; });
    CorrelatorFeed untimed(correlator::Mode::PoseCorrected, 1.0);

    for (std::size_t i = 0; i < 2; ++i) {
        ASSERT_TRUE(timed.add(messages[i], nullptr).has_value());
        ASSERT_TRUE(untimed.add(messages[i], nullptr).has_value());
    }

    EXPECT_DOUBLE_EQ(timed.addSeconds(), 2 * kTickS); // one tick between the two reads around each add()
    EXPECT_DOUBLE_EQ(untimed.addSeconds(), 0.0);
    EXPECT_DOUBLE_EQ(untimed.snapshotSeconds(), 0.0);
}

TEST(CorrelatorFeed, WithoutAWindowAnOlderMessageIsRefused)
{
    CorrelatorFeed feed(correlator::Mode::PoseCorrected, 1.0);
    correlator::UavFix fix;
    fix.t = 10.0;
    fix.lat = -34.9;
    fix.lon = 138.6;
    ASSERT_TRUE(feed.add(fix, nullptr));
    fix.t = 9.5;
    const auto refused = feed.add(fix, nullptr);
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error().fix, "sort the input by time");
    EXPECT_EQ(feed.applied(), 1U);
    EXPECT_DOUBLE_EQ(feed.earliestAccepted(), 10.0);
    fix.t = NAN;
    EXPECT_FALSE(feed.add(fix, nullptr));
    EXPECT_EQ(feed.applied(), 1U);
}

} // namespace
} // namespace ugv::adapters

namespace ugv::adapters {
namespace {

using correlator::CorrelatorFeed;

correlator::Observation observationAt(double t)
{
    correlator::Observation o;
    o.t = t;
    o.ugv = "ugv-1";
    o.track = "a";
    o.ugvLat = -34.9;
    o.ugvLon = 138.6;
    o.rangeM = 10.0;
    return o;
}

// Issue 22: a jump in time gives at most kMaxSnapshotsPerGap snapshots and counts the rest; an absurd time is refused.
TEST(CorrelatorFeedHostile, AJumpInTimeWritesABoundedNumberOfSnapshots)
{
    constexpr double kJumpS = 1e9;
    CorrelatorFeed sut(correlator::Mode::PoseCorrected, 1.0, 300.0);
    std::size_t written = 0;
    const auto count = [&written](const correlator::Snapshot&) { ++written; };
    ASSERT_TRUE(sut.add(Message{observationAt(0.0)}, count).has_value());

    ASSERT_TRUE(sut.add(Message{observationAt(kJumpS)}, count).has_value());

    EXPECT_EQ(written, CorrelatorFeed::kMaxSnapshotsPerGap);
    EXPECT_EQ(sut.skippedSnapshots(), static_cast<std::size_t>(kJumpS) - CorrelatorFeed::kMaxSnapshotsPerGap);
    ASSERT_TRUE(sut.add(Message{observationAt(kJumpS + 1.0)}, count).has_value());
    EXPECT_EQ(written, CorrelatorFeed::kMaxSnapshotsPerGap + 1); // the boundary at kJumpS + 1 is written again
}

TEST(CorrelatorFeedHostile, TimesBeyondTheLimitAreRefused)
{
    CorrelatorFeed sut(correlator::Mode::Original, 1.0);
    std::size_t written = 0;
    const auto count = [&written](const correlator::Snapshot&) { ++written; };
    ASSERT_TRUE(sut.add(Message{observationAt(0.0)}, count).has_value());

    const auto refused = sut.add(Message{observationAt(1e17)}, count);

    ASSERT_FALSE(refused.has_value());
    EXPECT_NE(refused.error().what.find("beyond"), std::string::npos) << refused.error().message();
    EXPECT_EQ(written, 0U);
}

TEST(CorrelatorFeedHostile, JsonFieldsOutsideTheirRangesAreRefusedNamingTheField)
{
    const std::string base = R"("kind": "observation", "ugv": "u", "track": "a", "class": "static", "ugv_lat": 0, )"
                             R"("ugv_lon": 0, "ugv_heading_deg": 0, "bearing_deg": 0)";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {R"({"t": 0, "range_m": 1e19, )" + base + "}", "field 'range_m' value 1e+19 is outside [0, 100000] m"},
        {R"({"t": 0, "range_m": 1e308, )" + base + "}", "field 'range_m' value 1e+308"},
        {R"({"t": 1e17, "range_m": 10, )" + base + "}", "field 't' value 1e+17 is outside"},
        {R"({"t": 0, "range_m": 10, "range_m": 1e300, )" + base + "}", "field 'range_m' is given twice"},
        {R"({"t": 0, "range_m": 10, "x": [[[[[[[[[[1]]]]]]]]]], )" + base + "}", "nested deeper than 8 levels"},
        {R"({"t": 0, "kind": "pose_correction", "ugv": "u", "since_t": 0, "until_t": 1, "d_east_m": 1e12, )"
         R"("d_north_m": 0, "d_heading_deg": 0})",
         "field 'd_east_m' value 1e+12"},
        {R"({"t": 0, "range_m": 10, "x": ")" + std::string(kMaxMessageLineBytes, 'x') + "\", " + base + "}",
         "line over 65536 bytes"},
    };
    for (const auto& [line, expected] : cases) {
        const auto parsed = parseMessageLine(line);

        ASSERT_FALSE(parsed.has_value()) << line.substr(0, 200);
        EXPECT_NE(parsed.error().message().find(expected), std::string::npos) << parsed.error().message();
    }
    EXPECT_TRUE(parseMessageLine(R"({"t": 0, "range_m": 99999, )" + base + "}").has_value());
}

TEST(CorrelatorFeedHostile, ReadBoundedLineKeepsAtMostOneByteOverTheLimit)
{
    std::istringstream in("abc\n" + std::string(100, 'x') + "\nlast");
    std::string line;

    ASSERT_TRUE(readBoundedLine(in, line, 10));
    EXPECT_EQ(line, "abc");
    ASSERT_TRUE(readBoundedLine(in, line, 10));
    EXPECT_EQ(line, std::string(11, 'x'));
    ASSERT_TRUE(readBoundedLine(in, line, 10));
    EXPECT_EQ(line, "last");
    EXPECT_FALSE(readBoundedLine(in, line, 10));
}

TEST(CorrelatorFeedHostile, SnapshotLinesAreCheckedAsInputLines)
{
    const auto twice = parseSnapshotLine(R"({"t": 1, "objects": [], "alerts": [], "t": 2})");
    ASSERT_FALSE(twice.has_value());
    EXPECT_NE(twice.error().what.find("field 't' is given twice"), std::string::npos) << twice.error().message();

    const auto far = parseSnapshotLine(R"({"t": 1e17, "objects": [], "alerts": []})");
    ASSERT_FALSE(far.has_value());
    EXPECT_NE(far.error().what.find("field 't' value 1e+17"), std::string::npos) << far.error().message();

    EXPECT_TRUE(parseSnapshotLine(R"({"t": 1, "objects": [], "alerts": []})").has_value());
}

TEST(CorrelatorFeedHostile, AnObservationCountBeyondIntIsRefusedNotConverted)
{
    // The correlator_line fuzz target's find (test/fuzz/corpus/correlator_line/crash-observations-beyond-int.json):
    // 3.8e124 observations was cast to int (undefined behaviour).
    const std::string object = R"({"id": "c-1", "class": "static", "lat": -34.9, "lon": 138.6, "sigma_major_m": 1,
        "sigma_minor_m": 0.5, "major_axis_deg": 5, "state": "unknown", "ugvs": ["ugv-1"], "zone_diameter_m": 20,
        "observations": )";
    for (const char* bad : {"3.8e124", "-1", "2147483648", "2.5"}) {
        const auto parsed = parseSnapshotLine(R"({"t": 1, "alerts": [], "objects": [)" + object + bad + "}]}");
        ASSERT_FALSE(parsed.has_value()) << bad;
        EXPECT_NE(parsed.error().what.find("'observations' is"), std::string::npos) << parsed.error().message();
    }
    const auto good = parseSnapshotLine(R"({"t": 1, "alerts": [], "objects": [)" + object + "2147483647}]}");
    ASSERT_TRUE(good.has_value()) << good.error().message();
    EXPECT_EQ(good->objects.at(0).observations, 2147483647);
}

} // namespace
} // namespace ugv::adapters
