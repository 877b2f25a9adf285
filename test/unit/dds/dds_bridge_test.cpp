// service/dds_bridge on a secured bus (issue 22 item 4): the vehicle takes poses naming it only from its own
// participants. A team member with a valid certificate of its own (ugv-2) that writes a pose naming ugv-1 is refused
// and counted, while ugv-1's localisation (another participant with ugv-1's certificate) is used. The team's files
// are made by bringup/deploy/security/make_security.sh (skipped with a message without openssl).

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

} // namespace
} // namespace ugv::service
