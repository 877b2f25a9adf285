#pragma once

// Rules both correlator modes share (internal): which classes move, the initial confirmation, its inheritance on
// merges, an object's identity, track keys, a published object's common fields, and the non-combatant alerts of a
// snapshot.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ugv/correlator/gaussian_mixture.hpp"
#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/messages.hpp"

namespace ugv::correlator::rules {

inline constexpr double kNonCombatantStaticAlertM = 5.0;
inline constexpr double kNonCombatantMobileAlertM = 20.0;

inline bool isMobileClass(OoiClass c) noexcept
{
    return c == OoiClass::Mobile || c == OoiClass::NonCombatant;
}

/// Non-combatants start confirmed negative (not a threat); everything else unknown until the operator says.
inline Confirmation initialState(OoiClass c) noexcept
{
    return c == OoiClass::NonCombatant ? Confirmation::ConfirmedNegative : Confirmation::Unknown;
}

/// A confirmed state wins over unknown; otherwise the kept object's state stays.
inline Confirmation inherit(Confirmation kept, Confirmation absorbed) noexcept
{
    return kept == Confirmation::Unknown ? absorbed : kept;
}

/// What every correlated object carries, in both modes and of both kinds: its published id, its creation order (a
/// merge keeps the earlier), class, confirmation, and whether it is still an object of its own (false once merged).
struct Identity {
    std::string id;
    std::uint64_t order = 0;
    OoiClass cls = OoiClass::Static;
    Confirmation state = Confirmation::Unknown;
    bool alive = true;
};

/// Gives a new object its identity: the id and order as issued, its class, and `state` (by default the class's
/// initial confirmation).
inline void identify(Identity& object, std::string id, std::uint64_t order, OoiClass cls, Confirmation state)
{
    object = Identity{std::move(id), order, cls, state, true};
}
inline void identify(Identity& object, std::string id, std::uint64_t order, OoiClass cls)
{
    identify(object, std::move(id), order, cls, initialState(cls));
}

inline std::string trackKey(const std::string& ugv, const std::string& track)
{
    return ugv + '\x1f' + track;
}

/// A published object as both modes fill it: id, class, confirmation, position (local frame -> WGS84), error
/// ellipse and the safety zone of its class; the caller adds the observation count and the sources.
inline ObjectEstimate estimateOf(const LocalFrame& frame, const Eigen::Vector2d& position, const Ellipse& ellipse,
                                 const std::string& id, OoiClass cls, Confirmation state)
{
    ObjectEstimate e;
    e.id = id;
    e.cls = cls;
    frame.toLatLon(position, e.lat, e.lon);
    e.sigmaMajorM = ellipse.sigmaMajor;
    e.sigmaMinorM = ellipse.sigmaMinor;
    e.majorAxisDeg = ellipse.majorAxisDeg;
    e.state = state;
    e.zoneDiameterM = isMobileClass(cls) ? kMobileZoneDiameterM : kStaticZoneDiameterM;
    return e;
}

/// (position in the local frame, index in snapshot.objects)
using Placed = std::vector<std::pair<Eigen::Vector2d, std::size_t>>;

/// An alert for every non-combatant within 20 m of a mobile OOI or 5 m of a static one.
inline void appendAlerts(Snapshot& s, const Placed& civilians, const Placed& threats)
{
    for (const auto& [pc, ci] : civilians) {
        for (const auto& [pt, ti] : threats) {
            const double limit =
                s.objects[ti].cls == OoiClass::Mobile ? kNonCombatantMobileAlertM : kNonCombatantStaticAlertM;
            const double d = (pc - pt).norm();
            if (d <= limit) {
                s.alerts.push_back(Alert{s.objects[ci].id, s.objects[ti].id, d});
            }
        }
    }
}

} // namespace ugv::correlator::rules
