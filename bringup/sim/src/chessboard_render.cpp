#include "ugv/sim/chessboard_render.hpp"

#include <cmath>

#include <opencv2/calib3d.hpp>

namespace ugv::sim {
namespace {

constexpr int kSamples = 3;           // supersampling per axis
constexpr double kBackground = 110.0; // grey level around the board
constexpr double kWhite = 225.0;      // grey levels of the squares
constexpr double kBlack = 30.0;
constexpr double kMinDistanceM = 0.65; // board distance range [m]
constexpr double kMaxDistanceM = 1.10;
constexpr double kMaxTiltRad = 0.45; // about 25 deg about x and y
constexpr double kMaxSpinRad = 0.15; // about the optical axis
constexpr int kInViewMarginPx = 12;
constexpr int kMaxTries = 1000;

} // namespace

cv::Mat SimRig::cameraMatrix() const
{
    return (cv::Mat_<double>(3, 3) << fx, 0, cx, 0, fy, cy, 0, 0, 1);
}

cv::Mat SimRig::distortion() const
{
    return (cv::Mat_<double>(1, 5) << k1, 0, 0, 0, 0);
}

cv::Mat SimRig::rotation() const
{
    cv::Mat r;
    cv::Rodrigues(rightRotation, r);
    return r;
}

cv::Mat SimRig::translation() const
{
    return (cv::Mat_<double>(3, 1) << -baselineM, 0, 0);
}

ChessboardRenderer::ChessboardRenderer(const SimRig& rig, const SimBoard& board) : rig_(rig), board_(board)
{
    const int w = rig.imageSize.width;
    const int h = rig.imageSize.height;
    std::vector<cv::Point2f> pixels;
    pixels.reserve(static_cast<std::size_t>(w) * h * kSamples * kSamples);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            for (int sy = 0; sy < kSamples; ++sy) {
                for (int sx = 0; sx < kSamples; ++sx) {
                    pixels.emplace_back(static_cast<float>(x + (sx + 0.5) / kSamples - 0.5),
                                        static_cast<float>(y + (sy + 0.5) / kSamples - 0.5));
                }
            }
        }
    }
    std::vector<cv::Point2f> normalised;
    cv::undistortPoints(pixels, normalised, rig.cameraMatrix(), rig.distortion(), cv::noArray(), cv::noArray(),
                        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 50, 1e-10));
    rays_.reserve(normalised.size());
    for (const auto& p : normalised) {
        rays_.emplace_back(p.x, p.y);
    }
}

bool ChessboardRenderer::inView(const BoardPose& pose) const
{
    const double x0 = -board_.squareM - board_.borderM;
    const double y0 = x0;
    const double x1 = board_.innerCorners.width * board_.squareM + board_.borderM;
    const double y1 = board_.innerCorners.height * board_.squareM + board_.borderM;
    const std::vector<cv::Point3d> outline{{x0, y0, 0}, {x1, y0, 0}, {x1, y1, 0}, {x0, y1, 0}};
    cv::Mat rBoard;
    cv::Rodrigues(pose.rvec, rBoard);
    const cv::Mat tBoard(pose.tvec);
    cv::Mat rRight = rig_.rotation() * rBoard;
    cv::Mat tRight = rig_.rotation() * tBoard + rig_.translation();
    cv::Mat rvecRight;
    cv::Rodrigues(rRight, rvecRight);
    for (int camera = 0; camera < 2; ++camera) {
        std::vector<cv::Point2d> image;
        if (camera == 0) {
            cv::projectPoints(outline, pose.rvec, pose.tvec, rig_.cameraMatrix(), rig_.distortion(), image);
        } else {
            cv::projectPoints(outline, rvecRight, tRight, rig_.cameraMatrix(), rig_.distortion(), image);
        }
        for (const auto& p : image) {
            if (p.x < kInViewMarginPx || p.y < kInViewMarginPx || p.x > rig_.imageSize.width - kInViewMarginPx ||
                p.y > rig_.imageSize.height - kInViewMarginPx) {
                return false;
            }
        }
    }
    return true;
}

std::vector<BoardPose> ChessboardRenderer::poses(int count, std::uint64_t seed) const
{
    cv::RNG rng(seed);
    std::vector<BoardPose> result;
    const cv::Vec3d centreOnBoard((board_.innerCorners.width - 1) * board_.squareM / 2,
                                  (board_.innerCorners.height - 1) * board_.squareM / 2, 0);
    for (int tries = 0; static_cast<int>(result.size()) < count && tries < kMaxTries * count; ++tries) {
        const double z = rng.uniform(kMinDistanceM, kMaxDistanceM);
        // Between the cameras, so that both see it; wider spread when farther.
        const cv::Vec3d centre(rig_.baselineM / 2 + rng.uniform(-0.25, 0.25) * z * 0.4,
                               rng.uniform(-0.25, 0.25) * z * 0.4, z);
        const cv::Vec3d rvec(rng.uniform(-kMaxTiltRad, kMaxTiltRad), rng.uniform(-kMaxTiltRad, kMaxTiltRad),
                             rng.uniform(-kMaxSpinRad, kMaxSpinRad));
        cv::Matx33d r;
        cv::Rodrigues(rvec, r);
        const BoardPose pose{rvec, centre - r * centreOnBoard};
        if (inView(pose)) {
            result.push_back(pose);
        }
    }
    return result;
}

cv::Mat ChessboardRenderer::renderView(const cv::Matx33d& rotation, const cv::Vec3d& translation, double noiseSigma,
                                       cv::RNG& rng) const
{
    // Camera centre and ray directions in board coordinates: X_board = R^T (X_cam - t).
    const cv::Matx33d rt = rotation.t();
    const cv::Vec3d centre = -(rt * translation);
    const double x0 = -board_.squareM;
    const double y0 = -board_.squareM;
    const double x1 = board_.innerCorners.width * board_.squareM;
    const double y1 = board_.innerCorners.height * board_.squareM;
    const int w = rig_.imageSize.width;
    const int h = rig_.imageSize.height;
    cv::Mat image(rig_.imageSize, CV_8UC1);
    std::size_t k = 0;
    for (int y = 0; y < h; ++y) {
        auto* row = image.ptr<std::uint8_t>(y);
        for (int x = 0; x < w; ++x) {
            double sum = 0.0;
            for (int s = 0; s < kSamples * kSamples; ++s, ++k) {
                const cv::Vec3d dir = rt * cv::Vec3d(rays_[k][0], rays_[k][1], 1.0);
                double value = kBackground;
                if (std::abs(dir[2]) > 1e-12) {
                    const double lambda = -centre[2] / dir[2];
                    if (lambda > 0) {
                        const double bx = centre[0] + lambda * dir[0];
                        const double by = centre[1] + lambda * dir[1];
                        if (bx >= x0 && bx < x1 && by >= y0 && by < y1) {
                            const int i = static_cast<int>(std::floor(bx / board_.squareM));
                            const int j = static_cast<int>(std::floor(by / board_.squareM));
                            value = ((i + j) & 1) == 0 ? kBlack : kWhite;
                        } else if (bx >= x0 - board_.borderM && bx < x1 + board_.borderM && by >= y0 - board_.borderM &&
                                   by < y1 + board_.borderM) {
                            value = kWhite;
                        }
                    }
                }
                sum += value;
            }
            const double mean = sum / (kSamples * kSamples) + (noiseSigma > 0 ? rng.gaussian(noiseSigma) : 0.0);
            row[x] = cv::saturate_cast<std::uint8_t>(mean);
        }
    }
    return image;
}

void ChessboardRenderer::render(const BoardPose& pose, double noiseSigma, cv::RNG& rng, cv::Mat& left,
                                cv::Mat& right) const
{
    cv::Matx33d rBoard;
    cv::Rodrigues(pose.rvec, rBoard);
    const cv::Matx33d rRig(rig_.rotation());
    const cv::Vec3d tRig(rig_.translation());
    left = renderView(rBoard, pose.tvec, noiseSigma, rng);
    right = renderView(rRig * rBoard, rRig * pose.tvec + tRig, noiseSigma, rng);
}

} // namespace ugv::sim
