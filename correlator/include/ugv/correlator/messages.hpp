#pragma once

/// @file
/// The correlator's inputs and outputs, as plain values. The offline tool reads and writes them as JSON lines
/// (bringup/adapters/src/correlate_io.cpp); the DDS samples carry the same fields (correlator_dds.cpp there).
///
/// Conventions: time t in seconds (the mission clock of the messages; the correlator has no clock of its own);
/// latitude/longitude in degrees WGS84; heading a compass heading (0 = north, clockwise, degrees); bearing
/// relative to the heading, positive clockwise (to the right); east/north offsets in metres.
///
/// Thread-safety: value types. RT-safe: no (strings).

#include <compare>
#include <string>
#include <variant>
#include <vector>

namespace ugv::correlator {

/// What a UGV's classifier said the object is. Combatant mobile and non-combatant objects are kept apart.
enum class OoiClass { Static, Mobile, NonCombatant, Unknown };

/// The operator's verdict on a correlated object.
enum class Confirmation { Unknown, ConfirmedPositive, ConfirmedNegative };

struct Observation {
    double t = 0.0;
    std::string ugv;   ///< reporting vehicle
    std::string track; ///< that vehicle's track UUID (changes when it loses and re-acquires the object)
    OoiClass cls = OoiClass::Unknown;
    double ugvLat = 0.0;        ///< [deg]
    double ugvLon = 0.0;        ///< [deg]
    double ugvHeadingDeg = 0.0; ///< [deg] compass, clockwise from north
    double rangeM = 0.0;        ///< [m]
    double bearingDeg = 0.0;    ///< [deg] relative to the heading, clockwise
};

/// An overhead fix of a mobile OOI (treated as ground truth).
struct UavFix {
    double t = 0.0;
    OoiClass cls = OoiClass::Mobile;
    double lat = 0.0;
    double lon = 0.0;
};

struct Confirm {
    double t = 0.0;
    std::string id; ///< correlator object id
    Confirmation state = Confirmation::Unknown;
};

/// The map builder's correction of one UGV's pose for its observations in [sinceT, untilT].
struct PoseCorrection {
    double t = 0.0;
    std::string ugv;
    double sinceT = 0.0;
    double untilT = 0.0;
    double dEastM = 0.0;
    double dNorthM = 0.0;
    double dHeadingDeg = 0.0;
};

using Message = std::variant<Observation, UavFix, Confirm, PoseCorrection>;

/// Where a message goes in the order the correlator applies messages in: by time; at equal times UGV by UGV (by
/// name) its pose correction, then its observations; then UAV fixes; then confirmations (by object id). The
/// scenario generator writes this order, the live task releases it and CorrelatorFeed re-sequences into it, so the
/// correlated list does not depend on the order of arrival. Messages with equal keys keep the order they came in
/// (one sender's, which reliable delivery keeps).
struct OrderKey {
    double t = 0.0;
    int group = 0; ///< 0 a UGV's, 1 UAV fixes, 2 confirmations
    std::string name;
    int rank = 0; ///< in a UGV's group: 0 pose correction, 1 observation
    friend auto operator<=>(const OrderKey&, const OrderKey&) = default;
};
[[nodiscard]] OrderKey orderKey(const Message& message);
/// orderKey(a) < orderKey(b)
[[nodiscard]] bool appliedBefore(const Message& a, const Message& b);

/// Activation (keep-out) zone diameters from the original requirements.
inline constexpr double kStaticZoneDiameterM = 5.0;
inline constexpr double kMobileZoneDiameterM = 20.0;

struct ObjectEstimate {
    std::string id;
    OoiClass cls = OoiClass::Unknown;
    double lat = 0.0;
    double lon = 0.0;
    double sigmaMajorM = 0.0;
    double sigmaMinorM = 0.0;
    double majorAxisDeg = 0.0; ///< [deg] compass direction of the major axis, 0..180
    Confirmation state = Confirmation::Unknown;
    int observations = 0;
    std::vector<std::string> ugvs; ///< vehicles that reported it, sorted
    double zoneDiameterM = 0.0;    ///< activation area (5 m static, 20 m mobile)
};

/// A non-combatant inside an OOI's alert distance (20 m of a mobile OOI, 5 m of a static one).
struct Alert {
    std::string nonCombatantId;
    std::string objectId;
    double distanceM = 0.0;
};

struct Snapshot {
    double t = 0.0;
    std::vector<ObjectEstimate> objects;
    std::vector<Alert> alerts;
};

[[nodiscard]] const char* toString(OoiClass c) noexcept;
[[nodiscard]] const char* toString(Confirmation c) noexcept;

} // namespace ugv::correlator
