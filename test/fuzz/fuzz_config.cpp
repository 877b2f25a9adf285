// Fuzz target: the service config (YAML text) as ugvsensed and `ugvsense check-config` read it.
#include <cstddef>
#include <cstdint>
#include <string>

#include "ugv/adapters/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    const auto parsed = ugv::adapters::parseConfig(text, "fuzz.yaml", "/nonexistent");
    if (parsed) {
        (void)ugv::adapters::formatConfig(*parsed);
    }
    return 0;
}
