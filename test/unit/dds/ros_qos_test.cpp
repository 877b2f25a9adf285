// The ROS 2 topics' writer reliability (issue 23, BusConfig::rosReliable): a reader with ROS 2's default QoS
// (reliable, as RViz and `ros2 topic echo` use) matches the LaserScan writer of the default config, and is told of
// an incompatible QoS by a best-effort one. The reader is plain Fast DDS, as a ROS 2 node's would be.

#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
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

/// A reliable ROS 2-style reader of rt/<ns>/obstacle_scan beside a Bus whose scan writer has `rosReliable`; what it
/// saw once it matched or was told of an incompatible writer (at most 15 s).
ReaderStatus reliableReaderAgainst(bool rosReliable)
{
    const int domain = 150 + static_cast<int>(::getpid() % 80);
    BusConfig c;
    c.domainId = domain;
    c.participantName = "unit-dds-ros-qos";
    c.rosNamespace = "rosqos" + std::to_string(::getpid()) + (rosReliable ? "r" : "b");
    c.rosReliable = rosReliable;
    auto bus = Bus::create(c);
    EXPECT_TRUE(bus) << bus.error().message();
    if (!bus) {
        return {};
    }
    auto writer = (*bus)->writer<ros::LaserScan_>();
    EXPECT_TRUE(writer) << writer.error().message();

    auto* factory = fdds::DomainParticipantFactory::get_instance();
    fdds::DomainParticipant* participant = factory->create_participant(domain, fdds::PARTICIPANT_QOS_DEFAULT);
    EXPECT_NE(participant, nullptr);
    if (participant == nullptr) {
        return {};
    }
    fdds::TypeSupport type(new ros::LaserScan_PubSubType());
    type.register_type(participant);
    fdds::Topic* topic = participant->create_topic("rt/" + c.rosNamespace + "/obstacle_scan", type.get_type_name(),
                                                   fdds::TOPIC_QOS_DEFAULT);
    fdds::Subscriber* subscriber = participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
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

TEST(RosQos, AReliableRos2ReaderMatchesTheDefaultScanWriter)
{
    const ReaderStatus sut = reliableReaderAgainst(true);

    EXPECT_EQ(sut.matched, 1);
    EXPECT_EQ(sut.incompatible, 0);
}

TEST(RosQos, ABestEffortScanWriterServesOnlyBestEffortReaders)
{
    const ReaderStatus sut = reliableReaderAgainst(false);

    EXPECT_EQ(sut.matched, 0);
    EXPECT_GE(sut.incompatible, 1);
}

} // namespace
} // namespace ugv::ipc::dds
