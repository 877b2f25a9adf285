#pragma once

/// @file
/// The settings of mode `pose-corrected` (PoseCorrectedCorrelator and its parts).

#include <cstddef>

#include "ugv/correlator/measurement_model.hpp"

namespace ugv::correlator {

struct PoseCorrectedConfig {
    // Observation error model.
    double rangeSigmaM = 0.1;
    double rangeSigmaFraction = 0.01;
    double bearingSigmaDeg = 1.0;
    // Pose error priors and the drift model.
    double headingBiasSigmaDeg = 5.0;
    double offsetSigmaM = 1.0;
    double driftSigmaMPerSqrtS = 0.05;
    double offsetWindowS = 60.0;
    double solvePeriodS = 120.0;
    int solveIterations = 2;
    // Association.
    double gateChi2 = 11.8; ///< 2 degrees of freedom, 99.7 %
    int minStaticObservations = 3;
    double tentativeTimeoutS = 60.0;        ///< an object with fewer observations this long after its first is dropped
    std::size_t samplesPerTrackWindow = 12; ///< reservoir per track and offset window
    double horizonS = 1800.0;               ///< windows older than this are frozen and their samples dropped
    // Mobile objects.
    /// [m^2/s^3] density of the continuous white acceleration of a mobile object: people walk at a steady
    /// velocity for tens of seconds; turns are handled as manoeuvres (the velocity is re-learnt, see
    /// MobileTracker::update), not by a process noise large enough to cover them.
    double mobileAccelDensity = 0.05;
    double mobileTimeoutS = 60.0;
    int minMobileObservations = 3;
    double uavSigmaM = 0.5;

    /// The configured range and bearing noise (the floor of the learnt one).
    [[nodiscard]] RangeBearingNoise noise() const noexcept
    {
        return RangeBearingNoise{rangeSigmaM, rangeSigmaFraction, bearingSigmaDeg};
    }
};

} // namespace ugv::correlator
