#include "ugv/hal/sys_call.hpp"

#include <cstring>

namespace ugv::hal {

const char* SysError::text() const noexcept
{
    return ::strerrordesc_np(code) != nullptr ? ::strerrordesc_np(code) : "unknown error";
}

const char* SysError::name() const noexcept
{
    return ::strerrorname_np(code) != nullptr ? ::strerrorname_np(code) : "errno";
}

} // namespace ugv::hal
