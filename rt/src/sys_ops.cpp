#include "ugv/rt/sys_ops.hpp"

#include <malloc.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>

namespace ugv::rt {
namespace {

int lockAllReal(int flags)
{
    return ::mlockall(flags) == 0 ? 0 : errno;
}
int mallocOptionReal(int option, int value)
{
    // NOLINTNEXTLINE(concurrency-mt-unsafe): lockMemory's contract: at init, from one thread (ugv/rt/memory.hpp)
    return ::mallopt(option, value) == 1 ? 0 : EINVAL;
}

} // namespace

SysOps realSysOps() noexcept
{
    return SysOps{&::pthread_setschedparam, &::pthread_setaffinity_np, &lockAllReal, &mallocOptionReal};
}

const char* schedFixHint(int error) noexcept
{
    if (error == EPERM) {
        return "run as root or grant CAP_SYS_NICE (systemd: AmbientCapabilities=CAP_SYS_NICE, LimitRTPRIO=99)";
    }
    return "check the task table against this machine (CPU count, priority range)";
}

std::string errnoText(int error)
{
    const char* description = ::strerrordesc_np(error); // thread-safe, unlike strerror
    const char* name = ::strerrorname_np(error);
    return std::string(description != nullptr ? description : "unknown error") + " (" +
           (name != nullptr ? std::string(name) : "errno " + std::to_string(error)) + ")";
}

} // namespace ugv::rt
