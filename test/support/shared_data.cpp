#include "shared_data.hpp"

#include <cstdlib>

namespace ugv::test {
namespace {

std::filesystem::path sharedRoot()
{
    if (const char* env = std::getenv("UGV_SHARED_DATA"); env != nullptr && *env != '\0') { // read-only, before threads
        return env;
    }
    return UGV_SHARED_DATA_DEFAULT;
}

} // namespace

std::optional<std::filesystem::path> sharedData(const std::string& sub)
{
    std::error_code ec;
    const auto path = sharedRoot() / sub;
    if (std::filesystem::is_directory(path, ec)) {
        return path;
    }
    return std::nullopt;
}

std::string sharedDataMissingMessage(const std::string& sub)
{
    return "shared test data '" + sub + "' not found under '" + sharedRoot().string() +
           "'; set UGV_SHARED_DATA=/path/to/shared/data to run this test";
}

} // namespace ugv::test
