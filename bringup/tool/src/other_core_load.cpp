#include "ugv/tool/other_core_load.hpp"

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cstdint>
#include <string>
#include <vector>

#include "ugv/hal/sys_call.hpp"

// NOLINTNEXTLINE(cppcoreguidelines-avoid-non-const-global-variables): POSIX's
extern char** environ; // posix_spawnp's environment

namespace ugv::tool {

OtherCoreLoad::~OtherCoreLoad()
{
    if (pid_ > 0) {
        ::kill(pid_, SIGTERM);
        int status = 0;
        ::waitpid(pid_, &status, 0);
    }
}

Result<void, Error> OtherCoreLoad::start(int cpu, double seconds)
{
    const std::string cpuText = std::to_string(cpu);
    const std::string timeout = std::to_string(static_cast<std::int64_t>(seconds) + 60) + "s";
    std::vector<std::string> words{"stress-ng", "--cpu", "1", "--taskset", cpuText, "--timeout", timeout, "--quiet"};
    std::vector<char*> argv;
    argv.reserve(words.size() + 1);
    for (std::string& word : words) {
        argv.push_back(word.data());
    }
    argv.push_back(nullptr);
    const int rc = ::posix_spawnp(&pid_, "stress-ng", nullptr, nullptr, argv.data(), environ);
    if (rc != 0) {
        pid_ = 0;
        return Unexpected(Error{"stress-ng", std::string("cannot start it: ") + hal::SysError{rc}.text(),
                                "install it (apt-get install stress-ng; toolchain/host.sh deps does), or leave out "
                                "--load-other-core"});
    }
    return {};
}

bool OtherCoreLoad::running()
{
    if (pid_ <= 0) {
        return false;
    }
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == 0) {
        return true;
    }
    pid_ = 0; // reaped (or not ours any more): nothing left to end
    return false;
}

} // namespace ugv::tool
