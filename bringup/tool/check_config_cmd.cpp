// ugvsense check-config: validate a service config file in full and print the effective config.

#include <iostream>

#include "args.hpp"
#include "commands.hpp"
#include "ugv/bringup/config.hpp"

namespace ugv::tool {

int runCheckConfig(int argc, char** argv)
{
    Args args("check-config", "[FILE] [--schema]",
              {{"schema", "", "print every key with its default, range and description, then exit", false}});
    if (auto parsed = args.parse(argc, argv, 2); !parsed) {
        return reportUsageError("check-config", parsed.error());
    }
    if (args.helpRequested()) {
        std::cout
            << args.usage()
            << "\nFILE defaults to $UGV_CONFIG, then /etc/ugvsense/config.yaml. Exit status: 0 valid, 1 invalid.\n";
        return 0;
    }
    if (args.has("schema")) {
        std::cout << bringup::formatConfig(bringup::ServiceConfig{});
        return 0;
    }
    if (args.positional().size() > 1) {
        return reportUsageError("check-config",
                                Error{"ugvsense check-config", "more than one FILE given", "give one config file"});
    }
    const std::string path = bringup::configPath(args.positional().empty() ? nullptr : args.positional()[0].c_str());
    const auto config = bringup::loadConfig(path);
    if (!config) {
        for (const auto& error : config.error()) {
            std::cerr << "error: " << error.message() << '\n';
        }
        std::cerr << path << ": " << config.error().size() << " error(s); the service would refuse to start\n";
        return 1;
    }
    std::cout << bringup::formatConfig(config.value());
    std::cerr << path << ": OK\n";
    return 0;
}

} // namespace ugv::tool
