#include "ugv/correlator/messages.hpp"

namespace ugv::correlator {

const char* toString(OoiClass c) noexcept
{
    switch (c) {
    case OoiClass::Static:
        return "static";
    case OoiClass::Mobile:
        return "mobile";
    case OoiClass::NonCombatant:
        return "noncombatant";
    case OoiClass::Unknown:
        break;
    }
    return "unknown";
}

const char* toString(Confirmation c) noexcept
{
    switch (c) {
    case Confirmation::ConfirmedPositive:
        return "confirmed_positive";
    case Confirmation::ConfirmedNegative:
        return "confirmed_negative";
    case Confirmation::Unknown:
        break;
    }
    return "unknown";
}

} // namespace ugv::correlator
