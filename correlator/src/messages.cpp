#include "ugv/correlator/messages.hpp"

namespace ugv::correlator {

OrderKey orderKey(const Message& message)
{
    struct Visitor {
        OrderKey operator()(const Observation& m) const { return OrderKey{m.t, 0, m.ugv, 1}; }
        OrderKey operator()(const PoseCorrection& m) const { return OrderKey{m.t, 0, m.ugv, 0}; }
        OrderKey operator()(const UavFix& m) const { return OrderKey{m.t, 1, "", 0}; }
        OrderKey operator()(const Confirm& m) const { return OrderKey{m.t, 2, m.id, 0}; }
    };
    return std::visit(Visitor{}, message);
}

bool appliedBefore(const Message& a, const Message& b)
{
    return orderKey(a) < orderKey(b);
}

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
