#include "ugv/vision/stereo_calibration.hpp"

namespace ugv::vision {

double StereoCalibration::baselineM() const
{
    return T.empty() ? 0.0 : cv::norm(T);
}

double StereoCalibration::rectifiedFocalPx() const
{
    return P1.empty() ? 0.0 : P1.at<double>(0, 0);
}

StereoCalibration makeRectifiedCalibration(cv::Size imageSize, double fx, double fy, double cx, double cy,
                                           double baselineM)
{
    return makeRectifiedCalibration(imageSize, fx, fy, cx, cy, baselineM, cx);
}

StereoCalibration makeRectifiedCalibration(cv::Size imageSize, double fx, double fy, double cx, double cy,
                                           double baselineM, double cxRight)
{
    StereoCalibration calib;
    calib.imageSize = imageSize;
    calib.rectified = true;
    calib.K1 = (cv::Mat_<double>(3, 3) << fx, 0, cx, 0, fy, cy, 0, 0, 1);
    calib.K2 = (cv::Mat_<double>(3, 3) << fx, 0, cxRight, 0, fy, cy, 0, 0, 1);
    calib.D1 = cv::Mat::zeros(1, 5, CV_64F);
    calib.D2 = cv::Mat::zeros(1, 5, CV_64F);
    calib.R = cv::Mat::eye(3, 3, CV_64F);
    calib.T = (cv::Mat_<double>(3, 1) << -baselineM, 0, 0);
    // E = [T]x R; F = K2^-T E K1^-1 (rectified: epipolar lines are the rows).
    calib.E = (cv::Mat_<double>(3, 3) << 0, 0, 0, 0, 0, baselineM, 0, -baselineM, 0);
    calib.F = calib.K2.inv().t() * calib.E * calib.K1.inv();
    calib.R1 = cv::Mat::eye(3, 3, CV_64F);
    calib.R2 = cv::Mat::eye(3, 3, CV_64F);
    calib.P1 = (cv::Mat_<double>(3, 4) << fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0);
    calib.P2 = (cv::Mat_<double>(3, 4) << fx, 0, cxRight, -fx * baselineM, 0, fy, cy, 0, 0, 0, 1, 0);
    // As cv::stereoRectify: Q(3,2) = -1/Tx and Q(3,3) = (cx - cxRight)/Tx with Tx = -baseline.
    calib.Q = (cv::Mat_<double>(4, 4) << 1, 0, 0, -cx, 0, 1, 0, -cy, 0, 0, 0, fx, 0, 0, 1.0 / baselineM,
               (cxRight - cx) / baselineM);
    return calib;
}

} // namespace ugv::vision
