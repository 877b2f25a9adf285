// ipc::dds::validate / Bus::create: configuration errors are caught before any DDS entity exists, and say what
// is wrong and how to fix it. Also the topic names of `ugvsense listen`.

#include "ugv/ipc/dds_bus.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include <gtest/gtest.h>

namespace ugv::ipc::dds {
namespace {

BusConfig good()
{
    BusConfig c;
    c.domainId = 0;
    c.rosNamespace = "ugv1";
    return c;
}

TEST(BusConfig, DefaultsAreValid)
{
    EXPECT_TRUE(validate(BusConfig{}, "dds"));
    BusConfig c = good();
    c.domainId = 232;
    c.discoveryServers = "127.0.0.1:11811;192.168.1.10:11812";
    c.partitions = {"team-a", "test"};
    c.rosNamespace = "team_a/ugv_1";
    EXPECT_TRUE(validate(c, "dds")) << validate(c, "dds").error().message();
}

TEST(BusConfig, Domain233IsRefused)
{
    BusConfig c = good();
    c.domainId = 233;

    const auto sut = validate(c, "config.yaml dds");

    ASSERT_FALSE(sut);
    EXPECT_NE(sut.error().where.find("config.yaml dds domain_id"), std::string::npos) << sut.error().message();
    EXPECT_NE(sut.error().what.find("233"), std::string::npos);
    EXPECT_NE(sut.error().fix.find("0..232"), std::string::npos);
    c.domainId = -1;
    EXPECT_FALSE(validate(c, "dds"));
}

TEST(BusConfig, BadDiscoveryServerIsRefused)
{
    for (const char* list :
         {"nonsense", "127.0.0.1:notaport", "127.0.0.1:99999", "300.1.2.3:11811", ";;", "1.2.3.4:11811;;x"}) {
        BusConfig c = good();
        c.discoveryServers = list;

        const auto sut = validate(c, "dds");

        ASSERT_FALSE(sut) << list << " was accepted";
        EXPECT_NE(sut.error().where.find("discovery_server"), std::string::npos);
        EXPECT_NE(sut.error().what.find(list), std::string::npos);
        EXPECT_NE(sut.error().fix.find("IP:PORT"), std::string::npos);
    }
}

TEST(BusConfig, BadRosNamespaceIsRefused)
{
    for (const char* ns : {"", "/ugv1", "ugv1/", "ugv 1", "ugv-1", "ügv"}) {
        BusConfig c = good();
        c.rosNamespace = ns;

        const auto sut = validate(c, "dds");

        ASSERT_FALSE(sut) << "'" << ns << "' was accepted";
        EXPECT_NE(sut.error().what.find("not a ROS 2 name"), std::string::npos) << sut.error().message();
        EXPECT_FALSE(sut.error().fix.empty());
    }
}

TEST(BusConfig, AVehicleNameOverTheBusBoundIsRefused)
{
    BusConfig c = good();
    c.rosNamespace = std::string(kMaxNameLength, 'u');
    EXPECT_TRUE(validate(c, "dds"));

    c.rosNamespace += 'u';
    const auto sut = validate(c, "dds");
    ASSERT_FALSE(sut);
    EXPECT_NE(sut.error().what.find("65 characters"), std::string::npos) << sut.error().message();
}

TEST(BusConfig, EmptyPartitionIsRefused)
{
    BusConfig c = good();
    c.partitions = {"team", ""};

    const auto sut = validate(c, "dds");

    ASSERT_FALSE(sut);
    EXPECT_NE(sut.error().where.find("partitions"), std::string::npos);
}

TEST(BusConfig, CreateRefusesAnInvalidConfigWithoutAParticipant)
{
    BusConfig c = good();
    c.domainId = 233;

    const auto sut = Bus::create(c);

    ASSERT_FALSE(sut);
    EXPECT_NE(sut.error().what.find("233"), std::string::npos);
}

TEST(BusSecurity, OffNeedsNoFilesAndOnNeedsEvery)
{
    BusConfig c = good();
    EXPECT_TRUE(validate(c, "dds"));
    c.security.enabled = true;
    c.security.identity = "ugv-1";

    const auto sut = validate(c, "dds");

    ASSERT_FALSE(sut);
    EXPECT_EQ(sut.error().where, "dds security.identity_ca");
    EXPECT_NE(sut.error().what.find("is empty"), std::string::npos) << sut.error().message();
    EXPECT_NE(sut.error().fix.find("make_security.sh"), std::string::npos) << sut.error().message();
}

TEST(BusSecurity, AFileThatCannotBeReadOrIsNotWhatItShouldBeIsNamed)
{
    SecurityConfig s;
    s.enabled = true;
    s.certificate = "/nonexistent/cert.pem";
    const auto files = securityFiles(s);
    ASSERT_EQ(std::string(files[1].key), "certificate");

    const auto missing = checkSecurityFile(files[1], "dds.security.certificate");
    s.certificate = "/proc/self/status"; // readable, no PEM certificate in it
    const auto wrong = checkSecurityFile(files[1], "dds.security.certificate");

    ASSERT_FALSE(missing);
    EXPECT_NE(missing.error().what.find("'/nonexistent/cert.pem' cannot be read"), std::string::npos);
    ASSERT_FALSE(wrong);
    EXPECT_NE(wrong.error().what.find("is not this participant's certificate (PEM)"), std::string::npos)
        << wrong.error().message();
}

TEST(BusSecurity, AFifoIsRefusedWithoutOpeningIt)
{
    const std::string fifo = "/tmp/ugv-bus-security-fifo-" + std::to_string(::getpid());
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    SecurityConfig s;
    s.certificate = fifo;

    const auto sut = checkSecurityFile(securityFiles(s)[1], "dds.security.certificate"); // would block if opened
    ::unlink(fifo.c_str());

    ASSERT_FALSE(sut);
    EXPECT_NE(sut.error().what.find("cannot be read"), std::string::npos) << sut.error().message();
}

// The identity CA's subject is read before the participant is made (peers that name it are the team's): a file
// that looks like a certificate but is none is named with its key and path.
TEST(BusSecurity, AnIdentityCaThatIsNoCertificateIsNamedBeforeAnyParticipant)
{
    const std::string dir = "/tmp/ugv-bus-security-ca-" + std::to_string(::getpid());
    ASSERT_EQ(::mkdir(dir.c_str(), 0700), 0);
    const auto write = [&](const std::string& name, const std::string& text) {
        const std::string path = dir + "/" + name;
        std::ofstream(path) << text;
        return path;
    };
    const std::string notACertificate = "-----BEGIN CERTIFICATE-----\nnot base64 at all\n-----END CERTIFICATE-----\n";
    BusConfig c = good();
    c.partitions = {"team"};
    c.security.enabled = true;
    c.security.identity = "ugv-1";
    c.security.identityCa = write("ca.pem", notACertificate);
    c.security.certificate = write("cert.pem", notACertificate);
    c.security.privateKey = write("key.pem", "-----BEGIN PRIVATE KEY-----\n-----END PRIVATE KEY-----\n");
    c.security.permissionsCa = c.security.identityCa;
    c.security.governance = write("governance.p7s", "Content-Type: application/pkcs7-signature\n");
    c.security.permissions = write("permissions.p7s", "Content-Type: application/pkcs7-signature\n");
    ASSERT_TRUE(validate(c, "dds")) << "the files should pass the checks before the CA is read";

    const auto sut = Bus::create(c);
    for (const char* name : {"ca.pem", "cert.pem", "key.pem", "governance.p7s", "permissions.p7s"}) {
        ::unlink((dir + "/" + name).c_str());
    }
    ::rmdir(dir.c_str());

    ASSERT_FALSE(sut);
    EXPECT_EQ(sut.error().where, "dds.security.identity_ca");
    EXPECT_NE(sut.error().what.find("cannot read a certificate from '" + c.security.identityCa + "'"),
              std::string::npos)
        << sut.error().message();
    EXPECT_NE(sut.error().fix.find("make_security.sh"), std::string::npos) << sut.error().message();
}

TEST(BusSecurity, TheIdentityMustNameAPartition)
{
    for (const char* bad : {"", "ugv 1", "a.b", "ugv*"}) {
        EXPECT_FALSE(checkIdentity(bad, "id")) << bad;
    }
    EXPECT_TRUE(checkIdentity("ugv-1", "id"));
    EXPECT_FALSE(checkIdentity(std::string(kMaxNameLength + 1, 'u'), "id"));
}

TEST(BusTopics, ShortAndWireNamesParse)
{
    BusConfig c = good();
    c.rosNamespace = "team/ugv7";
    for (int i = 0; i < kTopicCount; ++i) {
        const auto id = static_cast<TopicId>(i);
        TopicId byShort{};
        TopicId byWire{};
        EXPECT_TRUE(parseTopic(shortName(id), c, byShort)) << shortName(id);
        EXPECT_TRUE(parseTopic(topicName(id, c), c, byWire)) << topicName(id, c);
        EXPECT_EQ(byShort, id);
        EXPECT_EQ(byWire, id);
    }
    EXPECT_EQ(topicName(TopicId::RosScan, c), "rt/team/ugv7/obstacle_scan");
    EXPECT_EQ(topicName(TopicId::Observation, c), "ugvsense/ooi/observations");
    TopicId unused{};
    EXPECT_FALSE(parseTopic("observation", c, unused));           // singular: not a name
    EXPECT_FALSE(parseTopic("rt/ugv1/obstacle_scan", c, unused)); // another vehicle's namespace
}

} // namespace
} // namespace ugv::ipc::dds
