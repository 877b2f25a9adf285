// Fuzz target: every DDS sample the service or a tool receives, as the bus hands it over: the first byte picks the
// type, the rest is the serialized payload (CDR with its encapsulation header) given to the type's deserialize
// (what a DataReader does on receipt); an accepted sample then passes ipc::udds::check() and, where the service
// converts it, fromDds().
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "ugv/adapters/correlator_dds.hpp"
#include "ugv/ipc/dds_bus.hpp"
#include "ugv/ipc/dds_convert.hpp"

namespace {

namespace udds = ugv::ipc::dds;

template <class Sample, class After>
void decode(const std::uint8_t* data, std::size_t size, After after)
{
    typename udds::TopicOf<Sample>::PubSubType type;
    eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(size));
    if (size > 0) {
        std::memcpy(payload.data, data, size);
    }
    payload.length = static_cast<std::uint32_t>(size);
    Sample sample;
    if (type.deserialize(&payload, &sample) && udds::check(sample) == nullptr) {
        after(sample);
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    if (size == 0) {
        return 0;
    }
    const std::uint8_t which = data[0];
    ++data;
    --size;
    const auto none = [](const auto&) {};
    const auto toMessage = [](const auto& s) { (void)ugv::adapters::fromDds(s); };
    switch (which % 11U) {
    case 0:
        decode<udds::msg::ObstacleSectors>(data, size, [](const udds::msg::ObstacleSectors& s) {
            ugv::ObstacleSectors out;
            (void)udds::fromDds(s, out);
        });
        break;
    case 1:
        decode<udds::msg::ServiceHealth>(data, size, none);
        break;
    case 2:
        decode<udds::msg::VehiclePose>(data, size, none);
        break;
    case 3:
        decode<udds::msg::OoiObservation>(data, size, toMessage);
        break;
    case 4:
        decode<udds::msg::UavObservation>(data, size, toMessage);
        break;
    case 5:
        decode<udds::msg::ConfirmationState>(data, size, toMessage);
        break;
    case 6:
        decode<udds::msg::PoseCorrection>(data, size, toMessage);
        break;
    case 7:
        decode<udds::msg::CorrelatedOoiList>(data, size, toMessage);
        break;
    case 8:
        decode<udds::ros::LaserScan_>(data, size, none);
        break;
    case 9:
        decode<udds::ros::PointCloud2_>(data, size, none);
        break;
    default:
        decode<udds::graph::ParticipantEntitiesInfo_>(data, size, none); // `ugvsense listen ros_discovery`
        break;
    }
    return 0;
}
