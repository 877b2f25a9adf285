#pragma once

/// @file
/// The DDS options that `ugvsense listen` and `ugvsense bus-send` share (--domain, --partition, --ros-namespace,
/// --discovery-server, --no-shm) and their checks. Header-only: the two commands are the only users. Init-time only
/// (allocates).

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "ugv/ipc/dds_bus.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/tool/args.hpp"
#include "ugv/tool/stop_signal.hpp"

namespace ugv::tool::bus {

inline constexpr int kMaxDomainId = ipc::dds::kMaxDomainId;

/// The option specs, to append to a command's own.
inline std::vector<OptionSpec> options()
{
    return {
        {"domain", "N", "DDS domain id 0..232, default $UGV_DDS_DOMAIN, else $ROS_DOMAIN_ID, else 0", false},
        {"partition", "P[,P...]", "DDS partition(s) of our topics (a team, a test), default none", false},
        {"ros-namespace", "NS", "namespace of the ROS 2 topics rt/NS/obstacle_scan..., default ugv1", false},
        {"discovery-server", "LIST", "IP:PORT[;IP:PORT...] of Fast DDS discovery servers, default multicast discovery",
         false},
        {"no-shm", "", "UDP only, no Fast DDS shared memory (processes of one host in separate network namespaces)",
         false},
        {"security", "DIR",
         "secured bus (DDS Security) with a participant's files from bringup/deploy/security/make_security.sh: DIR "
         "holds identity_ca.cert.pem, cert.pem, key.pem, permissions_ca.cert.pem, governance.p7s, permissions.p7s",
         false},
        {"identity", "NAME", "the name in --security's certificate (its CN), default DIR's last folder name", false}};
}

/// Bus::followNetworkChanges() on a command's loop, saying on stderr what it did (`listen`, `correlate --from-dds`).
inline void followNetworkChanges(ipc::dds::Bus& bus)
{
    const ipc::dds::NetworkChange change = bus.followNetworkChanges();
    if (change == ipc::dds::NetworkChange::Followed) {
        std::cerr << "note: " << ipc::dds::kNetworkFollowedNote << '\n';
    } else if (change == ipc::dds::NetworkChange::Failed) {
        std::cerr << "error: " << ipc::dds::kNetworkFailedPrefix << bus.lastNetworkError().message() << '\n';
    }
}

/// What rejoinIfStalled() did.
enum class Rejoin : std::uint8_t { NotNeeded, Joined, Failed };

/// For a command still waiting for what it expects (bus-send's readers, listen's first sample): Bus::rejoinIfStalled()
/// (a secured handshake with a peer of this team's CA unfinished after 10 s: Fast DDS 2.9.1 sometimes stalls two
/// participants that join at the same moment, for good; a new participant's handshakes start afresh), saying on
/// stderr what it did.
inline Rejoin rejoinIfStalled(ipc::dds::Bus& bus, const std::string& command)
{
    const ipc::dds::StallRejoin r = bus.rejoinIfStalled();
    if (r.outcome == ipc::dds::StallRejoin::None) {
        return Rejoin::NotNeeded;
    }
    std::cerr << "ugvsense " << command << ": warning: still waiting; " << ipc::dds::describe(r) << '\n';
    return r.outcome == ipc::dds::StallRejoin::Failed ? Rejoin::Failed : Rejoin::Joined;
}

/// --security DIR [--identity NAME]: the files of one participant (ipc::dds::securityFromFolder).
inline ipc::dds::SecurityConfig securityFrom(const Args& args)
{
    if (!args.has("security")) {
        return {};
    }
    std::string dir = args.get("security");
    while (dir.size() > 1 && dir.back() == '/') {
        dir.pop_back();
    }
    return ipc::dds::securityFromFolder(dir, args.get("identity", dir.substr(dir.find_last_of('/') + 1)));
}

/// The domain without --domain: $UGV_DDS_DOMAIN, else ROS 2's $ROS_DOMAIN_ID, else 0.
inline Result<double, Error> environmentDomain()
{
    for (const char* var : {"UGV_DDS_DOMAIN", "ROS_DOMAIN_ID"}) {
        const auto domain = ipc::dds::domainFromEnvironment(var);
        if (!domain) {
            return Unexpected(domain.error());
        }
        if (domain->has_value()) {
            return static_cast<double>(**domain);
        }
    }
    return 0.0;
}

/// The bus settings of the command line; errors name the option (or UGV_DDS_DOMAIN) and how to fix it.
inline Result<ipc::dds::BusConfig, Error> configFrom(const Args& args, const std::string& command,
                                                     const std::string& participant)
{
    ipc::dds::BusConfig config;
    config.participantName = participant;
    const auto fallback = environmentDomain();
    if (!fallback) {
        return Unexpected(fallback.error());
    }
    const auto domain = args.number("domain", *fallback, 0, kMaxDomainId);
    if (!domain) {
        return Unexpected(domain.error());
    }
    if (static_cast<double>(static_cast<int>(*domain)) != *domain) {
        return Unexpected(Error{"ugvsense " + command + " --domain", "bad value '" + args.get("domain") + "'",
                                "give a whole number in [0, 232]"});
    }
    config.domainId = static_cast<int>(*domain);
    if (args.has("partition")) {
        const std::string list = args.get("partition");
        std::size_t from = 0;
        while (true) {
            const std::size_t comma = list.find(',', from);
            config.partitions.push_back(
                list.substr(from, comma == std::string::npos ? std::string::npos : comma - from));
            if (comma == std::string::npos) {
                break;
            }
            from = comma + 1;
        }
    }
    config.rosNamespace = args.get("ros-namespace", config.rosNamespace);
    config.discoveryServers = args.get("discovery-server");
    config.sharedMemory = !args.has("no-shm");
    config.security = securityFrom(args);
    if (auto ok = ipc::dds::validate(config, "ugvsense " + command); !ok) {
        // validate() names the service's config keys; on the command line they are options.
        Error e = ok.error();
        const std::string prefix = "ugvsense " + command;
        if (e.where == prefix + " vehicle") {
            e.where = prefix + " --ros-namespace";
        } else if (e.where == prefix + " partitions") {
            e.where = prefix + " --partition";
        } else if (e.where == prefix + " discovery_server") {
            e.where = prefix + " --discovery-server";
        } else if (e.where == prefix + " domain_id") {
            e.where = prefix + " --domain";
        } else if (e.where.rfind(prefix + " security", 0) == 0) {
            e.where = prefix + (e.where == prefix + " security identity" ? " --identity" : " --security");
        }
        return Unexpected(e);
    }
    return config;
}

/// "domain 7, partition 'a,b'" (for messages).
inline std::string describe(const ipc::dds::BusConfig& config)
{
    std::string text = "domain " + std::to_string(config.domainId);
    if (config.partitions.empty()) {
        text += ", default partition";
    } else {
        text += ", partition '";
        for (std::size_t i = 0; i < config.partitions.size(); ++i) {
            text += (i == 0 ? "" : ",") + config.partitions[i];
        }
        text += "'";
    }
    if (!config.discoveryServers.empty()) {
        text += ", discovery server " + config.discoveryServers;
    }
    if (config.security.enabled) {
        text += ", secured as '" + config.security.identity + "'";
    }
    return text;
}

} // namespace ugv::tool::bus
