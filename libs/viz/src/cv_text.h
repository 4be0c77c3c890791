/* imm-monoslam — internal OpenCV text helpers shared by overlays and snapshots. */
#pragma once

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace immslam::viz
{
/** The font every figure uses (Hershey simplex, anti-aliased). */
constexpr int kFont = 0;  // cv::FONT_HERSHEY_SIMPLEX

/** Size of one line of text (width, height above the baseline) and its baseline depth. */
cv::Size textSize(const std::string& s, double scale, int thickness, int* baseline = nullptr);

/** Draws text with its top-left corner at `topLeft`. */
void drawText(cv::Mat& img, const std::string& s, cv::Point topLeft, double scale,
    const cv::Scalar& colour, int thickness = 1);

/** Draws lines of text on a (semi-transparent when alpha < 1) box whose top-left corner is
 * `topLeft`; returns the box. */
cv::Rect drawTextBox(cv::Mat& img, const std::vector<std::string>& lines, cv::Point topLeft,
    double scale, const cv::Scalar& textColour, const cv::Scalar& boxColour, double alpha);

/** Fills a rectangle blending with what is below (alpha = opacity of the colour). */
void blendRect(cv::Mat& img, cv::Rect r, const cv::Scalar& colour, double alpha);
}  // namespace immslam::viz
