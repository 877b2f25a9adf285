// ROS 2's graph (issue 23 item 2): the service announces itself on ros_discovery_info as rmw_fastrtps does, so that
// `ros2 node list` shows it. The reader here is plain Fast DDS with the QoS of ROS 2's own graph reader (reliable,
// transient local, keep last 1), created after the announcement as a ROS 2 tool started later would be.

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <gtest/gtest.h>

#include "ugv/ipc/dds_bus.hpp"
#include "ugv/ipc/dds_convert.hpp"

namespace ugv::ipc::dds {
namespace {

namespace fdds = eprosima::fastdds::dds;

BusConfig graphConfig(const std::string& suffix)
{
    BusConfig c;
    c.domainId = 150 + static_cast<int>(::getpid() % 80);
    c.participantName = "unit-dds-ros-graph";
    c.rosNamespace = "rosgraph" + std::to_string(::getpid()) + suffix;
    return c;
}

/// A ROS 2 tool's graph reader on `domain`: the newest ParticipantEntitiesInfo holding a node in `nodeNamespace`
/// (others' samples are skipped), or nothing after 15 s.
struct GraphReader {
    explicit GraphReader(int domain)
    {
        auto* factory = fdds::DomainParticipantFactory::get_instance();
        participant = factory->create_participant(domain, fdds::PARTICIPANT_QOS_DEFAULT);
        fdds::TypeSupport type(new graph::ParticipantEntitiesInfo_PubSubType());
        type.register_type(participant);
        fdds::Topic* topic =
            participant->create_topic("ros_discovery_info", type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
        fdds::Subscriber* subscriber = participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
        fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
        q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
        q.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
        q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
        q.history().depth = 1;
        reader = subscriber->create_datareader(topic, q);
    }
    ~GraphReader()
    {
        participant->delete_contained_entities();
        fdds::DomainParticipantFactory::get_instance()->delete_participant(participant);
    }
    GraphReader(const GraphReader&) = delete;
    GraphReader& operator=(const GraphReader&) = delete;
    GraphReader(GraphReader&&) = delete;
    GraphReader& operator=(GraphReader&&) = delete;

    bool next(const std::string& nodeNamespace, graph::ParticipantEntitiesInfo_& out)
    {
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
        while (reader != nullptr && std::chrono::steady_clock::now() < deadline) {
            reader->wait_for_unread_message(eprosima::fastrtps::Duration_t(0, 100'000'000));
            graph::ParticipantEntitiesInfo_ sample;
            fdds::SampleInfo info;
            while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
                if (info.valid_data && !sample.node_entities_info_seq().empty() &&
                    sample.node_entities_info_seq()[0].node_namespace() == nodeNamespace) {
                    out = sample;
                    return true;
                }
            }
        }
        return false;
    }

    fdds::DomainParticipant* participant = nullptr;
    fdds::DataReader* reader = nullptr;
};

bool sameGid(const graph::Gid_& a, const graph::Gid_& b)
{
    return a.data() == b.data();
}

bool holds(const std::vector<graph::Gid_>& gids, const graph::Gid_& g)
{
    return std::any_of(gids.begin(), gids.end(), [&](const graph::Gid_& x) { return sameGid(x, g); });
}

TEST(RosGraph, AGidIsTheGuidPrefixThenTheEntityIdThenZeros)
{
    eprosima::fastrtps::rtps::GUID_t guid;
    for (int i = 0; i < 12; ++i) {
        guid.guidPrefix.value[i] = static_cast<eprosima::fastrtps::rtps::octet>(i + 1);
    }
    guid.entityId = eprosima::fastrtps::rtps::EntityId_t(0x00000102); // key 0x000001, kind 0x02 (writer, with key)

    const graph::Gid_ sut = rosGid(guid);

    for (int i = 0; i < 12; ++i) {
        EXPECT_EQ(sut.data()[i], i + 1);
    }
    EXPECT_EQ(sut.data()[12], guid.entityId.value[0]);
    EXPECT_EQ(sut.data()[15], guid.entityId.value[3]);
    for (int i = 16; i < 24; ++i) {
        EXPECT_EQ(sut.data()[i], 0);
    }
}

TEST(RosGraph, TheServiceIsANodeOfItsNamespaceWithItsRosWriters)
{
    const BusConfig c = graphConfig("w");
    auto bus = Bus::create(c);
    ASSERT_TRUE(bus) << bus.error().message();
    auto scan = (*bus)->writer<ros::LaserScan_>();
    auto clearScan = (*bus)->writer<ros::LaserScan_>(TopicId::RosClearScan);
    auto cloud = (*bus)->writer<ros::PointCloud2_>();
    auto sectors = (*bus)->writer<msg::ObstacleSectors>(); // ours: not a ROS 2 topic, not listed
    ASSERT_TRUE(scan && clearScan && cloud && sectors);

    ASSERT_TRUE((*bus)->announceRosNode("ugvsense"));
    GraphReader tool(c.domainId); // after the announcement: a ROS 2 tool started later
    graph::ParticipantEntitiesInfo_ got;
    ASSERT_TRUE(tool.next("/" + c.rosNamespace, got)) << "no ros_discovery_info sample in 15 s";

    ASSERT_EQ(got.node_entities_info_seq().size(), 1U);
    const graph::NodeEntitiesInfo_& node = got.node_entities_info_seq()[0];
    EXPECT_EQ(node.node_name().to_string(), "ugvsense");
    EXPECT_EQ(node.writer_gid_seq().size(), 3U);
    EXPECT_TRUE(holds(node.writer_gid_seq(), rosGid(scan->guid())));
    EXPECT_TRUE(holds(node.writer_gid_seq(), rosGid(clearScan->guid())));
    EXPECT_TRUE(holds(node.writer_gid_seq(), rosGid(cloud->guid())));
    EXPECT_FALSE(holds(node.writer_gid_seq(), rosGid(sectors->guid())));
    EXPECT_TRUE(node.reader_gid_seq().empty());
    // The participant's GID: its writers' prefix and the participant's entity id (00 00 01 c1).
    const graph::Gid_ writer = rosGid(scan->guid());
    EXPECT_TRUE(std::equal(writer.data().begin(), writer.data().begin() + 12, got.gid().data().begin()));
    EXPECT_EQ(got.gid().data()[15], 0xC1);
    EXPECT_EQ(check(got), nullptr);
}

/// Writes `sample` on `writer` until `reader` takes one (a discovery to wait out), at most 15 s.
template <class T>
bool arrives(Writer<T>& writer, Reader<T>& reader, const T& sample)
{
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
    T got;
    while (std::chrono::steady_clock::now() < deadline) {
        writer.write(sample);
        if (reader.wait(std::chrono::milliseconds(100)) && reader.take(got)) {
            return true;
        }
    }
    return false;
}

// A link that comes up after the start (Bus::followNetworkChanges, system.late-link) makes the participant and its
// endpoints anew. The handles taken before go on working, on the new entities; another thread using one meanwhile
// waits for the renewal instead of touching a deleted entity; the ROS 2 node is announced again with the new GIDs.
TEST(RosGraph, ARenewedBusKeepsItsHandlesWorkingAndAnnouncesItsNodeWithTheNewGids)
{
    const BusConfig c = graphConfig("r");
    auto bus = Bus::create(c);
    auto peer = Bus::create(c);
    ASSERT_TRUE(bus && peer);
    auto scan = (*bus)->writer<ros::LaserScan_>();
    auto out = (*bus)->writer<msg::ObstacleSectors>();
    auto in = (*bus)->reader<msg::VehiclePose>();
    auto peerIn = (*peer)->reader<msg::ObstacleSectors>();
    auto peerOut = (*peer)->writer<msg::VehiclePose>();
    ASSERT_TRUE(scan && out && in && peerIn && peerOut);
    ASSERT_TRUE((*bus)->announceRosNode("ugvsense"));
    msg::ObstacleSectors sectors;
    sectors.vehicle("ugv-renew");
    msg::VehiclePose pose;
    pose.vehicle("ugv-renew");
    ASSERT_TRUE(arrives(*out, *peerIn, sectors));
    const graph::Gid_ before = rosGid(scan->guid());

    std::atomic<bool> stop{false};
    std::atomic<int> writes{0};
    std::thread user([&] { // the vehicle's correlator task, say, on its own thread
        while (!stop.load()) {
            (void)out->write(sectors);
            writes.fetch_add(1);
        }
    });
    while (writes.load() < 10) {
        std::this_thread::yield();
    }
    auto renewed = (*bus)->renew();
    stop.store(true);
    user.join();
    ASSERT_TRUE(renewed) << renewed.error().message();

    EXPECT_FALSE(sameGid(rosGid(scan->guid()), before)) << "the writer was not made again";
    EXPECT_TRUE(arrives(*out, *peerIn, sectors)) << "a writer taken before the renewal no longer reaches its reader";
    EXPECT_TRUE(arrives(*peerOut, *in, pose)) << "a reader taken before the renewal no longer receives";
    GraphReader tool(c.domainId);
    graph::ParticipantEntitiesInfo_ got;
    ASSERT_TRUE(tool.next("/" + c.rosNamespace, got)) << "no ros_discovery_info sample in 15 s";
    ASSERT_EQ(got.node_entities_info_seq().size(), 1U);
    EXPECT_TRUE(holds(got.node_entities_info_seq()[0].writer_gid_seq(), rosGid(scan->guid())));
    EXPECT_FALSE(holds(got.node_entities_info_seq()[0].writer_gid_seq(), before));
}

TEST(RosGraph, AWriterOrReaderOfAnotherTypeOnATopicIsRefused)
{
    auto bus = Bus::create(graphConfig("t"));
    ASSERT_TRUE(bus) << bus.error().message();
    const auto cloudOnScan = (*bus)->writer<ros::PointCloud2_>(TopicId::RosClearScan);
    ASSERT_FALSE(cloudOnScan);
    EXPECT_NE(cloudOnScan.error().message().find("clear_scan"), std::string::npos) << cloudOnScan.error().message();
    EXPECT_FALSE((*bus)->reader<msg::ObstacleSectors>(TopicId::RosScan));
    EXPECT_TRUE((*bus)->reader<ros::LaserScan_>(TopicId::RosClearScan)); // the same type: a clearing scan's reader
}

TEST(RosGraph, AnAnnouncementAfterANewReaderListsIt)
{
    const BusConfig c = graphConfig("r");
    auto bus = Bus::create(c);
    ASSERT_TRUE(bus) << bus.error().message();
    auto scan = (*bus)->writer<ros::LaserScan_>();
    ASSERT_TRUE(scan && (*bus)->announceRosNode("ugvsense"));

    auto scanIn = (*bus)->reader<ros::LaserScan_>();
    ASSERT_TRUE(scanIn);
    ASSERT_TRUE((*bus)->announceRosNode("ugvsense"));
    GraphReader tool(c.domainId);
    graph::ParticipantEntitiesInfo_ got;
    ASSERT_TRUE(tool.next("/" + c.rosNamespace, got)) << "no ros_discovery_info sample in 15 s";

    ASSERT_EQ(got.node_entities_info_seq().size(), 1U); // keep last 1: the newest announcement only
    EXPECT_EQ(got.node_entities_info_seq()[0].reader_gid_seq().size(), 1U);
    EXPECT_EQ(got.node_entities_info_seq()[0].writer_gid_seq().size(), 1U);
}

TEST(RosGraph, ANameRos2CannotHoldIsRefused)
{
    auto bus = Bus::create(graphConfig("n"));
    ASSERT_TRUE(bus) << bus.error().message();

    for (const std::string& bad :
         std::vector<std::string>{"", "9lives", "ugv sense", "ugv-sense", std::string(256, 'u')}) {
        const auto sut = (*bus)->announceRosNode(bad);

        ASSERT_FALSE(sut) << bad;
        EXPECT_NE(sut.error().message().find("not a ROS 2 node name"), std::string::npos);
    }
}

} // namespace
} // namespace ugv::ipc::dds
