/* imm-monoslam — internal OpenCV text helpers. */
#include "cv_text.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace immslam::viz
{
cv::Size textSize(const std::string& s, double scale, int thickness, int* baseline)
{
  int b = 0;
  const cv::Size sz = cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &b);
  if (baseline) *baseline = b;
  return sz;
}

void drawText(cv::Mat& img, const std::string& s, cv::Point topLeft, double scale,
    const cv::Scalar& colour, int thickness)
{
  const cv::Size sz = textSize(s, scale, thickness);
  cv::putText(img, s, cv::Point(topLeft.x, topLeft.y + sz.height), cv::FONT_HERSHEY_SIMPLEX, scale,
      colour, thickness, cv::LINE_AA);
}

void blendRect(cv::Mat& img, cv::Rect r, const cv::Scalar& colour, double alpha)
{
  r &= cv::Rect(0, 0, img.cols, img.rows);
  if (r.empty()) return;
  cv::Mat roi = img(r);
  if (alpha >= 1.0)
  {
    roi.setTo(colour);
    return;
  }
  cv::Mat fill(roi.size(), roi.type(), colour);
  cv::addWeighted(fill, alpha, roi, 1.0 - alpha, 0.0, roi);
}

cv::Rect drawTextBox(cv::Mat& img, const std::vector<std::string>& lines, cv::Point topLeft,
    double scale, const cv::Scalar& textColour, const cv::Scalar& boxColour, double alpha)
{
  if (lines.empty()) return {};
  int base = 0;
  const int lineH = textSize("Ag", scale, 1, &base).height + base + std::max(2, int(4 * scale));
  int w = 0;
  for (const auto& l : lines) w = std::max(w, textSize(l, scale, 1).width);
  const int pad = std::max(3, int(6 * scale));
  const cv::Rect box(topLeft.x, topLeft.y, w + 2 * pad, int(lines.size()) * lineH + 2 * pad - 2);
  blendRect(img, box, boxColour, alpha);
  for (size_t i = 0; i < lines.size(); ++i)
    drawText(img, lines[i], cv::Point(topLeft.x + pad, topLeft.y + pad + int(i) * lineH), scale,
        textColour, 1);
  return box;
}
}  // namespace immslam::viz
