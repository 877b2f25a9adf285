#pragma once

/// @file
/// Shared pieces of the `ugvsense detect` and `ugvsense eval` commands: the detector configuration of the tool,
/// cv::Mat <-> ImageView glue, a ground-plane fit for calibrations without a mount, and sector naming / JSON.
/// Host tool only: everything here may allocate. Thread-safety: reentrant.

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "ugv/platform/error.hpp"
#include "ugv/platform/frame_header.hpp"
#include "ugv/platform/image_view.hpp"
#include "ugv/platform/obstacle_sectors.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/platform/sectors_json.hpp" // stateName, kindName, className, jsonNumber, sectorsJsonArray
#include "ugv/vision/colour_free_space.hpp"
#include "ugv/vision/ground_plane.hpp"
#include "ugv/vision/obstacle_detector.hpp"
#include "ugv/vision/rectifier.hpp"
#include "ugv/vision/sector_builder.hpp"
#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::tool {

struct DetectionOptions {
    int sectorCount = 64;
    float dangerM = 1.5F;                                                          ///< [m]
    float cautionM = 5.0F;                                                         ///< [m]
    float maxRangeDisparityPx = vision::SectorBuilderConfig{}.maxRangeDisparityPx; ///< [px] the reach: f B / this
};

/// The vision library's detector defaults with the sector count, danger distances and reach of `options`.
vision::DetectorConfig detectorConfig(const DetectionOptions& options);

/// Read-only view of a continuous or strided CV_8UC1 matrix (the matrix must outlive the view).
ConstImageViewU8 viewOf(const cv::Mat& grey);

/// Read-only view of a CV_8UC3 BGR matrix, for vision::ColourFreeSpace (the matrix must outlive the view).
ConstBgrView bgrViewOf(const cv::Mat& bgr);

/// A cv::Mat over one image of a frame, without a copy: CV_8UC1 (grey) or CV_8UC3 (BGR), empty for a missing right
/// image. Treat it as read only; it lives as long as the frame's buffer.
cv::Mat matOver(const StereoViews& images, bool right);

/// A ground plane fitted to a disparity map without a prior (calibration without a mount).
struct GroundFit {
    vision::DisparityPlane plane; ///< full-frame d = a x + b y + c [px]
    vision::GroundPlane ground;
    int samples = 0; ///< valid disparity samples in the fitted rows
    int inliers = 0;
};

/// RANSAC fit of d = a x + b y + c to the valid disparities of the bottom third of the image (sampled every
/// 4 px), refined by least squares on the inliers (|residual| <= 1 px). Fails with an explanation when there
/// are too few samples or inliers (< 300 or < 30 %), or when the plane is not a plausible ground (camera
/// height outside (0.05, 10] m, pitch beyond +-45 deg, roll beyond +-30 deg).
/// @param[in] disparity16  CV_16S disparity of the ROI rows (x16, invalid < 0), as RoiMatcher gives it
/// @param[in] roi          full-frame rectangle of those rows
Result<GroundFit, Error> fitGround(const cv::Mat& disparity16, Rect roi, const vision::RectifiedProjection& projection);

/// One stereo pair through the tool's detector (`detect`, `eval --real`): the ROI rectified, the ground of the
/// calibration's mount (or, without one, fitGround() on the ROI's disparity), the detector run once.
struct PairDetection {
    std::optional<vision::Rectifier> rectifier; ///< the ROI rectifier (its images are the detector's input)
    std::optional<vision::ObstacleDetector> detector;
    std::optional<GroundFit> fit; ///< set when the calibration has no mount and the ground was fitted
};

/// @param[in] left, right  8-bit grey images of calib.imageSize
/// @param[in] calibName    named in errors (the file, or the data set's pair)
/// @return the detector after process() with status Ok, or what failed (rectification, ground fit, pipeline).
/// With config.matcher.groundRange the pair is processed twice: the second frame searches from the first's ground.
Result<PairDetection, Error> detectPair(const vision::StereoCalibration& calib, const cv::Mat& left,
                                        const cv::Mat& right, const vision::DetectorConfig& config,
                                        const std::string& calibName);

/// The colour of a danger class in overlays (BGR).
cv::Scalar dangerColour(DangerClass danger);

/// The rectified left image in colour (identity for the rectified form; each channel remapped otherwise) with
/// the obstacle pixels of the dense cue tinted (above the ground: red, below: blue) and a bar of the sectors'
/// danger classes below it, each sector over the columns of its bearings.
cv::Mat makeOverlay(const cv::Mat& colourLeft, vision::Rectifier& fullRectifier, const vision::ObstacleDetector& det,
                    const vision::DetectorConfig& config, const vision::RectifiedProjection& p);

/// Appends a bar of kBarHeightPx rows below `canvas` with one colour per sector over the columns of its bearings.
cv::Mat appendSectorBar(const cv::Mat& canvas, const ObstacleSectors& layout, const std::vector<cv::Scalar>& colours,
                        const vision::RectifiedProjection& p);

} // namespace ugv::tool
