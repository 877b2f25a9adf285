// service/dds_bridge on a secured bus (issue 22 item 4): the vehicle takes poses naming it only from its own
// participants. A team member with a valid certificate of its own (ugv-2) that writes a pose naming ugv-1 is refused
// and counted, while ugv-1's localisation (another participant with ugv-1's certificate) is used. The team's files
// are made by bringup/deploy/security/make_security.sh (skipped with a message without openssl). And a renewal of a
// secured bus (what it does when the network changes) makes new endpoints that pass the handshakes again, or, when it
// cannot, leaves the bus working as it was.

#include <sys/wait.h>
#include <unistd.h>

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

    adapters::ServiceConfig vehicle(const std::string& identity) const
    {
        adapters::ServiceConfig c;
        c.vehicleId = identity;
        c.dds.domainId = 150 + static_cast<int>(::getpid() % 80);
        c.dds.partition = partition_;
        c.dds.security.enabled = true;
        const dds::SecurityConfig files = dds::securityFromFolder((folder_ / identity).string(), identity);
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

} // namespace
} // namespace ugv::service
