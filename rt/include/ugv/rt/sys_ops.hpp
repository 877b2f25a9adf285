#pragma once

/// @file
/// `ugv::rt::SysOps`: the OS calls that apply real-time settings, as a seam. Production uses realSysOps();
/// tests pass functions that fail with EPERM to exercise the degrade paths without changing the machine.
/// Every function returns 0 on success or an errno value (never -1), whatever the underlying call does.
///
/// Thread-safety: a value type of function pointers. RT-safe: not used on the frame path.

#include <pthread.h>
#include <sched.h>

#include <cstddef>
#include <string>

namespace ugv::rt {

struct SysOps {
    int (*setSchedParam)(pthread_t thread, int policy, const sched_param* param);    ///< pthread_setschedparam
    int (*setAffinity)(pthread_t thread, std::size_t setSize, const cpu_set_t* set); ///< pthread_setaffinity_np
    int (*lockAll)(int flags);                                                       ///< mlockall
    int (*mallocOption)(int option, int value); ///< mallopt (0 = success, EINVAL when glibc refuses)
};

/// The real calls. Thread-safety: reentrant. RT-safe: yes.
[[nodiscard]] SysOps realSysOps() noexcept;

/// "run as root, or grant CAP_SYS_NICE (systemd: LimitRTPRIO=99)" for EPERM, and a generic hint otherwise.
/// Thread-safety: reentrant. RT-safe: yes.
[[nodiscard]] const char* schedFixHint(int error) noexcept;

} // namespace ugv::rt

namespace ugv::rt {

/// "Operation not permitted (EPERM)"-style text of an errno value. Thread-safety: reentrant. RT-safe: no.
[[nodiscard]] std::string errnoText(int error);

} // namespace ugv::rt
