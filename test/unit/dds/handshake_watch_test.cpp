// ipc::dds::HandshakeWatch: which secured handshakes never ended (Bus::stalledHandshakes()).

#include "ugv/ipc/handshake_watch.hpp"

#include <array>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace ugv::ipc::dds {
namespace {

using std::chrono::seconds;
const HandshakeWatch::Clock::time_point kT0{seconds(1000)};
constexpr bool kOurs = true;     ///< a peer naming this team's CA
constexpr bool kForeign = false; ///< a peer naming another CA, or none

TEST(HandshakeWatch, AHandshakeIsStalledOnlyWhenItOutlivesTheLimitUnended)
{
    HandshakeWatch w;
    w.discovered("us", "ugv-1", kT0, kOurs);
    w.discovered("us", "ugv-2", kT0 + seconds(5), kOurs);
    EXPECT_EQ(w.stalled("us", kT0 + seconds(9), seconds(10)), 0U);
    EXPECT_EQ(w.stalled("us", kT0 + seconds(10), seconds(10)), 1U);
    EXPECT_EQ(w.stalled("us", kT0 + seconds(15), seconds(10)), 2U);
    w.ended("us", "ugv-1");
    EXPECT_EQ(w.stalled("us", kT0 + seconds(15), seconds(10)), 1U);
    w.removed("us", "ugv-2");
    EXPECT_EQ(w.stalled("us", kT0 + seconds(60), seconds(10)), 0U);
}

TEST(HandshakeWatch, AnEndReportedBeforeTheDiscoveryIsKept)
{
    HandshakeWatch w;
    w.ended("us", "ugv-1");
    w.discovered("us", "ugv-1", kT0, kOurs);
    EXPECT_EQ(w.stalled("us", kT0 + seconds(60), seconds(10)), 0U);
    w.removed("us", "ugv-1"); // it left; when it comes back its handshake starts again
    w.discovered("us", "ugv-1", kT0 + seconds(100), kOurs);
    EXPECT_EQ(w.stalled("us", kT0 + seconds(110), seconds(10)), 1U);
}

TEST(HandshakeWatch, EachLocalParticipantCountsItsOwnAndAForgottenOneNone)
{
    HandshakeWatch w; // a renewed bus: the old participant's stalled handshake is not the new one's
    w.discovered("old", "ugv-1", kT0, kOurs);
    w.discovered("new", "ugv-1", kT0 + seconds(20), kOurs);
    EXPECT_EQ(w.stalled("old", kT0 + seconds(25), seconds(10)), 1U);
    EXPECT_EQ(w.stalled("new", kT0 + seconds(25), seconds(10)), 0U);
    w.forget("old");
    EXPECT_EQ(w.stalled("old", kT0 + seconds(60), seconds(10)), 0U);
    EXPECT_EQ(w.stalled("new", kT0 + seconds(60), seconds(10)), 1U);
    EXPECT_EQ(w.stalled("ne", kT0 + seconds(60), seconds(10)), 0U); // a prefix of another's name is not it
}

TEST(HandshakeWatch, AFloodOfParticipantsKeepsTheTableBoundedAndForgetsTheOldestFirst)
{
    HandshakeWatch w;
    w.discovered("us", "ended", kT0, kOurs);
    w.ended("us", "ended");
    for (std::size_t i = 0; i < HandshakeWatch::kMaxEntries + 10; ++i) {
        w.discovered("us", "intruder-" + std::to_string(i), kT0 + seconds(static_cast<long>(i)), kOurs);
    }
    const auto late = kT0 + seconds(100000);
    EXPECT_EQ(w.stalled("us", late, seconds(10)), HandshakeWatch::kMaxEntries);
    // The newest is kept: it still counts when only it is old enough.
    const auto newest = kT0 + seconds(static_cast<long>(HandshakeWatch::kMaxEntries + 9));
    EXPECT_EQ(w.stalled("us", newest + seconds(10), seconds(10)), HandshakeWatch::kMaxEntries);
    EXPECT_EQ(w.stalled("us", newest + seconds(9), seconds(10)), HandshakeWatch::kMaxEntries - 1);
}

TEST(HandshakeWatch, AnUnfinishedHandshakeWithAPeerOfAnotherCaIsNotAStall)
{
    HandshakeWatch w; // Fast DDS 2.9.1 reports nothing, ever, on the side another CA's participant refused
    w.discovered("us", "rogue", kT0, kForeign);
    w.discovered("us", "ugv-1", kT0, kOurs);
    const auto u = w.unfinished("us", kT0 + seconds(30), seconds(10));
    EXPECT_EQ(u.sameCa, 1U);
    EXPECT_EQ(u.otherCa, 1U);
    EXPECT_EQ(w.stalled("us", kT0 + seconds(30), seconds(10)), 1U);
    w.ended("us", "ugv-1");
    EXPECT_EQ(w.stalled("us", kT0 + seconds(30), seconds(10)), 0U);
    EXPECT_EQ(w.unfinished("us", kT0 + seconds(30), seconds(10)).otherCa, 1U);
}

TEST(RejoinBackoff, JoinsAtOnceThenWaitsTwiceAsLongEachTimeUpToTheLongestWait)
{
    RejoinBackoff b;
    auto t = kT0;
    EXPECT_FALSE(b.due(t, 0));
    ASSERT_TRUE(b.due(t, 1));
    std::vector<long> waits;
    for (int i = 0; i < 8; ++i) {
        b.joined(t);
        const auto wait = b.wait();
        waits.push_back(std::chrono::duration_cast<seconds>(wait).count());
        EXPECT_FALSE(b.due(t + wait - seconds(1), 1)) << "join " << i;
        t += wait;
        EXPECT_TRUE(b.due(t, 1)) << "join " << i;
    }
    EXPECT_EQ(waits, (std::vector<long>{10, 20, 40, 80, 160, 320, 320, 320}));
}

TEST(RejoinBackoff, ACheckWithoutAStallStartsThePaceAgain)
{
    RejoinBackoff b;
    b.joined(kT0);
    b.joined(kT0 + seconds(10));
    EXPECT_EQ(b.wait(), seconds(20));
    EXPECT_FALSE(b.due(kT0 + seconds(11), 0)); // the handshakes ended after the join
    EXPECT_TRUE(b.due(kT0 + seconds(12), 1));  // a new stall is met at once
    b.joined(kT0 + seconds(12));
    EXPECT_EQ(b.wait(), seconds(10));
}

/// A GUID prefix whose first bytes are `n`.
std::array<std::uint8_t, RefusedPrefixes::kPrefixBytes> prefix(std::uint32_t n)
{
    std::array<std::uint8_t, RefusedPrefixes::kPrefixBytes> p{};
    for (std::size_t i = 0; i < 4; ++i) {
        p[i] = static_cast<std::uint8_t>(n >> (8 * i));
    }
    return p;
}

TEST(RefusedPrefixes, OnlyARefusedParticipantsDatagramsAreDroppedAndCounted)
{
    RefusedPrefixes r;
    EXPECT_FALSE(r.drop(prefix(1).data())); // nothing refused yet
    r.add(prefix(1).data());
    r.add(prefix(1).data()); // Fast DDS reports a refused participant again and again
    EXPECT_TRUE(r.drop(prefix(1).data()));
    EXPECT_FALSE(r.drop(prefix(2).data()));
    EXPECT_TRUE(r.drop(prefix(1).data()));
    EXPECT_EQ(r.dropped(), 2U);
}

TEST(RefusedPrefixes, AFloodOfRefusedParticipantsKeepsTheNewestAndForgetsTheOldest)
{
    RefusedPrefixes r;
    const auto n = static_cast<std::uint32_t>(RefusedPrefixes::kMaxEntries + 10);
    for (std::uint32_t i = 0; i < n; ++i) {
        r.add(prefix(i).data());
    }
    EXPECT_FALSE(r.drop(prefix(0).data()));
    EXPECT_FALSE(r.drop(prefix(9).data()));
    EXPECT_TRUE(r.drop(prefix(10).data()));
    EXPECT_TRUE(r.drop(prefix(n - 1).data()));
}

} // namespace
} // namespace ugv::ipc::dds
