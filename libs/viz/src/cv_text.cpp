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

std::string formatNumber(double v, int significant)
{
  if (!std::isfinite(v)) return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
  if (v == 0) return "0";
  char buf[64];
  const double a = std::abs(v);
  if (a >= 1e5 || a < 1e-3)
    std::snprintf(buf, sizeof buf, "%.*e", std::max(0, significant - 1), v);
  else
    std::snprintf(buf, sizeof buf, "%.*f",
        std::max(0, significant - 1 - int(std::floor(std::log10(a)))), v);
  std::string s(buf);
  // Trim trailing zeros of the mantissa.
  const auto e = s.find('e');
  std::string mant = s.substr(0, e), exp = e == std::string::npos ? "" : s.substr(e);
  if (mant.find('.') != std::string::npos)
  {
    while (!mant.empty() && mant.back() == '0') mant.pop_back();
    if (!mant.empty() && mant.back() == '.') mant.pop_back();
  }
  if (!exp.empty())
  {
    // e+05 -> e5, e-04 -> e-4
    const char sign = exp[1];
    std::string digits = exp.substr(2);
    while (digits.size() > 1 && digits[0] == '0') digits.erase(0, 1);
    exp = std::string("e") + (sign == '-' ? "-" : "") + digits;
  }
  return mant + exp;
}
}  // namespace immslam::viz
