#include "ugv/rt/memory.hpp"

#include <alloca.h>
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <fstream>
#include <sstream>

#include "ugv/platform/log.hpp"

namespace ugv::rt {

MemoryReport lockMemory(const SysOps& ops)
{
    MemoryReport report;
    if (const int error = ops.lockAll(MCL_CURRENT | MCL_FUTURE); error != 0) {
        report.warnings.push_back("could not lock memory (mlockall): " + errnoText(error) +
                                  "; page faults may stall RT tasks. Fix: run as root or raise the locked-memory limit "
                                  "(systemd: LimitMEMLOCK=infinity; shell: ulimit -l unlimited)");
    } else {
        report.locked = true;
    }
    const int trimError = ops.mallocOption(M_TRIM_THRESHOLD, -1);
    const int mmapError = ops.mallocOption(M_MMAP_MAX, 0);
    if (trimError != 0 || mmapError != 0) {
        report.warnings.push_back("could not tune malloc (mallopt M_TRIM_THRESHOLD=-1 / M_MMAP_MAX=0): " +
                                  errnoText(trimError != 0 ? trimError : mmapError) +
                                  "; freed memory may return to the OS and be faulted in again. Fix: use glibc's "
                                  "malloc (no LD_PRELOAD allocator)");
    } else {
        report.mallocTuned = true;
    }
    report.lockedBytes = readLockedBytes();
    for (const std::string& warning : report.warnings) {
        UGV_LOG(Rt, Warn) << warning;
    }
    return report;
}

std::optional<std::size_t> statusBytes(std::string_view statusText, std::string_view key)
{
    constexpr std::size_t kBytesPerKb = 1024;
    std::size_t pos = statusText.find(key);
    // The key must start a line and end at its colon.
    while (pos != std::string_view::npos &&
           ((pos != 0 && statusText[pos - 1] != '\n') || statusText.substr(pos + key.size(), 1) != ":")) {
        pos = statusText.find(key, pos + 1);
    }
    if (pos == std::string_view::npos) {
        return std::nullopt;
    }
    std::string_view rest = statusText.substr(pos + key.size() + 1);
    rest.remove_prefix(std::min(rest.find_first_not_of(" \t"), rest.size()));
    std::size_t kb = 0;
    const auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), kb);
    if (ec != std::errc{} ||
        !std::string_view(end, static_cast<std::size_t>(rest.data() + rest.size() - end)).starts_with(" kB")) {
        return std::nullopt;
    }
    return kb * kBytesPerKb;
}

std::optional<std::size_t> lockedBytesFromStatus(std::string_view statusText)
{
    return statusBytes(statusText, "VmLck");
}

std::optional<std::size_t> readStatusBytes(std::string_view key)
{
    std::ifstream file("/proc/self/status");
    if (!file) {
        return std::nullopt;
    }
    std::ostringstream text;
    text << file.rdbuf();
    return statusBytes(text.view(), key);
}

std::optional<std::size_t> readLockedBytes()
{
    return readStatusBytes("VmLck");
}

std::size_t prefaultStack(std::size_t bytes) noexcept
{
    if (bytes == 0) {
        return 0;
    }
    const auto pageBytes = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
    // alloca: the touched bytes must be this function's own frame, below the caller's.
    auto* stack = static_cast<volatile unsigned char*>(::alloca(bytes));
    for (std::size_t offset = 0; offset < bytes; offset += pageBytes) {
        stack[offset] = 0;
    }
    stack[bytes - 1] = 0;
    return bytes;
}

} // namespace ugv::rt
