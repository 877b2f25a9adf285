#pragma once

/// @file
/// Mode `pose-corrected`'s UAV fixes: precise measurements of mobile objects that confirm them. The fixes of one
/// instant are held until the instant ends (a message of a later time, or advance()) and then assigned together
/// (an optimal assignment of their statistical distances), so that one object's fix cannot take the track of
/// another it passes close to. A fix outside every gate may still go to an object it could have walked to since
/// its last estimate (a turn between two fixes of an object that only the UAV sees), at a cost above every gated
/// pair; a fix cheapest alone is a new object. Each assigned fix also goes to UavAnchors (the object's absolute
/// position at that instant).
///
/// Thread-safety: thread-bound. RT-safe: no (allocates).

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "ugv/correlator/geodesy.hpp"
#include "ugv/correlator/messages.hpp"
#include "ugv/correlator/mobile_tracker.hpp"
#include "ugv/correlator/object_ids.hpp"
#include "ugv/correlator/pose_corrected_config.hpp"
#include "ugv/correlator/uav_anchors.hpp"

namespace ugv::correlator {

class UavAssignment {
public:
    explicit UavAssignment(const PoseCorrectedConfig& config);

    /// Holds `fix` with the others of its instant; a fix of a later instant first assigns those.
    void add(const UavFix& fix, const LocalFrame& frame, MobileTracker& tracker, ObjectIds& ids, UavAnchors& anchors);
    /// Fixes of an instant before `t` are held (a message at `t` ends their instant).
    [[nodiscard]] bool pendingBefore(double t) const noexcept { return !pending_.empty() && t > pending_.front().t; }
    /// Assigns the fixes held (none: nothing happens).
    void flush(const LocalFrame& frame, MobileTracker& tracker, ObjectIds& ids, UavAnchors& anchors);

private:
    /// The cost of each pending fix (rows) for a new object of its own (the first pending_.size() columns) and for
    /// each of `candidates` (the alive mobile objects, the columns after).
    [[nodiscard]] std::vector<double> costs(const std::vector<Eigen::Vector2d>& fixes,
                                            const std::vector<int>& candidates, const MobileTracker& tracker) const;

    PoseCorrectedConfig config_;
    std::vector<UavFix> pending_; ///< the fixes of the latest instant, not yet assigned
};

} // namespace ugv::correlator
