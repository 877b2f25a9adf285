// service/dds_bridge on a secured bus (issue 22 item 4): the vehicle takes poses naming it only from its own
// participants. A team member with a valid certificate of its own (ugv-2) that writes a pose naming ugv-1 is refused
// and counted, while ugv-1's localisation (another participant with ugv-1's certificate) is used. The team's files
// are made by bringup/deploy/security/make_security.sh (skipped with a message without openssl). And a renewal of a
// secured bus (what it does when the network changes) makes new endpoints that pass the handshakes again, or, when it
// cannot, leaves the bus working as it was. A handshake that never ends with a peer naming the team's CA makes the
// service join the bus again (at the back-off's pace); one with a peer of another CA does not.

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "ugv/ipc/dds_bus.hpp"
#include "ugv/ipc/dds_convert.hpp"
#include "ugv/service/dds_bridge.hpp"

namespace ugv::service {
namespace {

namespace dds = ipc::dds;

/// A team of two vehicles made by make_security.sh in a folder of this test's own, removed at the end.
class SecuredTeam : public ::testing::Test {
protected:
    void SetUp() override
    {
        folder_ = std::filesystem::temp_directory_path() / ("ugv-dds-bridge-test-" + std::to_string(::getpid()));
        partition_ = "bridge_test_" + std::to_string(::getpid());
        const std::string command = "bash '" UGV_SOURCE_DIR "/bringup/deploy/security/make_security.sh' '" +
                                    folder_.string() + "' --partition " + partition_ + " ugv-1 ugv-2 >/dev/null 2>&1";
        const int status = std::system(command.c_str());
        if (status != 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
            GTEST_SKIP() << "bringup/deploy/security/make_security.sh failed (is openssl installed? bash "
                            "toolchain/host.sh deps installs it)";
        }
    }
    void TearDown() override
    {
        std::error_code ec;
        std::filesystem::remove_all(folder_, ec); // the private keys too
    }

    /// `identity`'s files from this team (or from `team`, another folder made by make_security.sh).
    adapters::ServiceConfig vehicle(const std::string& identity, const std::filesystem::path& team = {}) const
    {
        adapters::ServiceConfig c;
        c.vehicleId = identity;
        c.dds.domainId = 150 + static_cast<int>(::getpid() % 80);
        c.dds.partition = partition_;
        c.dds.security.enabled = true;
        const dds::SecurityConfig files =
            dds::securityFromFolder(((team.empty() ? folder_ : team) / identity).string(), identity);
        c.dds.security.identityCa = files.identityCa;
        c.dds.security.certificate = files.certificate;
        c.dds.security.privateKey = files.privateKey;
        c.dds.security.permissionsCa = files.permissionsCa;
        c.dds.security.governance = files.governance;
        c.dds.security.permissions = files.permissions;
        return c;
    }

    std::filesystem::path folder_;
    std::string partition_;
};

dds::msg::VehiclePose poseNaming(const std::string& vehicle, double eastM)
{
    dds::msg::VehiclePose p;
    p.vehicle(vehicle);
    p.stamp_ns(dds::realtimeNowNs());
    p.latitude_deg(-34.9);
    p.longitude_deg(138.6);
    p.east_m(eastM);
    p.heading_deg(90.0);
    return p;
}

/// Writes `sample` every 50 ms until `in` takes one (true) or 30 s pass (false).
template <class T>
bool arrives(dds::Writer<T>& out, dds::Reader<T>& in, const T& sample)
{
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    T got;
    while (std::chrono::steady_clock::now() < deadline) {
        (void)out.write(sample);
        if (in.wait(std::chrono::milliseconds(50)) && in.take(got)) {
            while (in.take(got)) { // what an older writer sent as well
            }
            return true;
        }
    }
    return false;
}

TEST_F(SecuredTeam, APoseInThisVehiclesNameFromAnotherParticipantIsRefused)
{
    // Arrange: ugv-1's service (the bridge), ugv-1's localisation, and team member ugv-2.
    const adapters::ServiceConfig config = vehicle("ugv-1");
    auto serviceBus = dds::Bus::create(busConfig(config));
    auto localisationBus = dds::Bus::create(busConfig(vehicle("ugv-1")));
    auto otherBus = dds::Bus::create(busConfig(vehicle("ugv-2")));
    ASSERT_TRUE(serviceBus) << serviceBus.error().message();
    ASSERT_TRUE(localisationBus) << localisationBus.error().message();
    ASSERT_TRUE(otherBus) << otherBus.error().message();
    auto bridge = DdsBridge::create(**serviceBus, config, std::chrono::milliseconds(100));
    ASSERT_TRUE(bridge) << bridge.error().message();
    auto own = (*localisationBus)->writer<dds::msg::VehiclePose>();
    auto other = (*otherBus)->writer<dds::msg::VehiclePose>();
    ASSERT_TRUE(own) << own.error().message();
    ASSERT_TRUE(other) << other.error().message();

    // Act: once both writers reached the bridge's reader (the secured handshakes), each writes 5 poses naming ugv-1.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while ((own->matched() < 1 || other->matched() < 1) && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    ASSERT_GE(own->matched(), 1) << "ugv-1's localisation never matched the service's pose reader";
    ASSERT_GE(other->matched(), 1) << "ugv-2's writer never matched ugv-1's pose reader (it may read the topic)";
    // Pose is best effort, keep last 8: one pose from each at a time, taken before the next two.
    constexpr int kEach = 5;
    DdsBridgeStats stats;
    for (int i = 0; i < kEach; ++i) {
        ASSERT_TRUE(own->write(poseNaming("ugv-1", 1.0 + i)));
        ASSERT_TRUE(other->write(poseNaming("ugv-1", 99.0 + i)));
        const auto taken = std::chrono::steady_clock::now() + std::chrono::seconds(5);
        do {
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
            (*bridge)->idle();
            stats = (*bridge)->stats();
        } while (stats.posesUsed + stats.posesImpersonated < 2U * (i + 1U) && std::chrono::steady_clock::now() < taken);
    }

    // Assert: the localisation's five used, ugv-2's five refused as written in ugv-1's name.
    EXPECT_EQ(stats.posesUsed, static_cast<std::uint64_t>(kEach));
    EXPECT_EQ(stats.posesImpersonated, static_cast<std::uint64_t>(kEach));
    EXPECT_EQ(stats.posesRejected, 0U);
    EXPECT_EQ(stats.posesForeign, 0U);
}

// Make before break: a renewal that cannot make the new participant (a certificate replaced by another's, a file
// gone) says why and leaves the old one working; once the file is back, the next renewal succeeds and its new
// endpoints pass the secured handshakes in both directions.
TEST_F(SecuredTeam, ARenewalThatCannotMakeTheParticipantLeavesTheBusWorkingAndTheNextOneSucceeds)
{
    // Arrange: the bus to renew (ugv-1's service) and a peer of ugv-1, with a topic each way between them.
    const adapters::ServiceConfig config = vehicle("ugv-1");
    auto bus = dds::Bus::create(busConfig(config));
    auto peer = dds::Bus::create(busConfig(vehicle("ugv-1")));
    ASSERT_TRUE(bus) << bus.error().message();
    ASSERT_TRUE(peer) << peer.error().message();
    auto poseOut = (*bus)->writer<dds::msg::VehiclePose>();
    auto sectorsIn = (*bus)->reader<dds::msg::ObstacleSectors>();
    auto poseIn = (*peer)->reader<dds::msg::VehiclePose>();
    auto sectorsOut = (*peer)->writer<dds::msg::ObstacleSectors>();
    ASSERT_TRUE(poseOut && sectorsIn && poseIn && sectorsOut);
    const dds::msg::VehiclePose pose = poseNaming("ugv-1", 1.0);
    dds::msg::ObstacleSectors sectors;
    sectors.vehicle("ugv-1");
    ASSERT_TRUE(arrives(*poseOut, *poseIn, pose)) << "the secured handshake never completed";
    ASSERT_TRUE(arrives(*sectorsOut, *sectorsIn, sectors));
    const auto before = poseOut->guid();
    const std::filesystem::path certificate = config.dds.security.certificate;
    const std::filesystem::path kept = folder_ / "ugv-1-certificate.kept";
    std::filesystem::copy_file(certificate, kept);

    // Act and assert 1: ugv-2's certificate (valid, but not for ugv-1's key and permissions) in its place.
    std::filesystem::copy_file(dds::securityFromFolder((folder_ / "ugv-2").string(), "ugv-2").certificate, certificate,
                               std::filesystem::copy_options::overwrite_existing);
    const auto wrong = (*bus)->renew();
    ASSERT_FALSE(wrong) << "a participant was made with another's certificate";
    EXPECT_NE(wrong.error().message().find("cannot create the DDS participant"), std::string::npos)
        << wrong.error().message();
    EXPECT_EQ(poseOut->guid(), before) << "the old writer was not kept";
    EXPECT_TRUE(arrives(*poseOut, *poseIn, pose)) << "the bus stopped writing after a failed renewal";
    EXPECT_TRUE(arrives(*sectorsOut, *sectorsIn, sectors)) << "the bus stopped reading after a failed renewal";

    // Act and assert 2: the file gone.
    std::filesystem::remove(certificate);
    const auto gone = (*bus)->renew();
    ASSERT_FALSE(gone);
    EXPECT_NE(gone.error().message().find("security.certificate"), std::string::npos) << gone.error().message();
    EXPECT_TRUE(arrives(*poseOut, *poseIn, pose));

    // Act and assert 3: the file back.
    std::filesystem::copy_file(kept, certificate);
    const auto renewed = (*bus)->renew();
    ASSERT_TRUE(renewed) << renewed.error().message();
    EXPECT_NE(poseOut->guid(), before) << "the writer was not made again";
    EXPECT_TRUE(arrives(*poseOut, *poseIn, pose)) << "a renewed writer never passed the secured handshake";
    EXPECT_TRUE(arrives(*sectorsOut, *sectorsIn, sectors)) << "a renewed reader never passed the secured handshake";
}

/// Polls `done` every 100 ms for up to 30 s.
template <class Done>
bool eventually(Done done)
{
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!done()) {
        if (std::chrono::steady_clock::now() >= deadline) {
            return false;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return true;
}

// A participant of another CA leaves a handshake unfinished for good on one side (Fast DDS 2.9.1 reports nothing
// there); the peers' identity tokens tell it from a stalled handshake of the team's own, which alone makes a bus join
// again (Bus::rejoinIfStalled()).
TEST_F(SecuredTeam, APeerOfAnotherTeamsCaIsNotTakenForAStalledHandshake)
{
    // Arrange: two vehicles of the team, authenticated to each other before the intruder comes.
    const std::filesystem::path rogueTeam = folder_ / "rogue";
    const std::string command = "bash '" UGV_SOURCE_DIR "/bringup/deploy/security/make_security.sh' '" +
                                rogueTeam.string() + "' --partition " + partition_ + " ugv-2 >/dev/null 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    auto a = dds::Bus::create(busConfig(vehicle("ugv-1")));
    auto b = dds::Bus::create(busConfig(vehicle("ugv-2")));
    ASSERT_TRUE(a) << a.error().message();
    ASSERT_TRUE(b) << b.error().message();
    const auto teamDone = [&] {
        (void)(*a)->rejoinIfStalled(); // two participants that join at the same moment may stall (the remedy)
        (void)(*b)->rejoinIfStalled();
        return (*a)->handshakePeers().sameCa == 1 && (*b)->handshakePeers().sameCa == 1 &&
               (*a)->stalledHandshakes(std::chrono::seconds(0)) == 0 &&
               (*b)->stalledHandshakes(std::chrono::seconds(0)) == 0;
    };
    ASSERT_TRUE(eventually(teamDone)) << "the team's two participants never authenticated each other (or one was "
                                         "not taken for a peer of this team's CA)";

    // Act: ugv-2 of another CA joins.
    auto rogue = dds::Bus::create(busConfig(vehicle("ugv-2", rogueTeam)));
    ASSERT_TRUE(rogue) << rogue.error().message();
    const auto foreignUnfinished = [&] {
        std::size_t n = 0;
        for (const auto* bus : {&*a, &*b, &*rogue}) {
            n += (**bus).unfinishedHandshakes(std::chrono::seconds(0)).otherCa;
        }
        return n;
    };

    // Assert: each pair with the intruder stays unfinished on one side, counted apart from the team's own; none of
    // the three has a stalled handshake, so none would join again.
    EXPECT_TRUE(eventually([&] { return foreignUnfinished() >= 2; }))
        << "expected the two handshakes with the intruder unfinished on one side each, got " << foreignUnfinished();
    std::this_thread::sleep_for(std::chrono::seconds(2));
    for (const auto* bus : {&*a, &*b, &*rogue}) {
        EXPECT_EQ((**bus).stalledHandshakes(std::chrono::seconds(0)), 0U);
    }
    EXPECT_EQ((*rogue)->handshakePeers().sameCa, 0U) << "the intruder took the team's CA for its own";
    EXPECT_EQ((*a)->handshakePeers().sameCa, 1U);
}

// Fast DDS 2.9.1 answers every handshake request of a participant it refused (one a second) and leaks the
// certificate it parses each time (ASan; 4.4 kB/s of a station's RSS). A participant whose identity names another CA
// is refused as it is discovered and its UDP datagrams are dropped on arrival, so that no handshake of it is answered
// (before, one on each side, then every retry). Over UDP alone, as between vehicles: shared memory is not filtered
// (the filter there made the secured hand-over's tail 2.5 times as long; dds_bus.cpp).
TEST_F(SecuredTeam, AParticipantOfAnotherCaIsRefusedAtDiscoveryAndNoHandshakeOfItIsAnswered)
{
    const std::filesystem::path rogueTeam = folder_ / "rogue";
    const std::string command = "bash '" UGV_SOURCE_DIR "/bringup/deploy/security/make_security.sh' '" +
                                rogueTeam.string() + "' --partition " + partition_ + " ugv-2 >/dev/null 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    // Arrange: ugv-1 of the team and ugv-2 of another CA, over UDP.
    adapters::ServiceConfig teamConfig = vehicle("ugv-1");
    adapters::ServiceConfig rogueConfig = vehicle("ugv-2", rogueTeam);
    teamConfig.dds.sharedMemory = false;
    rogueConfig.dds.sharedMemory = false;
    auto team = dds::Bus::create(busConfig(teamConfig));
    auto rogue = dds::Bus::create(busConfig(rogueConfig));
    ASSERT_TRUE(team) << team.error().message();
    ASSERT_TRUE(rogue) << rogue.error().message();
    const auto answered = [&] { return (*team)->refusals().reported + (*rogue)->refusals().reported; };
    const auto dropped = [&] { return (*team)->refusals().datagramsDropped + (*rogue)->refusals().datagramsDropped; };

    // Act: each discovers the other, then 5 s of the other's retries.
    ASSERT_TRUE(eventually([&] { return (*team)->refusals().atDiscovery > 0 && (*rogue)->refusals().atDiscovery > 0; }))
        << "a side did not refuse the other as it discovered it";
    std::this_thread::sleep_for(std::chrono::seconds(5));

    // Assert: no handshake answered and refused (1 without the refusal at discovery, about 6 in 5 s without the
    // filter), the other's datagrams dropped on arrival.
    EXPECT_EQ(answered(), 0U) << "Fast DDS answered a handshake of a participant of another CA";
    EXPECT_GT(dropped(), 0U);
    EXPECT_EQ((*team)->refusals().atDiscovery, 1U);
    EXPECT_EQ((*rogue)->refusals().atDiscovery, 1U);
}

// What a stall looks like from one side: a peer that names this team's CA and whose handshake never ends. An impostor
// (a CA of its own under the team CA's very subject) makes one for good: the side its certificate reaches refuses
// it, the other waits forever. On that side the service's DDS task (DdsBridge) joins the bus again once the
// handshake is 10 s old, then not again before the back-off's wait.
TEST_F(SecuredTeam, AHandshakeWithAPeerNamingTheTeamsCaThatNeverEndsMakesTheServiceJoinAgainAtTheBackoffsPace)
{
    // Arrange: ugv-1 of the team, and an impostor ugv-2 whose CA bears the team CA's subject.
    const std::filesystem::path impostor = folder_ / "impostor";
    const std::string command =
        "set -e; mkdir -p '" + impostor.string() + "/ca'; cd '" + impostor.string() +
        "/ca'; openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out ca.key 2>/dev/null; "
        "openssl req -x509 -new -key ca.key -days 30 -sha256 -out ca.cert.pem -subj \"$(openssl x509 -in '" +
        (folder_ / "ca" / "ca.cert.pem").string() +
        "' -noout -subject -nameopt compat | sed 's/^subject=//')\" -addext basicConstraints=critical,CA:TRUE "
        "-addext keyUsage=critical,keyCertSign,cRLSign,digitalSignature; bash '" UGV_SOURCE_DIR
        "/bringup/deploy/security/make_security.sh' '" +
        impostor.string() + "' --partition " + partition_ + " ugv-2 >/dev/null 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    // Each side runs a service's DDS task (the bridge's loop); the side the impostor's certificate never reaches
    // waits for good (which side that is, is Fast DDS's choice).
    const std::array<adapters::ServiceConfig, 2> configs{vehicle("ugv-1"), vehicle("ugv-2", impostor)};
    std::array<std::unique_ptr<dds::Bus>, 2> buses;
    std::array<std::unique_ptr<DdsBridge>, 2> bridges;
    std::array<dds::Writer<dds::msg::VehiclePose>, 2> writers;
    std::array<eprosima::fastrtps::rtps::GUID_t, 2> before;
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < 2; ++i) {
        auto bus = dds::Bus::create(busConfig(configs[i]));
        ASSERT_TRUE(bus) << bus.error().message();
        buses[i] = std::move(*bus);
        auto bridge = DdsBridge::create(*buses[i], configs[i], std::chrono::seconds(1));
        ASSERT_TRUE(bridge) << bridge.error().message();
        bridges[i] = std::move(*bridge);
        auto writer = buses[i]->writer<dds::msg::VehiclePose>();
        ASSERT_TRUE(writer) << writer.error().message();
        writers[i] = *writer;
        before[i] = writers[i].guid();
    }
    const auto rejoins = [&](std::size_t i) { return bridges[i]->stats().stallRejoins; };
    const auto turn = [&] {
        for (auto& bridge : bridges) {
            bridge->idle();
        }
    };

    // Act: the two services run until one joins again, and 3 s more.
    const bool joined = eventually([&] {
        turn();
        return rejoins(0) + rejoins(1) > 0;
    });
    const auto firstJoin = std::chrono::steady_clock::now() - start;
    for (int i = 0; i < 30; ++i) {
        turn();
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }

    // Assert: one side joined again (a new participant: its writers made again), not before the handshake was 10 s
    // old, and not a second time within the back-off's wait.
    ASSERT_TRUE(joined) << "neither service joined again";
    EXPECT_GE(firstJoin, dds::kHandshakeStall);
    const std::size_t side = rejoins(0) > 0 ? 0 : 1;
    EXPECT_EQ(rejoins(side), 1U);
    EXPECT_NE(writers[side].guid(), before[side]) << "the writer was not made again";
    EXPECT_EQ(buses[side]->rejoinIfStalled().outcome, dds::StallRejoin::None);
}

} // namespace
} // namespace ugv::service
