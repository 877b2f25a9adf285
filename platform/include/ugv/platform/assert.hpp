#pragma once

/// @file
/// Contract checks for programming errors only (never for input validation: bad input returns a Result error).
/// A failed check prints the condition, file and line to stderr and aborts; systemd then restarts the service.
/// Thread-safety: reentrant. RT-safe: yes until it fires (then the process ends anyway).

namespace ugv::platform::detail {
[[noreturn]] void contractFailed(const char* kind, const char* condition, const char* file, int line) noexcept;
} // namespace ugv::platform::detail

#define UGV_ASSERT(cond)                                                                                               \
    ((cond) ? static_cast<void>(0) : ::ugv::platform::detail::contractFailed("assertion", #cond, __FILE__, __LINE__))
#define UGV_EXPECTS(cond)                                                                                              \
    ((cond) ? static_cast<void>(0) : ::ugv::platform::detail::contractFailed("precondition", #cond, __FILE__, __LINE__))
#define UGV_ENSURES(cond)                                                                                              \
    ((cond) ? static_cast<void>(0)                                                                                     \
            : ::ugv::platform::detail::contractFailed("postcondition", #cond, __FILE__, __LINE__))
