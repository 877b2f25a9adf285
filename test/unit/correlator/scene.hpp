#pragma once

// Test scenes of the correlator: observations of local points (east, north) [m] from UGVs at local positions,
// through the real geodesy. headingErrorDeg is added to the reported heading (the bearing is measured from the
// true one), offset to the reported position.

#include <cmath>
#include <string>

#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/messages.hpp"

namespace ugv::correlator::test {

/// The snapshot at t once the correlator has advanced to t (what CorrelatorFeed does at every period boundary).
template <class Correlator>
Snapshot snapshotAt(Correlator& sut, double t)
{
    sut.advance(t);
    return sut.snapshot(t);
}

class Scene {
public:
    static constexpr double kLat0 = -34.9;
    static constexpr double kLon0 = 138.6;

    Scene() : frame_(kLat0, kLon0) {}

    [[nodiscard]] Observation see(double t, const std::string& ugv, const std::string& track, OoiClass cls,
                                  const Eigen::Vector2d& ugvAt, const Eigen::Vector2d& object,
                                  double headingErrorDeg = 0.0, const Eigen::Vector2d& offset = Eigen::Vector2d::Zero(),
                                  double trueHeadingDeg = 20.0) const
    {
        constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;
        Observation o;
        o.t = t;
        o.ugv = ugv;
        o.track = track;
        o.cls = cls;
        frame_.toLatLon(ugvAt + offset, o.ugvLat, o.ugvLon);
        o.ugvHeadingDeg = trueHeadingDeg + headingErrorDeg;
        const Eigen::Vector2d d = object - ugvAt;
        o.rangeM = d.norm();
        o.bearingDeg = std::atan2(d.x(), d.y()) * kRadToDeg - trueHeadingDeg;
        return o;
    }
    [[nodiscard]] Eigen::Vector2d local(const ObjectEstimate& e) const { return frame_.toLocal(e.lat, e.lon); }
    void latLon(const Eigen::Vector2d& en, double& lat, double& lon) const { frame_.toLatLon(en, lat, lon); }

private:
    LocalFrame frame_;
};

} // namespace ugv::correlator::test
