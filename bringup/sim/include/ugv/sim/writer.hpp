#pragma once

/// @file
/// Writes a rendered sample and the rig's calibration to disk (host tooling; uses OpenCV imgcodecs).
///
/// Files for `stem` in `dir`:
/// - `<stem>_left.png`, `<stem>_right.png`: 8-bit grey images.
/// - `<stem>_left_colour.png`: the left image in colour (8-bit BGR; its luminance is `<stem>_left.png`).
/// - `<stem>_disparity.png`: 16-bit, value = round(disparity [px] * 256); 0 = sky (no disparity).
/// - `<stem>_depth.png`: 16-bit, value = round(Z [mm]); 0 = sky; saturates at 65535 (65.535 m).
/// - `<stem>_labels.png` (8-bit, values of sim::Label) and `<stem>_ids.png` (16-bit obstacle index + 1).
/// - `<stem>_sectors.json`: the ground-truth sectors.
/// - `calibration.yaml`: see writeCalibration().
///
/// Thread-safety: reentrant (distinct paths). RT-safe: no.

#include <filesystem>
#include <string>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"
#include "ugv/sim/renderer.hpp"
#include "ugv/sim/scene.hpp"

namespace ugv::sim {

/// Value scale of `<stem>_disparity.png`: stored = round(disparity [px] * kDisparityScale).
inline constexpr double kDisparityScale = 256.0;
/// Value scale of `<stem>_depth.png`: stored = round(Z [m] * kDepthScale), i.e. millimetres.
inline constexpr double kDepthScale = 1000.0;

/// The calibration of the rig as the text of `calibration.yaml` (see writeCalibration()).
[[nodiscard]] std::string calibrationText(const Rig& rig);

/// Writes `calibration.yaml` into `dir`: the already-rectified form (cv::FileStorage YAML) with the keys
/// schema_version (1), rectified (1), image_width, image_height, fx, fy, cx, cy, baseline_m and a `mount` map
/// with height_m, pitch_deg, roll_deg.
/// @return nothing, or an Error naming the file when it cannot be written.
[[nodiscard]] Result<void, Error> writeCalibration(const Rig& rig, const std::filesystem::path& dir);

/// The sectors as JSON: {"count": N, "sectors": [{bearing_min_deg, bearing_max_deg, range_m (null when
/// +inf), kind ("none"|"positive"|"negative"), state ("unknown"|"clear"|"obstacle"), class
/// ("unknown"|"green"|"blue"|"red"), height_m}, ...]}.
[[nodiscard]] std::string sectorsJson(const ObstacleSectors& sectors);

/// Writes all files of one sample (and calibration.yaml) into the existing directory `dir`.
/// @return nothing, or an Error naming the first file that could not be written (missing directory, ...).
[[nodiscard]] Result<void, Error> writeSample(const RenderResult& sample, const Rig& rig,
                                              const std::filesystem::path& dir, const std::string& stem);

} // namespace ugv::sim
