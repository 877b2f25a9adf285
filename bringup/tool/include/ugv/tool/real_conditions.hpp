#pragma once
/// @file
/// Conditions the world can bring, applied to a real stereo pair before it is matched (`ugvsense eval --real
/// --perturb`): more sensor noise, a gain mismatch between the two cameras, defocus, underexposure, compression, and
/// another rig's resolution. The detector and the plain OpenCV baseline see the same changed images and are scored
/// against the same LiDAR truth, so a threshold that holds at one noise level, one exposure or one rig only shows.

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::tool {

/// One condition; the default changes nothing.
struct Perturbation {
    std::string name = "none"; ///< as given (e.g. "exposure:0.35+noise:3")
    double exposure = 1.0;     ///< both images scaled: below 1 underexposed (dusk, a tunnel), above 1 overexposed
    double rightGain = 1.0;    ///< the right camera's gain against the left's
    double blurSigmaPx = 0.0;  ///< Gaussian blur of both images [px] (defocus, motion)
    double noiseGrey = 0.0;    ///< Gaussian noise added to each image, drawn independently [grey levels]
    int jpegQuality = 0;       ///< both images JPEG-compressed at this quality (0: not)
    bool half = false; ///< images, truth and calibration at half resolution (another rig: half the focal length)
};

/// "none", or parts joined by '+': noise:S (0..50 grey levels), gain:G (right camera, 0.2..5), blur:S (0..10 px),
/// exposure:F (0.05..4), jpeg:Q (1..100), half. A usage error names the part and the ranges.
Result<Perturbation, Error> parsePerturbation(const std::string& text);

/// A comma-separated list of conditions; "sweep" stands for sweepConditions().
Result<std::vector<Perturbation>, Error> parsePerturbations(const std::string& list);

/// The conditions `--perturb sweep` runs: none, each kind alone at a moderate and a strong setting (JPEG at three:
/// 70, a common MJPEG setting, 50 and 20), and underexposure with the noise that comes with it.
const std::vector<std::string>& sweepConditions();

/// Applies `p` to a pair's grey images (8-bit), in the order a camera would: resolution, exposure and gain, blur,
/// noise (seeded by `seed`, each image its own draw), saturation to 8 bits, compression.
void perturbImages(const Perturbation& p, std::uint64_t seed, cv::Mat& left, cv::Mat& right);

/// The truth at half resolution for Perturbation::half: every other pixel (0 = no truth stays 0), disparities halved.
cv::Mat halveDisparityTruth(const cv::Mat& disparity);

} // namespace ugv::tool
