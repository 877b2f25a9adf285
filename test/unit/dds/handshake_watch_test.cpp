// ipc::dds::HandshakeWatch: which secured handshakes never ended (Bus::stalledHandshakes()).

#include "ugv/ipc/handshake_watch.hpp"

#include <chrono>
#include <string>

#include <gtest/gtest.h>

namespace ugv::ipc::dds {
namespace {

using std::chrono::seconds;
const HandshakeWatch::Clock::time_point kT0{seconds(1000)};

TEST(HandshakeWatch, AHandshakeIsStalledOnlyWhenItOutlivesTheLimitUnended)
{
    HandshakeWatch w;
    w.discovered("us", "ugv-1", kT0);
    w.discovered("us", "ugv-2", kT0 + seconds(5));
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
    w.discovered("us", "ugv-1", kT0);
    EXPECT_EQ(w.stalled("us", kT0 + seconds(60), seconds(10)), 0U);
    w.removed("us", "ugv-1"); // it left; when it comes back its handshake starts again
    w.discovered("us", "ugv-1", kT0 + seconds(100));
    EXPECT_EQ(w.stalled("us", kT0 + seconds(110), seconds(10)), 1U);
}

TEST(HandshakeWatch, EachLocalParticipantCountsItsOwnAndAForgottenOneNone)
{
    HandshakeWatch w; // a renewed bus: the old participant's stalled handshake is not the new one's
    w.discovered("old", "ugv-1", kT0);
    w.discovered("new", "ugv-1", kT0 + seconds(20));
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
    w.discovered("us", "ended", kT0);
    w.ended("us", "ended");
    for (std::size_t i = 0; i < HandshakeWatch::kMaxEntries + 10; ++i) {
        w.discovered("us", "intruder-" + std::to_string(i), kT0 + seconds(static_cast<long>(i)));
    }
    const auto late = kT0 + seconds(100000);
    EXPECT_EQ(w.stalled("us", late, seconds(10)), HandshakeWatch::kMaxEntries);
    // The newest is kept: it still counts when only it is old enough.
    const auto newest = kT0 + seconds(static_cast<long>(HandshakeWatch::kMaxEntries + 9));
    EXPECT_EQ(w.stalled("us", newest + seconds(10), seconds(10)), HandshakeWatch::kMaxEntries);
    EXPECT_EQ(w.stalled("us", newest + seconds(9), seconds(10)), HandshakeWatch::kMaxEntries - 1);
}

} // namespace
} // namespace ugv::ipc::dds
