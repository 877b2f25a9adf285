// ugvsense listen TOPIC: field debugging of the DDS bus. Subscribes to one of our topics with the topic's own QoS
// (ipc/include/ugv/ipc/dds_bus.hpp) and prints every sample as one JSON line with all its fields on stdout;
// samples that ipc::dds::check() refuses, and on a secured bus those naming a sender other than their writer, go to
// stderr as "refused: <reason>" and are counted. Progress and the
// summary go to stderr too, so stdout stays pure JSON lines (pipe it into jq).

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "ugv/ipc/dds_bus.hpp"
#include "ugv/ipc/dds_convert.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/bus_options.hpp"
#include "ugv/tool/commands.hpp"

namespace ugv::tool {
namespace {

namespace dds = ipc::dds;
namespace msg = ipc::dds::msg;
namespace ros = ipc::dds::ros;
namespace graph = ipc::dds::graph;
using nlohmann::ordered_json;

constexpr const char* kListenCommand = "listen";
constexpr double kMaxCount = 1e12;
constexpr double kMaxTimeoutS = 1e7;
constexpr auto kPollSlice = std::chrono::milliseconds(100); ///< how quickly SIGINT and --timeout are noticed
constexpr std::uint8_t kPointFieldFloat32 = 7;              ///< sensor_msgs/PointField FLOAT32

/// JSON has no NaN or infinity (nlohmann would write null): those become the strings "nan", "inf", "-inf",
/// which keeps a LaserScan's clear rays (+inf) apart from its unknown ones (NaN).
ordered_json num(double v)
{
    if (std::isnan(v)) {
        return "nan";
    }
    if (std::isinf(v)) {
        return v > 0 ? "inf" : "-inf";
    }
    return v;
}

/// A float as its shortest decimal (0.1F prints as 0.1, not as 0.10000000149011612).
ordered_json num(float v)
{
    if (!std::isfinite(v)) {
        return num(static_cast<double>(v));
    }
    char text[32];
    const auto r = std::to_chars(text, text + sizeof(text), v);
    double d = static_cast<double>(v);
    std::from_chars(text, r.ptr, d);
    return d;
}

/// "2 s", "0.5 s".
std::string seconds(double s)
{
    char text[32];
    (void)std::snprintf(text, sizeof(text), "%g s", s);
    return text;
}

template <std::size_t N>
std::string str(const eprosima::fastrtps::fixed_string<N>& s)
{
    return s.to_string();
}

ordered_json toJson(const msg::VehiclePose& s)
{
    ordered_json cov = ordered_json::array();
    for (double c : s.covariance()) {
        cov.push_back(num(c));
    }
    return {{"vehicle", str(s.vehicle())},           {"stamp_ns", s.stamp_ns()},
            {"latitude_deg", num(s.latitude_deg())}, {"longitude_deg", num(s.longitude_deg())},
            {"altitude_m", num(s.altitude_m())},     {"east_m", num(s.east_m())},
            {"north_m", num(s.north_m())},           {"up_m", num(s.up_m())},
            {"heading_deg", num(s.heading_deg())},   {"covariance", cov}};
}

ordered_json toJson(const msg::ObstacleSectors& s)
{
    ordered_json sectors = ordered_json::array();
    for (const msg::Sector& x : s.sectors()) {
        sectors.push_back({{"bearing_min_deg", num(x.bearing_min_deg())},
                           {"bearing_max_deg", num(x.bearing_max_deg())},
                           {"range_m", num(x.range_m())},
                           {"height_m", num(x.height_m())},
                           {"confidence", num(x.confidence())},
                           {"state", x.state()},
                           {"kind", x.kind()},
                           {"danger", x.danger()}});
    }
    const msg::GroundEstimate& g = s.ground();
    return {{"vehicle", str(s.vehicle())},
            {"sequence_number", s.sequence_number()},
            {"capture_stamp_ns", s.capture_stamp_ns()},
            {"publish_stamp_ns", s.publish_stamp_ns()},
            {"pose_valid", s.pose_valid()},
            {"pose_stale", s.pose_stale()},
            {"pose", toJson(s.pose())},
            {"ground",
             {{"reliable", g.reliable()},
              {"pitch_deg", num(g.pitch_deg())},
              {"roll_deg", num(g.roll_deg())},
              {"camera_height_m", num(g.camera_height_m())}}},
            {"degraded", s.degraded()},
            {"sectors", sectors}};
}

ordered_json toJson(const msg::ServiceHealth& s)
{
    return {{"vehicle", str(s.vehicle())},
            {"stamp_ns", s.stamp_ns()},
            {"latency_p50_ms", num(s.latency_p50_ms())},
            {"latency_p90_ms", num(s.latency_p90_ms())},
            {"latency_p99_ms", num(s.latency_p99_ms())},
            {"latency_max_ms", num(s.latency_max_ms())},
            {"frames_captured", s.frames_captured()},
            {"frames_processed", s.frames_processed()},
            {"frames_dropped", s.frames_dropped()},
            {"camera_gaps", s.camera_gaps()},
            {"deadline_misses", s.deadline_misses()},
            {"degraded_frames", s.degraded_frames()},
            {"camera_reconnects", s.camera_reconnects()},
            {"camera_state", s.camera_state()},
            {"bus_drops", s.bus_drops()},
            {"rejected_messages", s.rejected_messages()}};
}

ordered_json toJson(const msg::OoiObservation& s)
{
    return {{"ugv", str(s.ugv())},
            {"sequence_number", s.sequence_number()},
            {"t", num(s.t())},
            {"track", str(s.track())},
            {"cls", s.cls()},
            {"ugv_lat_deg", num(s.ugv_lat_deg())},
            {"ugv_lon_deg", num(s.ugv_lon_deg())},
            {"ugv_heading_deg", num(s.ugv_heading_deg())},
            {"range_m", num(s.range_m())},
            {"bearing_deg", num(s.bearing_deg())}};
}

ordered_json toJson(const msg::UavObservation& s)
{
    return {{"source", str(s.source())},
            {"sequence_number", s.sequence_number()},
            {"t", num(s.t())},
            {"cls", s.cls()},
            {"lat_deg", num(s.lat_deg())},
            {"lon_deg", num(s.lon_deg())}};
}

ordered_json toJson(const msg::ConfirmationState& s)
{
    return {{"source", str(s.source())},
            {"sequence_number", s.sequence_number()},
            {"t", num(s.t())},
            {"id", str(s.id())},
            {"state", s.state()}};
}

ordered_json toJson(const msg::PoseCorrection& s)
{
    return {{"source", str(s.source())},
            {"sequence_number", s.sequence_number()},
            {"t", num(s.t())},
            {"ugv", str(s.ugv())},
            {"since_t", num(s.since_t())},
            {"until_t", num(s.until_t())},
            {"d_east_m", num(s.d_east_m())},
            {"d_north_m", num(s.d_north_m())},
            {"d_heading_deg", num(s.d_heading_deg())}};
}

ordered_json toJson(const msg::CorrelatedOoiList& s)
{
    ordered_json objects = ordered_json::array();
    for (const msg::CorrelatedOoi& o : s.objects()) {
        ordered_json ugvs = ordered_json::array();
        for (const auto& u : o.ugvs()) {
            ugvs.push_back(str(u));
        }
        objects.push_back({{"id", str(o.id())},
                           {"cls", o.cls()},
                           {"lat_deg", num(o.lat_deg())},
                           {"lon_deg", num(o.lon_deg())},
                           {"sigma_major_m", num(o.sigma_major_m())},
                           {"sigma_minor_m", num(o.sigma_minor_m())},
                           {"major_axis_deg", num(o.major_axis_deg())},
                           {"state", o.state()},
                           {"observations", o.observations()},
                           {"ugvs", ugvs},
                           {"zone_diameter_m", num(o.zone_diameter_m())}});
    }
    ordered_json alerts = ordered_json::array();
    for (const msg::Alert& a : s.alerts()) {
        alerts.push_back({{"non_combatant_id", str(a.non_combatant_id())},
                          {"object_id", str(a.object_id())},
                          {"distance_m", num(a.distance_m())}});
    }
    return {{"source", str(s.source())},
            {"sequence_number", s.sequence_number()},
            {"t", num(s.t())},
            {"inputs_accepted", s.inputs_accepted()},
            {"inputs_rejected", s.inputs_rejected()},
            {"objects", objects},
            {"alerts", alerts}};
}

ordered_json toJson(const std_msgs::msg::dds_::Header_& h)
{
    return {{"stamp", {{"sec", h.stamp().sec()}, {"nanosec", h.stamp().nanosec()}}}, {"frame_id", h.frame_id()}};
}

ordered_json toJson(const ros::LaserScan_& s)
{
    ordered_json ranges = ordered_json::array();
    for (float r : s.ranges()) {
        ranges.push_back(num(r));
    }
    ordered_json intensities = ordered_json::array();
    for (float i : s.intensities()) {
        intensities.push_back(num(i));
    }
    return {{"header", toJson(s.header())},
            {"angle_min", num(s.angle_min())},
            {"angle_max", num(s.angle_max())},
            {"angle_increment", num(s.angle_increment())},
            {"time_increment", num(s.time_increment())},
            {"scan_time", num(s.scan_time())},
            {"range_min", num(s.range_min())},
            {"range_max", num(s.range_max())},
            {"ranges", ranges},
            {"intensities", intensities}};
}

/// The points of a little-endian x, y, z FLOAT32 cloud (ours); empty for any other layout.
ordered_json decodedPoints(const ros::PointCloud2_& s)
{
    ordered_json points = ordered_json::array();
    const auto& f = s.fields();
    const bool xyz = f.size() >= 3 && f[0].name() == "x" && f[1].name() == "y" && f[2].name() == "z" &&
                     f[0].offset() == 0 && f[1].offset() == 4 && f[2].offset() == 8 &&
                     f[0].datatype() == kPointFieldFloat32 && f[1].datatype() == kPointFieldFloat32 &&
                     f[2].datatype() == kPointFieldFloat32 && !s.is_bigendian() && s.point_step() >= 12;
    if (!xyz) {
        return points;
    }
    for (std::size_t at = 0; at + 12 <= s.data().size(); at += s.point_step()) {
        float p[3];
        std::memcpy(p, s.data().data() + at, sizeof(p));
        points.push_back({num(p[0]), num(p[1]), num(p[2])});
    }
    return points;
}

ordered_json toJson(const ros::PointCloud2_& s)
{
    ordered_json fields = ordered_json::array();
    for (const ros::PointField_& f : s.fields()) {
        fields.push_back(
            {{"name", f.name()}, {"offset", f.offset()}, {"datatype", f.datatype()}, {"count", f.count()}});
    }
    static constexpr char kHex[] = "0123456789abcdef";
    std::string hex;
    hex.reserve(2 * s.data().size());
    for (std::uint8_t b : s.data()) {
        hex.push_back(kHex[b >> 4]);
        hex.push_back(kHex[b & 0xF]);
    }
    return {{"header", toJson(s.header())},
            {"height", s.height()},
            {"width", s.width()},
            {"fields", fields},
            {"is_bigendian", s.is_bigendian()},
            {"point_step", s.point_step()},
            {"row_step", s.row_step()},
            {"data", hex},
            {"is_dense", s.is_dense()},
            {"points", decodedPoints(s)}};
}

std::string hex(const graph::Gid_& gid)
{
    static constexpr char kHex[] = "0123456789abcdef";
    std::string out;
    for (std::uint8_t b : gid.data()) {
        out.push_back(kHex[b >> 4]);
        out.push_back(kHex[b & 0xF]);
    }
    return out;
}

ordered_json toJson(const graph::ParticipantEntitiesInfo_& s)
{
    ordered_json nodes = ordered_json::array();
    for (const graph::NodeEntitiesInfo_& n : s.node_entities_info_seq()) {
        ordered_json readers = ordered_json::array();
        ordered_json writers = ordered_json::array();
        for (const graph::Gid_& g : n.reader_gid_seq()) {
            readers.push_back(hex(g));
        }
        for (const graph::Gid_& g : n.writer_gid_seq()) {
            writers.push_back(hex(g));
        }
        nodes.push_back({{"node_namespace", str(n.node_namespace())},
                         {"node_name", str(n.node_name())},
                         {"reader_gids", readers},
                         {"writer_gids", writers}});
    }
    return {{"gid", hex(s.gid())}, {"nodes", nodes}};
}

struct ListenOptions {
    std::uint64_t count = 0; ///< 0: no limit
    double timeoutS = 0.0;   ///< 0: none
};

/// Prints the samples of T on its topic (or `id`, a topic of the same type) until --count, --timeout or a signal.
/// The exit code of the command.
template <class T>
int listenTo(dds::Bus& bus, const ListenOptions& o, dds::TopicId id = dds::TopicOf<T>::id)
{
    const std::string topic = dds::topicName(id, bus.config());
    auto reader = bus.reader<T>(id);
    if (!reader) {
        return reportError(kListenCommand, reader.error());
    }
    std::cerr << "listening to " << topic << " on " << bus::describe(bus.config())
              << (o.count > 0 ? ", for " + std::to_string(o.count) + " sample(s)" : std::string())
              << (o.timeoutS > 0.0 ? ", at most " + seconds(o.timeoutS) : std::string()) << " (Ctrl-C to stop)\n";
    const auto start = std::chrono::steady_clock::now();
    const auto deadline = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(o.timeoutS));
    std::uint64_t printed = 0;
    std::uint64_t refused = 0;
    bool timedOut = false;
    T sample;
    eprosima::fastdds::dds::SampleInfo info;
    const bool secured = bus.config().security.enabled;
    bool rejoin = secured; // while nothing came, until joining again fails (said once)
    while (!gStop.load() && (o.count == 0 || printed < o.count)) {
        bus::followNetworkChanges(bus);
        if (rejoin && printed + refused == 0 && bus::rejoinIfStalled(bus, kListenCommand) == bus::Rejoin::Failed) {
            rejoin = false;
        }
        auto slice = kPollSlice;
        if (o.timeoutS > 0.0) {
            const auto now = std::chrono::steady_clock::now();
            if (now >= deadline) {
                timedOut = true;
                break;
            }
            slice = std::min(slice, std::chrono::ceil<std::chrono::milliseconds>(deadline - now));
        }
        if (!reader->wait(slice)) {
            continue;
        }
        while ((o.count == 0 || printed < o.count) && reader->take(sample, &info)) {
            if (const char* why = dds::check(sample)) {
                ++refused;
                std::cerr << "refused: " << why << '\n';
                continue;
            }
            if (const std::string claimed = dds::sender(sample); secured && !claimed.empty()) {
                if (const std::string writer = bus.writerIdentity(info); writer != claimed) {
                    ++refused;
                    std::cerr << "refused: a sample naming '" << claimed << "' written by '"
                              << (writer.empty() ? std::string("an undiscovered writer") : writer)
                              << "' (on a secured bus a participant may send only in its own name)\n";
                    continue;
                }
            }
            std::cout << toJson(sample).dump() << '\n';
            std::cout.flush(); // one line at a time into a pipe or a file that another process watches
            ++printed;
        }
    }
    const double elapsedS = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    (void)std::fprintf(stderr, "ugvsense %s: %llu sample(s) printed, %llu refused, in %.1f s%s\n", kListenCommand,
                       static_cast<unsigned long long>(printed), static_cast<unsigned long long>(refused), elapsedS,
                       gStop.load() ? " (stopped by a signal)" : "");
    if (timedOut && printed == 0) {
        const int writers = reader->matched();
        return reportError(kListenCommand,
                           Error{topic + " on " + bus::describe(bus.config()),
                                 "nothing arrived in " + seconds(o.timeoutS) + " (" + std::to_string(writers) +
                                     " publisher(s) matched, " + std::to_string(refused) + " sample(s) refused)",
                                 writers == 0
                                     ? "check that the publisher runs, on the same domain (--domain, "
                                       "$UGV_DDS_DOMAIN) and partition (--partition), and that discovery reaches "
                                       "it (multicast, or --discovery-server)"
                                     : "a publisher is there but sent nothing valid: check that it publishes "
                                       "now, and its QoS (ugvsense listen uses the topic's own)"});
    }
    return 0;
}

/// Prints the samples of topic `id` (see listenTo).
int listenOn(dds::Bus& b, dds::TopicId id, const ListenOptions& o)
{
    switch (id) {
    case dds::TopicId::Sectors:
        return listenTo<msg::ObstacleSectors>(b, o);
    case dds::TopicId::Health:
        return listenTo<msg::ServiceHealth>(b, o);
    case dds::TopicId::Pose:
        return listenTo<msg::VehiclePose>(b, o);
    case dds::TopicId::Observation:
        return listenTo<msg::OoiObservation>(b, o);
    case dds::TopicId::Uav:
        return listenTo<msg::UavObservation>(b, o);
    case dds::TopicId::Confirmation:
        return listenTo<msg::ConfirmationState>(b, o);
    case dds::TopicId::PoseCorrection:
        return listenTo<msg::PoseCorrection>(b, o);
    case dds::TopicId::Correlated:
        return listenTo<msg::CorrelatedOoiList>(b, o);
    case dds::TopicId::RosScan:
        return listenTo<ros::LaserScan_>(b, o);
    case dds::TopicId::RosNegatives:
        return listenTo<ros::PointCloud2_>(b, o);
    case dds::TopicId::RosGraph:
        return listenTo<graph::ParticipantEntitiesInfo_>(b, o);
    case dds::TopicId::RosClearScan:
        return listenTo<ros::LaserScan_>(b, o, id);
    }
    return reportError(kListenCommand, Error{std::string("ugvsense ") + kListenCommand, "topic without a listener",
                                             "a bug: add it to listenOn"});
}

} // namespace

int runListen(int argc, char** argv)
{
    std::vector<OptionSpec> specs{
        {"count", "N", "stop after N samples printed (exit 0), default no limit", false},
        {"timeout", "S", "stop after S seconds: exit 0 if a sample was printed, else 1", false}};
    for (auto& spec : bus::options()) {
        specs.push_back(std::move(spec));
    }
    Args args(
        kListenCommand,
        "TOPIC [--count N] [--timeout S] [--domain N] [--partition P] [--ros-namespace NS] "
        "[--discovery-server LIST]\n"
        "  Subscribes to one topic of the DDS bus with the topic's QoS and prints every sample as one JSON\n"
        "  line with all its fields on stdout (NaN and infinities as the strings \"nan\", \"inf\", \"-inf\";\n"
        "  a PointCloud2's data as hex plus its decoded x, y, z \"points\"). Samples failing the checks the\n"
        "  service applies (on a secured bus: a sample naming a sender other than the participant that wrote it)\n"
        "  go to stderr as 'refused: <reason>' and are counted; the summary goes to stderr.\n"
        "  Stops after --count samples, after --timeout seconds, or on Ctrl-C.\n\n"
        "  TOPIC: sectors, health, pose, observations, uav, confirmations, pose_corrections, correlated, scan,\n"
        "  negatives, clear_scan (the scan for clearing: range_max is the clear range), ros_discovery (ROS 2's\n"
        "  graph: which nodes each participant holds), or a wire name\n"
        "  (ugvsense/ooi/observations, rt/NS/obstacle_scan, ros_discovery_info, ...)",
        specs);
    if (const auto exit = parseOrExit(args, argc, argv, kListenCommand, Positionals::Allowed)) {
        return *exit;
    }
    const std::string where = std::string("ugvsense ") + kListenCommand;
    if (args.positional().size() != 1) {
        return reportUsageError(
            kListenCommand,
            Error{where,
                  args.positional().empty() ? "no TOPIC given" : "more than one TOPIC ('" + args.positional()[1] + "')",
                  "give one, e.g. 'ugvsense listen observations'; see --help"});
    }
    auto config = bus::configFrom(args, kListenCommand, "ugvsense/listen");
    if (!config) {
        return reportUsageError(kListenCommand, config.error());
    }
    dds::TopicId id{};
    if (!dds::parseTopic(args.positional()[0], *config, id)) {
        std::string names;
        for (int i = 0; i < dds::kTopicCount; ++i) {
            names += (i == 0 ? "" : ", ") + std::string(dds::shortName(static_cast<dds::TopicId>(i)));
        }
        return reportUsageError(kListenCommand,
                                Error{where, "unknown topic '" + args.positional()[0] + "'", "use one of " + names});
    }
    const auto count = args.number("count", 0, 1, kMaxCount);
    const auto timeout = args.number("timeout", 0, 0.001, kMaxTimeoutS);
    if (!count || !timeout) {
        return reportUsageError(kListenCommand, !count ? count.error() : timeout.error());
    }
    if (std::floor(*count) != *count) {
        return reportUsageError(
            kListenCommand, Error{where + " --count", "bad value '" + args.get("count") + "'", "give a whole number"});
    }
    ListenOptions o;
    o.count = static_cast<std::uint64_t>(*count);
    o.timeoutS = *timeout;

    installStopHandler();
    auto created = dds::Bus::create(*config);
    if (!created) {
        return reportError(kListenCommand, created.error());
    }
    return listenOn(**created, id, o);
}

} // namespace ugv::tool
