#include "ugv/ipc/dds_bus.hpp"

#include "ugv/ipc/handshake_watch.hpp"
#include "ugv/platform/log.hpp"

#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <unordered_map>
#include <utility>
#include <vector>

#include <openssl/pem.h>
#include <openssl/x509.h>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/publisher/qos/PublisherQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/subscriber/qos/SubscriberQos.hpp>
#include <fastdds/rtps/attributes/ServerAttributes.h>
#include <fastdds/rtps/builtin/data/WriterProxyData.h>
#include <fastdds/rtps/transport/ChainingTransport.h>
#include <fastdds/rtps/transport/ChainingTransportDescriptor.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>

namespace ugv::ipc::dds {

namespace fdds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

namespace {

struct TopicSpec {
    const char* shortName;
    const char* suffix; ///< our topics and ROS 2's graph: the whole name; ROS 2 ones: after rt/<ns>/
    bool ros;           ///< in the default partition (the only one ROS 2 reads)
    bool reliable;      ///< the readers'; writers: reliable, or for ROS 2 topics BusConfig::rosReliable
    bool transientLocal;
    bool keepAll;
    int depth;          ///< keep-last depth
    bool graph = false; ///< ROS 2's own graph topic: not namespaced, its QoS fixed by rmw
};

// Why these QoS (ipc/README.md): sensor-like streams are best effort, keep last 1 (a late sample is worse than
// none; a consumer wants the newest); the correlator's inputs must all arrive and be replayed to a late or
// restarted ground station (reliable, transient local, keep all); states (health, the correlated list) reach a
// late joiner as their latest value (transient local, keep last 1). Writers are reliable (it matches every reader;
// why for best-effort topics: Bus::makeWriter), the ROS 2 ones as BusConfig::rosReliable says.
constexpr std::array<TopicSpec, kTopicCount> kTopics{{
    {"sectors", "ugvsense/sectors", false, false, false, false, 1},
    {"health", "ugvsense/health", false, true, true, false, 1},
    {"pose", "ugvsense/pose", false, false, false, false, 8},
    {"observations", "ugvsense/ooi/observations", false, true, true, true, 0},
    {"uav", "ugvsense/ooi/uav", false, true, true, true, 0},
    {"confirmations", "ugvsense/ooi/confirmations", false, true, true, true, 0},
    {"pose_corrections", "ugvsense/ooi/pose_corrections", false, true, true, true, 0},
    {"correlated", "ugvsense/ooi/correlated", false, true, true, false, 1},
    {"scan", "obstacle_scan", true, false, false, false, 1},
    {"negatives", "negative_obstacles", true, false, false, false, 1},
    {"ros_discovery", "ros_discovery_info", true, true, true, false, 1, true},
    {"clear_scan", "clear_scan", true, false, false, false, 1},
}};

/// Keep-all histories are bounded too: a writer whose readers do not acknowledge blocks (up to its
/// max_blocking_time) and then refuses the sample, counted by the caller; memory stays bounded.
constexpr int kKeepAllMaxSamples = 100'000;

const TopicSpec& spec(TopicId id)
{
    return kTopics[static_cast<std::size_t>(id)];
}

template <class Qos>
void applyCommon(Qos& q, const TopicSpec& s)
{
    // No data-sharing delivery (Fast DDS's default AUTO enables it between processes of one host for our bounded
    // types). In 2.9.1 a late-joining reader of a keep-all transient-local writer's data-sharing history could spin
    // at 100 % CPU in DataSharingListener::process_new_data() and then hang forever when deleted (found by
    // `ugvsense listen observations --count 1`, about 1 run in 12 against a writer with a few hundred samples).
    // Same-host traffic still goes through the shared-memory transport.
    q.data_sharing().off();
    q.reliability().kind = s.reliable ? fdds::RELIABLE_RELIABILITY_QOS : fdds::BEST_EFFORT_RELIABILITY_QOS;
    q.durability().kind = s.transientLocal ? fdds::TRANSIENT_LOCAL_DURABILITY_QOS : fdds::VOLATILE_DURABILITY_QOS;
    if (s.keepAll) {
        q.history().kind = fdds::KEEP_ALL_HISTORY_QOS;
        q.resource_limits().max_samples = kKeepAllMaxSamples;
        q.resource_limits().max_instances = 1;
        q.resource_limits().max_samples_per_instance = kKeepAllMaxSamples;
    } else {
        q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
        q.history().depth = s.depth;
    }
}

Result<void, Error> parseServers(const std::string& list, rtps::RemoteServerList_t& out, const std::string& where)
{
    if (!eprosima::fastdds::rtps::load_environment_server_info(list, out) || out.empty()) {
        return Unexpected(
            Error{where, "bad discovery server list '" + list + "'",
                  "write IP:PORT[;IP:PORT...], e.g. 192.168.1.10:11811, or leave it empty for multicast"});
    }
    return {};
}

constexpr std::uintmax_t kMaxSecurityFileBytes = 1U << 20U;
constexpr const char* kSecurityFix =
    "make the files with bringup/deploy/security/make_security.sh (README \"Secured bus\")";

/// The subject of the CA certificate in PEM file `path`, in the form Fast DDS 2.9.1's PKI-DH announces it in a
/// participant's identity token (`dds.ca.sn`: OpenSSL's one-line form, e.g. "/CN=ugvsense team CA 0123456789abcdef").
Result<std::string, Error> caSubject(const std::string& path, const std::string& where)
{
    const Error bad{where, "cannot read a certificate from '" + path + "'", kSecurityFix};
    std::unique_ptr<BIO, decltype(&BIO_free)> file(BIO_new_file(path.c_str(), "r"), &BIO_free);
    if (!file) {
        return Unexpected(bad);
    }
    std::unique_ptr<X509, decltype(&X509_free)> cert(PEM_read_bio_X509(file.get(), nullptr, nullptr, nullptr),
                                                     &X509_free);
    char* line = cert ? X509_NAME_oneline(X509_get_subject_name(cert.get()), nullptr, 0) : nullptr;
    if (line == nullptr) {
        return Unexpected(bad);
    }
    std::string subject(line);
    OPENSSL_free(line);
    return subject;
}

/// The Fast DDS properties that load the three builtin security plugins with `c`'s files.
void addSecurityProperties(const SecurityConfig& c, fdds::DomainParticipantQos& pq)
{
    const auto uri = [](const std::string& path) { return "file://" + std::filesystem::absolute(path).string(); };
    auto& p = pq.properties().properties();
    p.emplace_back("dds.sec.auth.plugin", "builtin.PKI-DH");
    p.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_ca", uri(c.identityCa));
    p.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_certificate", uri(c.certificate));
    p.emplace_back("dds.sec.auth.builtin.PKI-DH.private_key", uri(c.privateKey));
    p.emplace_back("dds.sec.access.plugin", "builtin.Access-Permissions");
    p.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions_ca", uri(c.permissionsCa));
    p.emplace_back("dds.sec.access.builtin.Access-Permissions.governance", uri(c.governance));
    p.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions", uri(c.permissions));
    p.emplace_back("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
}

/// A transport with the messages of refused participants dropped on arrival (RefusedPrefixes: Fast DDS 2.9.1 leaks
/// memory on every handshake request of a refused participant it answers). A message's RTPS header carries its
/// sender's GUID prefix in clear at bytes 8-19, whatever the protection.
class RefusedFilterTransport : public eprosima::fastdds::rtps::ChainingTransport {
public:
    RefusedFilterTransport(const eprosima::fastdds::rtps::ChainingTransportDescriptor& descriptor,
                           std::shared_ptr<const RefusedPrefixes> refused)
        : ChainingTransport(descriptor), refused_(std::move(refused))
    {
    }
    eprosima::fastdds::rtps::TransportDescriptorInterface* get_configuration() override
    {
        return low_level_transport_->get_configuration();
    }
    bool send(rtps::SenderResource* low, const rtps::octet* buffer, std::uint32_t size, rtps::LocatorsIterator* begin,
              rtps::LocatorsIterator* end, const std::chrono::steady_clock::time_point& timeout) override
    {
        return low->send(buffer, size, begin, end, timeout);
    }
    void receive(eprosima::fastdds::rtps::TransportReceiverInterface* next, const rtps::octet* buffer,
                 std::uint32_t size, const rtps::Locator_t& local, const rtps::Locator_t& remote) override
    {
        constexpr std::uint32_t kPrefixAt = 8; // "RTPS", version (2), vendor (2), then the GUID prefix
        if (size >= kPrefixAt + RefusedPrefixes::kPrefixBytes && refused_->drop(buffer + kPrefixAt)) {
            return;
        }
        next->OnDataReceived(buffer, size, local, remote);
    }

private:
    std::shared_ptr<const RefusedPrefixes> refused_;
};

/// `low` (UDPv4) through the filter.
struct RefusedFilterDescriptor : eprosima::fastdds::rtps::ChainingTransportDescriptor {
    RefusedFilterDescriptor(std::shared_ptr<eprosima::fastdds::rtps::TransportDescriptorInterface> low,
                            std::shared_ptr<const RefusedPrefixes> refusedPrefixes)
        : ChainingTransportDescriptor(std::move(low)), refused(std::move(refusedPrefixes))
    {
    }
    eprosima::fastdds::rtps::TransportInterface* create_transport() const override
    {
        return new RefusedFilterTransport(*this, refused); // owned by Fast DDS's network factory
    }
    std::shared_ptr<const RefusedPrefixes> refused;
};

/// The participant's QoS: name, transports (UDP through the filter of `refused` when given), discovery servers, the
/// security plugins.
Result<fdds::DomainParticipantQos, Error> participantQos(const BusConfig& config,
                                                         const std::shared_ptr<const RefusedPrefixes>& refused)
{
    fdds::DomainParticipantQos pq = fdds::PARTICIPANT_QOS_DEFAULT;
    pq.name(config.participantName);
    // A ROS 2 participant's user data names its security enclave (rmw_fastrtps: "enclave=/;"); ROS 2 tools show a
    // participant's nodes with it.
    const std::string enclave = "enclave=/;";
    pq.user_data().data_vec(std::vector<rtps::octet>(enclave.begin(), enclave.end()));
    pq.transport().use_builtin_transports = false;
    // Shared memory is not filtered: chained behind the filter (a ChainingTransport behind a descriptor of the
    // shared-memory type, by which Fast DDS 2.9.1 tells that transport), it made the secured hand-over's p99 2.5 times
    // as long (bench-dds InTurns, 2026-12-07), while the filter there only spares the leak of a refused participant
    // on this very computer.
    if (config.sharedMemory) {
        pq.transport().user_transports.push_back(
            std::make_shared<eprosima::fastdds::rtps::SharedMemTransportDescriptor>());
    }
    if (refused) {
        pq.transport().user_transports.push_back(std::make_shared<RefusedFilterDescriptor>(
            std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>(), refused));
    } else {
        pq.transport().user_transports.push_back(std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>());
    }
    if (!config.discoveryServers.empty()) {
        rtps::RemoteServerList_t servers;
        if (auto ok = parseServers(config.discoveryServers, servers, "dds discovery_server"); !ok) {
            return Unexpected(ok.error());
        }
        auto& discovery = pq.wire_protocol().builtin.discovery_config;
        discovery.discoveryProtocol = rtps::DiscoveryProtocol_t::CLIENT;
        discovery.m_DiscoveryServers = servers;
    }
    if (config.security.enabled) {
        addSecurityProperties(config.security, pq);
    }
    return pq;
}

/// Our topics' partitions: as configured on an open bus; on a secured one written in `<p>.<identity>` (the only
/// one the participant's permissions allow it) and read in `<p>.*` (every participant's).
void applyPartitions(const BusConfig& config, fdds::PublisherQos& pubq, fdds::SubscriberQos& subq)
{
    if (!config.security.enabled) {
        for (const std::string& p : config.partitions) {
            pubq.partition().push_back(p.c_str());
            subq.partition().push_back(p.c_str());
        }
        return;
    }
    const std::vector<std::string> team = config.partitions.empty() ? std::vector<std::string>{""} : config.partitions;
    for (const std::string& p : team) {
        const std::string prefix = p.empty() ? std::string() : p + ".";
        pubq.partition().push_back((prefix + config.security.identity).c_str());
        subq.partition().push_back((prefix + "*").c_str());
    }
}

} // namespace

/// The secured bus's discovery listener. Writer GUID -> the identity of its partition (the part after the last '.'),
/// filled from discovery (on a secured bus only authenticated participants' writers are discovered, and their
/// partitions were checked against their signed permissions), and the handshakes that never ended (HandshakeWatch).
/// Thread-safe: written by Fast DDS's discovery thread, read by the bus's users; plain mutexes, as no real-time task
/// reads them (the correlator task is SCHED_OTHER).
class WriterIdentities : public fdds::DomainParticipantListener {
public:
    /// @param[in] caSubject  the subject of this team's identity CA, as peers of the team announce it (caSubject())
    explicit WriterIdentities(std::string caSubject) : caSubject_(std::move(caSubject)) {}

    /// The participants refused, for the UDP transport's filter.
    const std::shared_ptr<RefusedPrefixes> refused = std::make_shared<RefusedPrefixes>();
    std::atomic<std::uint64_t> refusals{0}; ///< refusals Fast DDS reported (each retry of a refused one counts)
    /// Participants refused as they were discovered: naming another CA than this team's (one naming none is not).
    std::atomic<std::uint64_t> refusedAtDiscovery{0};

    void on_participant_discovery(fdds::DomainParticipant* participant,
                                  eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override
    {
        using Status = eprosima::fastrtps::rtps::ParticipantDiscoveryInfo;
        const std::string local = prefixKey(participant->guid().guidPrefix);
        const std::string remote = prefixKey(info.info.m_guid.guidPrefix);
        if (info.status == Status::DISCOVERED_PARTICIPANT) {
            // The identity token a peer announces names its CA (an open participant's names none).
            const auto& token = info.info.identity_token_.properties();
            const auto ca = std::find_if(token.begin(), token.end(),
                                         [](const rtps::Property& p) { return p.name() == "dds.ca.sn"; });
            const bool sameCa = ca != token.end() && ca->value() == caSubject_;
            handshakes.discovered(local, remote, HandshakeWatch::Clock::now(), sameCa);
            if (ca != token.end() && !sameCa) {
                // Its certificate cannot be of this team's CA, so its handshake would be refused, and Fast DDS 2.9.1
                // leaks the certificate of every handshake request it refuses: its messages are dropped from now on,
                // before any handshake. A peer that names no CA is left to the handshake: an open participant sends
                // no handshake request, and a Cyclone DDS participant (a ROS 2 node) of the team names none here
                // (measured: system.cyclone-interop-secured).
                refusedAtDiscovery.fetch_add(1, std::memory_order_relaxed);
                refused->add(info.info.m_guid.guidPrefix.value);
                refuse(info.info.m_guid.guidPrefix, "it names another identity CA, '" + ca->value() + "'");
            }
        } else if (info.status == Status::REMOVED_PARTICIPANT || info.status == Status::DROPPED_PARTICIPANT) {
            handshakes.removed(local, remote);
        }
    }
    void onParticipantAuthentication(fdds::DomainParticipant* participant,
                                     eprosima::fastrtps::rtps::ParticipantAuthenticationInfo&& info) override
    {
        handshakes.ended(prefixKey(participant->guid().guidPrefix), prefixKey(info.guid.guidPrefix));
        if (info.status == eprosima::fastrtps::rtps::ParticipantAuthenticationInfo::UNAUTHORIZED_PARTICIPANT) {
            refusals.fetch_add(1, std::memory_order_relaxed);
            refused->add(info.guid.guidPrefix.value);
            refuse(info.guid.guidPrefix, "it has no certificate (DDS Security off), or one this team's identity CA "
                                         "did not sign, or its signed permissions refuse it");
        }
    }
    void on_publisher_discovery(fdds::DomainParticipant* /*participant*/,
                                eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override
    {
        // A removed writer is kept: its last samples may still wait in a reader (one entry per writer ever seen,
        // a few per process start).
        const std::string key = guidKey(info.info.guid());
        std::lock_guard<std::mutex> lock(mutex_);
        const auto names = info.info.m_qos.m_partition.names();
        const std::string first = names.empty() ? std::string() : names.front();
        byWriter_[key] = first.substr(first.find_last_of('.') + 1);
    }
    std::string identity(const rtps::GUID_t& writer) const
    {
        std::lock_guard<std::mutex> lock(mutex_);
        const auto it = byWriter_.find(guidKey(writer));
        return it == byWriter_.end() ? std::string() : it->second;
    }

    static std::string prefixKey(const rtps::GuidPrefix_t& p)
    {
        return {reinterpret_cast<const char*>(p.value), sizeof(p.value)};
    }
    static std::string prefixHex(const rtps::GuidPrefix_t& p)
    {
        static constexpr char kHex[] = "0123456789abcdef";
        std::string out;
        for (const auto byte : p.value) {
            out += kHex[byte >> 4U];
            out += kHex[byte & 0xFU];
        }
        return out;
    }

    HandshakeWatch handshakes; ///< the secured handshakes that never ended

private:
    static constexpr std::size_t kRefusalsNamed = 10;
    /// Each refused participant is news to an operator (an intruder, or a team member with wrong files), but a
    /// flood must not flood the journal: the first few participants are named once each (Fast DDS tries a refused
    /// one again and again), the rest not.
    void refuse(const rtps::GuidPrefix_t& who, const std::string& why)
    {
        const std::string key = prefixKey(who);
        bool last = false;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            if (named_.size() >= kRefusalsNamed || std::find(named_.begin(), named_.end(), key) != named_.end()) {
                return;
            }
            named_.push_back(key);
            last = named_.size() == kRefusalsNamed;
        }
        UGV_LOG(Ipc, Warn) << "dds: refused participant " << prefixHex(who) << ": " << why
                           << " (if it is the team's, give it this team's files from make_security.sh)"
                           << (last ? "; further refused participants are not named" : "");
    }
    static std::string guidKey(const rtps::GUID_t& g)
    {
        return prefixKey(g.guidPrefix)
            .append(reinterpret_cast<const char*>(g.entityId.value), sizeof(g.entityId.value));
    }
    const std::string caSubject_;
    mutable std::mutex mutex_;
    std::unordered_map<std::string, std::string> byWriter_;
    std::vector<std::string> named_; ///< the refused participants named on the log (at most kRefusalsNamed)
};

std::array<SecurityFile, 6> securityFiles(const SecurityConfig& c)
{
    return {
        {{"identity_ca", &c.identityCa, "-----BEGIN CERTIFICATE-----", "the identity CA's certificate (PEM)"},
         {"certificate", &c.certificate, "-----BEGIN CERTIFICATE-----", "this participant's certificate (PEM)"},
         {"private_key", &c.privateKey, "PRIVATE KEY-----", "this participant's private key (PEM)"},
         {"permissions_ca", &c.permissionsCa, "-----BEGIN CERTIFICATE-----", "the permissions CA's certificate (PEM)"},
         {"governance", &c.governance, "pkcs7-signature", "the signed governance document (S/MIME)"},
         {"permissions", &c.permissions, "pkcs7-signature", "the signed permissions document (S/MIME)"}}};
}

SecurityConfig securityFromFolder(const std::string& folder, const std::string& identity)
{
    return SecurityConfig{true,
                          folder + "/identity_ca.cert.pem",
                          folder + "/cert.pem",
                          folder + "/key.pem",
                          folder + "/permissions_ca.cert.pem",
                          folder + "/governance.p7s",
                          folder + "/permissions.p7s",
                          identity};
}

Result<void, Error> checkSecurityFile(const SecurityFile& file, const std::string& where)
{
    const std::string& path = *file.path;
    if (path.empty()) {
        return Unexpected(Error{where, "is empty but dds.security.enabled is true",
                                std::string("give the path of ") + file.description + "; " + kSecurityFix});
    }
    // A regular file before anything opens it (a FIFO would block the open).
    std::error_code ec;
    const bool regular = std::filesystem::is_regular_file(path, ec);
    const auto size = regular ? std::filesystem::file_size(path, ec) : 0;
    std::ifstream in;
    if (regular && !ec) {
        in.open(path, std::ios::binary);
    }
    if (!regular || ec || !in) {
        return Unexpected(Error{where, "'" + path + "' cannot be read (missing, not a file, or no permission)",
                                std::string("give ") + file.description + " readable by the service; " + kSecurityFix});
    }
    if (size > kMaxSecurityFileBytes) {
        return Unexpected(Error{where, "'" + path + "' is " + std::to_string(size) + " bytes, not a security file",
                                std::string("give ") + file.description + " (at most 1 MB)"});
    }
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (text.find(file.expected) == std::string::npos) {
        return Unexpected(Error{where,
                                "'" + path + "' is not " + file.description + " (no '" + file.expected + "' in it)",
                                std::string("give ") + file.description + "; " + kSecurityFix});
    }
    return {};
}

Result<void, Error> checkSecurity(const SecurityConfig& config, const std::string& where)
{
    if (!config.enabled) {
        return {};
    }
    for (const SecurityFile& f : securityFiles(config)) {
        if (auto ok = checkSecurityFile(f, where + "." + f.key); !ok) {
            return ok;
        }
    }
    return checkIdentity(config.identity, where + " identity");
}

Result<void, Error> checkIdentity(const std::string& id, const std::string& where)
{
    if (id.empty() || id.size() > kMaxNameLength ||
        id.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") != std::string::npos) {
        return Unexpected(Error{where, "'" + id + "' cannot name a partition",
                                "1 to 64 letters, digits, _ and -: the certificate's name (CN), e.g. ugv-1"});
    }
    return {};
}

Result<void, Error> validate(const BusConfig& config, const std::string& where)
{
    if (config.domainId < 0 || config.domainId > kMaxDomainId) {
        return Unexpected(Error{where + " domain_id", "domain id " + std::to_string(config.domainId) + " out of range",
                                "use 0..232 (the same on every vehicle and the ground station)"});
    }
    if (config.participantName.empty() || config.rosNamespace.empty() ||
        config.rosNamespace.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_/") !=
            std::string::npos ||
        config.rosNamespace.front() == '/' || config.rosNamespace.back() == '/') {
        return Unexpected(Error{where + " vehicle", "vehicle name '" + config.rosNamespace + "' is not a ROS 2 name",
                                "letters, digits, _ and inner /, e.g. ugv1"});
    }
    if (config.rosNamespace.size() > kMaxNameLength) {
        return Unexpected(Error{where + " vehicle",
                                "vehicle name of " + std::to_string(config.rosNamespace.size()) + " characters",
                                "at most " + std::to_string(kMaxNameLength) + " (the bus's name bound)"});
    }
    for (const std::string& p : config.partitions) {
        if (p.empty()) {
            return Unexpected(Error{where + " partitions", "an empty partition name", "remove it or name it"});
        }
    }
    if (auto ok = checkSecurity(config.security, where + " security"); !ok) {
        return ok;
    }
    return checkDiscoveryServers(config.discoveryServers, where + " discovery_server");
}

Result<std::optional<int>, Error> domainFromEnvironment(const char* variable)
{
    const char* env = std::getenv(variable);
    if (env == nullptr || *env == '\0') {
        return std::optional<int>();
    }
    const char* const end = env + std::strlen(env);
    int id = -1;
    const auto [stop, error] = std::from_chars(env, end, id);
    if (error != std::errc{} || stop != end || id < 0 || id > kMaxDomainId) {
        return Unexpected(Error{std::string("$") + variable, std::string("'") + env + "' is not a DDS domain id",
                                "give a whole number in 0..232, or unset it"});
    }
    return std::optional<int>(id);
}

Result<void, Error> checkDiscoveryServers(const std::string& list, const std::string& where)
{
    if (list.empty()) {
        return {};
    }
    rtps::RemoteServerList_t servers;
    return parseServers(list, servers, where);
}

std::string topicName(TopicId id, const BusConfig& config)
{
    const TopicSpec& s = spec(id);
    return s.ros && !s.graph ? "rt/" + config.rosNamespace + "/" + s.suffix : std::string(s.suffix);
}

const char* shortName(TopicId id) noexcept
{
    return spec(id).shortName;
}

bool parseTopic(const std::string& name, const BusConfig& config, TopicId& out)
{
    for (int i = 0; i < kTopicCount; ++i) {
        const auto id = static_cast<TopicId>(i);
        if (name == shortName(id) || name == topicName(id, config)) {
            out = id;
            return true;
        }
    }
    return false;
}

namespace {

/// The IPv4 addresses of the interfaces that are up, sorted (loopback too): what Fast DDS reads when it makes its
/// unicast locators. False when the system would not list them.
bool upIpv4Addresses(std::vector<std::uint32_t>& out)
{
    ifaddrs* list = nullptr;
    if (::getifaddrs(&list) != 0) {
        return false;
    }
    out.clear();
    for (const ifaddrs* a = list; a != nullptr; a = a->ifa_next) {
        if (a->ifa_addr != nullptr && a->ifa_addr->sa_family == AF_INET && (a->ifa_flags & IFF_UP) != 0U) {
            sockaddr_in in{};
            std::memcpy(&in, a->ifa_addr, sizeof in);
            out.push_back(in.sin_addr.s_addr);
        }
    }
    ::freeifaddrs(list);
    std::sort(out.begin(), out.end());
    return true;
}

} // namespace

Result<std::unique_ptr<Bus>, Error> Bus::create(const BusConfig& config)
{
    if (auto ok = validate(config, "dds"); !ok) {
        return Unexpected(ok.error());
    }
    std::unique_ptr<Bus> bus(new Bus());
    bus->config_ = config;
    if (config.security.enabled) {
        auto ca = caSubject(config.security.identityCa, "dds.security.identity_ca");
        if (!ca) {
            return Unexpected(ca.error());
        }
        bus->identities_ = std::make_unique<WriterIdentities>(std::move(*ca));
    }
    auto pq = participantQos(config, bus->refusedPrefixes());
    if (!pq) {
        return Unexpected(pq.error());
    }
    upIpv4Addresses(bus->startAddresses_);
    bus->lastAddresses_ = bus->startAddresses_;
    if (auto opened = bus->openParticipant(*pq); !opened) {
        return Unexpected(opened.error());
    }
    return bus;
}

Result<void, Error> Bus::openParticipant(const fdds::DomainParticipantQos& qos)
{
    dds_.participant = fdds::DomainParticipantFactory::get_instance()->create_participant(
        static_cast<fdds::DomainId_t>(config_.domainId), qos, identities_.get(), fdds::StatusMask::none());
    if (dds_.participant == nullptr) {
        return Unexpected(Error{"dds domain " + std::to_string(config_.domainId), "cannot create the DDS participant",
                                config_.security.enabled
                                    ? "check the dds.security files: the certificate signed by the identity CA, "
                                      "the permissions' subject equal to the certificate's, both documents signed "
                                      "by the permissions CA, and the Fast DDS messages above"
                                    : "check the network interfaces, /dev/shm, and the Fast DDS messages above"});
    }
    fdds::PublisherQos pubq = fdds::PUBLISHER_QOS_DEFAULT;
    fdds::SubscriberQos subq = fdds::SUBSCRIBER_QOS_DEFAULT;
    applyPartitions(config_, pubq, subq);
    dds_.publisher = dds_.participant->create_publisher(pubq);
    dds_.subscriber = dds_.participant->create_subscriber(subq);
    dds_.rosPublisher = dds_.participant->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
    dds_.rosSubscriber = dds_.participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    if (dds_.publisher == nullptr || dds_.subscriber == nullptr || dds_.rosPublisher == nullptr ||
        dds_.rosSubscriber == nullptr) {
        return Unexpected(Error{"dds", "cannot create the publishers and subscribers", "a bug or out of memory"});
    }
    return {};
}

void Bus::deleteEntities(Entities& entities) noexcept
{
    if (entities.participant != nullptr) {
        entities.participant->delete_contained_entities();
        fdds::DomainParticipantFactory::get_instance()->delete_participant(entities.participant);
    }
    entities = Entities{};
}

Bus::~Bus()
{
    deleteEntities(dds_);
}

template <class Count>
HandshakeWatch::ByCa Bus::watched(Count count) const
{
    const std::shared_lock lock(endpointGuard_);
    if (identities_ == nullptr || dds_.participant == nullptr) {
        return {};
    }
    return count(WriterIdentities::prefixKey(dds_.participant->guid().guidPrefix));
}

HandshakeWatch::ByCa Bus::unfinishedHandshakes(std::chrono::steady_clock::duration olderThan) const
{
    const auto now = HandshakeWatch::Clock::now();
    return watched([&](const std::string& local) { return identities_->handshakes.unfinished(local, now, olderThan); });
}

HandshakeWatch::ByCa Bus::handshakePeers() const
{
    return watched([&](const std::string& local) { return identities_->handshakes.peers(local); });
}

std::shared_ptr<const RefusedPrefixes> Bus::refusedPrefixes() const
{
    return identities_ == nullptr ? nullptr : identities_->refused;
}

Bus::Refusals Bus::refusals() const
{
    if (identities_ == nullptr) {
        return {};
    }
    return {identities_->refusals.load(std::memory_order_relaxed),
            identities_->refusedAtDiscovery.load(std::memory_order_relaxed), identities_->refused->dropped()};
}

std::string describe(const StallRejoin& r)
{
    std::string out = std::to_string(r.stalled) +
                      " secured handshake(s) with participants of this team's CA unfinished after " +
                      std::to_string(kHandshakeStall.count()) +
                      " s (Fast DDS 2.9.1 sometimes stalls two participants that join at the same moment, for good; a "
                      "participant that names this CA but holds another's certificate looks the same): ";
    out += r.outcome == StallRejoin::Failed ? "joining the bus again failed: " + r.error.message()
                                            : std::string("joined the bus again as a new participant");
    const auto wait = std::chrono::duration_cast<std::chrono::seconds>(r.nextWait).count();
    return out + "; the next join for a stall waits at least " + std::to_string(wait) + " s";
}

StallRejoin Bus::rejoinIfStalled()
{
    const auto now = HandshakeWatch::Clock::now();
    const std::size_t stalled = stalledHandshakes(kHandshakeStall);
    if (!rejoinBackoff_.due(now, stalled)) {
        return StallRejoin{};
    }
    rejoinBackoff_.joined(now);
    StallRejoin out{StallRejoin::Rejoined, stalled, rejoinBackoff_.wait(), {}};
    if (auto renewed = renew(); !renewed) {
        out.outcome = StallRejoin::Failed;
        out.error = renewed.error();
    }
    return out;
}

void Bus::forgetHandshakes(const Entities& entities) const
{
    if (identities_ != nullptr && entities.participant != nullptr) {
        identities_->handshakes.forget(WriterIdentities::prefixKey(entities.participant->guid().guidPrefix));
    }
}

std::string Bus::writerIdentity(const fdds::SampleInfo& info) const
{
    return identities_ == nullptr ? std::string() : identities_->identity(info.sample_identity.writer_guid());
}

Error Bus::topicError(TopicId id, std::string what, std::string securedFix) const
{
    return Error{"dds topic " + topicName(id, config_), std::move(what),
                 config_.security.enabled ? std::move(securedFix) : std::string("a bug")};
}

Error Bus::wrongType(TopicId id) const
{
    return topicError(id, "a writer or reader of another type", "a bug");
}

Result<fdds::Topic*, Error> Bus::topic(TopicId id, MakeType make)
{
    fdds::Topic*& t = dds_.topics[static_cast<std::size_t>(id)];
    if (t == nullptr) {
        fdds::TypeSupport type(make());
        if (type.register_type(dds_.participant) == ReturnCode_t::RETCODE_OK) {
            t = dds_.participant->create_topic(topicName(id, config_), type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
        }
    }
    if (t == nullptr) {
        return Unexpected(topicError(id, "cannot create the topic", "a bug"));
    }
    return t;
}

Result<fdds::DataWriter*, Error> Bus::createWriter(TopicId id, MakeType make)
{
    const auto t = topic(id, make);
    if (!t) {
        return Unexpected(t.error());
    }
    const TopicSpec& s = spec(id);
    fdds::DataWriterQos q = fdds::DATAWRITER_QOS_DEFAULT;
    TopicSpec chosen = s;
    // Our best-effort topics are written reliable too; their readers stay best effort, so nothing is acknowledged or
    // repaired for them. Fast DDS 2.9.1's best-effort writer sends each sample to a reader on the same host twice,
    // over shared memory and over UDP loopback: it keeps the reader's UDP locators (fixed after 2.9.1 upstream,
    // eProsima/Fast-DDS#3655). Its reliable writer drops them. Measured: README "Secured bus".
    chosen.reliable = s.ros && !s.graph ? config_.rosReliable : true;
    applyCommon(q, chosen);
    if (chosen.reliable) {
        q.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0, 100'000'000);
        q.reliability().max_blocking_time = eprosima::fastrtps::Duration_t(0, 100'000'000);
    }
    fdds::DataWriter* w = (s.ros ? dds_.rosPublisher : dds_.publisher)->create_datawriter(*t, q);
    if (w == nullptr) {
        return Unexpected(topicError(id, "cannot create the writer",
                                     "does the signed permissions document allow this participant to write it in "
                                     "its own partition?"));
    }
    return w;
}

Result<fdds::DataReader*, Error> Bus::createReader(TopicId id, MakeType make)
{
    const auto t = topic(id, make);
    if (!t) {
        return Unexpected(t.error());
    }
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    applyCommon(q, spec(id));
    fdds::DataReader* r = (spec(id).ros ? dds_.rosSubscriber : dds_.subscriber)->create_datareader(*t, q);
    if (r == nullptr) {
        return Unexpected(topicError(id, "cannot create the reader",
                                     "does the signed permissions document allow this participant "
                                     "to read it?"));
    }
    return r;
}

Result<detail::Endpoint*, Error> Bus::makeWriter(TopicId id, MakeType make)
{
    auto w = createWriter(id, make);
    if (!w) {
        return Unexpected(w.error());
    }
    const std::unique_lock lock(endpointGuard_);
    return &endpoints_.emplace_back(detail::Endpoint{&endpointGuard_, *w, nullptr, id, make, true});
}

Result<detail::Endpoint*, Error> Bus::makeReader(TopicId id, MakeType make)
{
    auto r = createReader(id, make);
    if (!r) {
        return Unexpected(r.error());
    }
    const std::unique_lock lock(endpointGuard_);
    return &endpoints_.emplace_back(detail::Endpoint{&endpointGuard_, nullptr, *r, id, make, false});
}

NetworkChange Bus::followNetworkChanges()
{
    const auto t = std::chrono::steady_clock::now();
    if (t < nextInterfaceCheck_) {
        return NetworkChange::None;
    }
    nextInterfaceCheck_ = t + kInterfaceCheckPeriod;
    std::vector<std::uint32_t> now;
    if (!upIpv4Addresses(now) || now == lastAddresses_) {
        return NetworkChange::None;
    }
    lastAddresses_ = std::move(now);
    if (lastAddresses_ == startAddresses_) {
        return NetworkChange::None;
    }
    if (auto renewed = renew(); !renewed) {
        networkError_ = renewed.error();
        lastAddresses_.clear(); // the next check (a second later) tries again
        return NetworkChange::Failed;
    }
    return NetworkChange::Followed;
}

Result<void, Error> Bus::renew()
{
    std::vector<std::uint32_t> now;
    upIpv4Addresses(now);
    const std::unique_lock lock(endpointGuard_);
    if (auto renewed = renewEndpoints(); !renewed) {
        return Unexpected(renewed.error());
    }
    startAddresses_ = now;
    lastAddresses_ = std::move(now);
    return {};
}

Result<void, Error> Bus::renewEndpoints()
{
    // Made anew, the participant and its endpoints take the interfaces up now. Setting the participant's QoS again
    // is not enough (its endpoints keep their addresses), and Fast DDS 2.9 then gives a second participant of the
    // host the first one's ports on the new interfaces (measured: two processes announcing 10.80.0.1:55410).
    if (auto ok = validate(config_, "dds"); !ok) { // the security files as at the start: a file gone is named
        return Unexpected(ok.error());
    }
    auto pq = participantQos(config_, refusedPrefixes());
    if (!pq) {
        return Unexpected(pq.error());
    }
    Entities old = std::exchange(dds_, Entities{});
    std::vector<detail::Endpoint> made(endpoints_.begin(), endpoints_.end());
    auto opened = openParticipant(*pq);
    for (std::size_t i = 0; opened && i < made.size(); ++i) {
        opened = remake(made[i]);
    }
    if (!opened) {
        forgetHandshakes(dds_);
        deleteEntities(dds_);
        dds_ = old;
        return Unexpected(opened.error());
    }
    for (std::size_t i = 0; i < made.size(); ++i) {
        endpoints_[i].writer = made[i].writer;
        endpoints_[i].reader = made[i].reader;
    }
    forgetHandshakes(old);
    deleteEntities(old);
    return rosNode_.empty() ? Result<void, Error>{} : writeRosNode();
}

Result<void, Error> Bus::remake(detail::Endpoint& endpoint)
{
    if (endpoint.writes) {
        auto w = createWriter(endpoint.id, endpoint.make);
        if (!w) {
            return Unexpected(w.error());
        }
        endpoint.writer = *w;
    } else {
        auto r = createReader(endpoint.id, endpoint.make);
        if (!r) {
            return Unexpected(r.error());
        }
        endpoint.reader = *r;
    }
    return {};
}

graph::Gid_ rosGid(const rtps::GUID_t& guid)
{
    graph::Gid_ gid;
    gid.data().fill(0);
    std::copy(std::begin(guid.guidPrefix.value), std::end(guid.guidPrefix.value), gid.data().begin());
    std::copy(std::begin(guid.entityId.value), std::end(guid.entityId.value),
              gid.data().begin() + sizeof(guid.guidPrefix.value));
    return gid;
}

Result<void, Error> Bus::announceRosNode(const std::string& nodeName)
{
    const std::string where = "dds topic ros_discovery_info";
    if (nodeName.empty() || nodeName.size() > 255 || std::isdigit(static_cast<unsigned char>(nodeName.front())) != 0 ||
        nodeName.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") !=
            std::string::npos) {
        return Unexpected(Error{where, "'" + nodeName + "' is not a ROS 2 node name",
                                "letters, digits and _, not starting with a digit, e.g. ugvsense"});
    }
    if (graphOut_ == nullptr) {
        auto w = makeWriter(TopicId::RosGraph,
                            []() -> fdds::TopicDataType* { return new graph::ParticipantEntitiesInfo_PubSubType(); });
        if (!w) {
            return Unexpected(w.error());
        }
        graphOut_ = *w;
    }
    const std::shared_lock lock(endpointGuard_);
    rosNode_ = nodeName;
    return writeRosNode();
}

Result<void, Error> Bus::writeRosNode()
{
    graph::NodeEntitiesInfo_ node;
    node.node_namespace("/" + config_.rosNamespace);
    node.node_name(rosNode_);
    for (const detail::Endpoint& e : endpoints_) {
        if (!spec(e.id).ros || &e == graphOut_ || (e.writer == nullptr && e.reader == nullptr)) {
            continue;
        }
        if (e.writes) {
            node.writer_gid_seq().push_back(rosGid(e.writer->guid()));
        } else {
            node.reader_gid_seq().push_back(rosGid(e.reader->guid()));
        }
    }
    graph::ParticipantEntitiesInfo_ info;
    info.gid(rosGid(dds_.participant->guid()));
    info.node_entities_info_seq().push_back(std::move(node));
    if (graphOut_->writer == nullptr || !graphOut_->writer->write(&info)) {
        return Unexpected(Error{"dds topic ros_discovery_info", "the sample was refused",
                                "a bug, or see the Fast DDS messages above"});
    }
    return {};
}

} // namespace ugv::ipc::dds
