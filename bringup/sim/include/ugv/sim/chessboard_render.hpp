#pragma once

/// @file
/// Renders synthetic chessboard stereo pairs seen by a known rig (host tooling for `ugvsense sim` and tests).
/// Each pixel is inverse-mapped: its (distorted) position is undistorted into a viewing ray, the ray is
/// intersected with the board plane and the square colour is sampled, supersampled 3x3 for anti-aliasing.

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace ugv::sim {

/// A stereo rig in OpenCV's conventions: X_right = R * X_left + T. Both cameras share K and distortion.
struct SimRig {
    cv::Size imageSize{640, 480};                  ///< [px]
    double fx = 546.0;                             ///< [px]
    double fy = 546.0;                             ///< [px]
    double cx = 320.0;                             ///< [px]
    double cy = 240.0;                             ///< [px]
    double k1 = -0.05;                             ///< radial distortion of both cameras
    double baselineM = 0.20;                       ///< [m]
    cv::Vec3d rightRotation{0.004, -0.012, 0.006}; ///< Rodrigues vector of R [rad]

    [[nodiscard]] cv::Mat cameraMatrix() const;
    [[nodiscard]] cv::Mat distortion() const;  ///< 1x5: k1, 0, 0, 0, 0
    [[nodiscard]] cv::Mat rotation() const;    ///< R, 3x3
    [[nodiscard]] cv::Mat translation() const; ///< T = (-baseline, 0, 0) [m], 3x1
};

struct SimBoard {
    cv::Size innerCorners{9, 6};
    double squareM = 0.025; ///< [m]
    double borderM = 0.02;  ///< white margin around the squares [m]
};

/// Board pose in the left camera frame: X_left = Rodrigues(rvec) * X_board + tvec.
struct BoardPose {
    cv::Vec3d rvec; ///< [rad]
    cv::Vec3d tvec; ///< [m]
};

/// Renders stereo pairs for one rig; the per-pixel rays are computed once.
/// Thread-safety: const methods are reentrant. RT-safe: no.
class ChessboardRenderer {
public:
    ChessboardRenderer(const SimRig& rig, const SimBoard& board);

    /// `count` varied poses (distance 0.65 to 1.1 m, tilts up to about 25 deg), deterministic for a seed,
    /// with the board in view of both cameras.
    [[nodiscard]] std::vector<BoardPose> poses(int count, std::uint64_t seed) const;

    /// Renders the board at `pose` into 8-bit grey left and right images, adding Gaussian noise of
    /// `noiseSigma` grey levels (drawn from `rng`).
    void render(const BoardPose& pose, double noiseSigma, cv::RNG& rng, cv::Mat& left, cv::Mat& right) const;

    [[nodiscard]] const SimRig& rig() const { return rig_; }

private:
    cv::Mat renderView(const cv::Matx33d& rotation, const cv::Vec3d& translation, double noiseSigma,
                       cv::RNG& rng) const;
    [[nodiscard]] bool inView(const BoardPose& pose) const;

    SimRig rig_;
    SimBoard board_;
    std::vector<cv::Vec2f> rays_; ///< normalised (x, y) of each subsample, row-major, kSamples^2 per pixel
};

} // namespace ugv::sim
