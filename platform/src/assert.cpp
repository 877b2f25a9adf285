#include "ugv/platform/assert.hpp"

#include <cstdio>
#include <cstdlib>

namespace ugv::platform::detail {

void contractFailed(const char* kind, const char* condition, const char* file, int line) noexcept
{
    // fprintf to an unbuffered stderr: no allocation, safe to call from any thread.
    (void)std::fprintf(stderr, "ugvsense: %s failed: %s (%s:%d)\n", kind, condition, file, line);
    std::abort();
}

} // namespace ugv::platform::detail
