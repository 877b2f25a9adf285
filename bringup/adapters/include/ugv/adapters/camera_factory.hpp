#pragma once

/// @file
/// The camera the config names (camera.backend): replay (camera.replay_path at camera.replay_pace), v4l2
/// (camera.left_device/right_device, width, height, fps, format, max_pair_skew_ms), libcamera (the same keys; the
/// devices are libcamera camera ids, or /dev/ paths for "the first and second camera"; an empty right device means
/// one side-by-side camera), or a recording given on the command line (`--replay REC`), which overrides the config.
///
/// Thread-safety: reentrant. RT-safe: no (init).

#include <memory>
#include <string>

#include "ugv/adapters/config.hpp"
#include "ugv/hal/replay_camera.hpp"
#include "ugv/hal/stereo_camera.hpp"
#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::adapters {

/// @param[in] replayPath  a recording to replay instead of the configured camera (empty: the config decides)
/// @param[in] replay      pace and looping for `replayPath`
Result<std::unique_ptr<hal::StereoCamera>, Error> openCamera(const ServiceConfig& config, const std::string& replayPath,
                                                             const hal::ReplayOptions& replay);

} // namespace ugv::adapters
