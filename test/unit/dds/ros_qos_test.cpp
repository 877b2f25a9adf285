// The writers' reliability. The ROS 2 topics' (issue 23, BusConfig::rosReliable): a reader with ROS 2's default QoS
// (reliable, as RViz and `ros2 topic echo` use) matches the LaserScan writer of the default config, and is told of
// an incompatible QoS by a best-effort one. Our best-effort topics' writers are reliable (so that Fast DDS 2.9.1
// sends a same-host sample once, over shared memory: Bus::makeWriter): a reliable reader matches the sectors writer.
// The reader is plain Fast DDS, as a ROS 2 node's would be.

#include <unistd.h>

#include <chrono>
#include <functional>
#include <string>
#include <thread>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/subscriber/qos/SubscriberQos.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <gtest/gtest.h>

#include "ugv/ipc/dds_bus.hpp"

namespace ugv::ipc::dds {
namespace {

namespace fdds = eprosima::fastdds::dds;

struct ReaderStatus {
    int matched = 0;
    int incompatible = 0;
};

/// A topic of a Bus: how its writer is made, and where a plain reader finds it.
struct WriterUnderTest {
    std::function<bool(Bus&)> makeWriter; ///< false when it could not be made
    std::string topicName;
    fdds::TopicDataType* type; ///< owned by the reader's TypeSupport
    std::string partition;     ///< empty: the default one
};

/// What a reliable reader saw once it matched `w`'s writer (made on a Bus with `c`) or was told of an incompatible
/// writer (at most 15 s).
ReaderStatus reliableReaderAgainst(const BusConfig& c, const WriterUnderTest& w)
{
    auto bus = Bus::create(c);
    EXPECT_TRUE(bus) << bus.error().message();
    if (!bus || !w.makeWriter(**bus)) {
        ADD_FAILURE() << "cannot make the writer of " << w.topicName;
        return {};
    }
    auto* factory = fdds::DomainParticipantFactory::get_instance();
    fdds::DomainParticipant* participant = factory->create_participant(c.domainId, fdds::PARTICIPANT_QOS_DEFAULT);
    EXPECT_NE(participant, nullptr);
    if (participant == nullptr) {
        return {};
    }
    fdds::TypeSupport type(w.type);
    type.register_type(participant);
    fdds::Topic* topic = participant->create_topic(w.topicName, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    fdds::SubscriberQos sq = fdds::SUBSCRIBER_QOS_DEFAULT;
    if (!w.partition.empty()) {
        sq.partition().push_back(w.partition.c_str());
    }
    fdds::Subscriber* subscriber = participant->create_subscriber(sq);
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS; // ROS 2's default (rmw_qos_profile_default)
    fdds::DataReader* reader = subscriber->create_datareader(topic, q);
    EXPECT_NE(reader, nullptr);

    ReaderStatus seen;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
    while (reader != nullptr && seen.matched == 0 && seen.incompatible == 0 &&
           std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        fdds::SubscriptionMatchedStatus matched;
        fdds::RequestedIncompatibleQosStatus incompatible;
        reader->get_subscription_matched_status(matched);
        reader->get_requested_incompatible_qos_status(incompatible);
        seen = {matched.current_count, static_cast<int>(incompatible.total_count)};
    }
    participant->delete_contained_entities();
    factory->delete_participant(participant);
    return seen;
}

BusConfig busConfig(const std::string& tag)
{
    BusConfig c;
    c.domainId = 150 + static_cast<int>(::getpid() % 80);
    c.participantName = "unit-dds-ros-qos";
    c.rosNamespace = "rosqos" + std::to_string(::getpid()) + tag;
    c.partitions = {"rosqos-" + std::to_string(::getpid()) + tag};
    return c;
}

/// A reliable ROS 2-style reader of rt/<ns>/obstacle_scan beside a Bus whose scan writer has `rosReliable`.
ReaderStatus reliableReaderOfTheScan(bool rosReliable)
{
    BusConfig c = busConfig(rosReliable ? "r" : "b");
    c.rosReliable = rosReliable;
    const WriterUnderTest scan{[](Bus& bus) { return bus.writer<ros::LaserScan_>().has_value(); },
                               "rt/" + c.rosNamespace + "/obstacle_scan", new ros::LaserScan_PubSubType(), ""};
    return reliableReaderAgainst(c, scan);
}

TEST(RosQos, AReliableRos2ReaderMatchesTheDefaultScanWriter)
{
    const ReaderStatus sut = reliableReaderOfTheScan(true);

    EXPECT_EQ(sut.matched, 1);
    EXPECT_EQ(sut.incompatible, 0);
}

TEST(RosQos, ABestEffortScanWriterServesOnlyBestEffortReaders)
{
    const ReaderStatus sut = reliableReaderOfTheScan(false);

    EXPECT_EQ(sut.matched, 0);
    EXPECT_GE(sut.incompatible, 1);
}

TEST(RosQos, TheBestEffortSectorsTopicIsWrittenReliableSoThatASameHostSampleIsSentOnce)
{
    const BusConfig c = busConfig("s");
    const WriterUnderTest sectors{[](Bus& bus) { return bus.writer<msg::ObstacleSectors>().has_value(); },
                                  "ugvsense/sectors", new msg::ObstacleSectorsPubSubType(), c.partitions.front()};

    const ReaderStatus sut = reliableReaderAgainst(c, sectors);

    EXPECT_EQ(sut.matched, 1);
    EXPECT_EQ(sut.incompatible, 0);
}

} // namespace
} // namespace ugv::ipc::dds
