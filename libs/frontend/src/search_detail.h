/* imm-monoslam — internal pieces of the active search (not installed): ZNCC score maps and
 * sub-pixel refinement. */
#pragma once

#include <immslam/frontend/frontend.h>

namespace immslam::frontend::detail
{
/** Marks score-map entries that were not computed (ZNCC lies in [-1, 1]). */
constexpr float kNotComputed = -3.0f;

/** Direct ZNCC (same definition as cv::matchTemplate TM_CCOEFF_NORMED; 0 where the image window
 * is flat) of `templ` at the positions (x, y), y in [sy0, sy1], x in [lo[y - sy0], hi[y - sy0]]
 * (clipped to [sx0, sx1]; empty rows have lo > hi), into ws.scores ((sy1-sy0+1) x (sx1-sx0+1),
 * CV_32F, kNotComputed elsewhere; a header over ws.scoreBuffer). Every template pixel must lie
 * inside the image for every position of the box. Single-threaded, no heap allocation once ws has
 * grown. */
void znccScoreRows(const cv::Mat& grey, const cv::Mat& templ, int sx0, int sy0, int sx1, int sy1,
                   const std::vector<int>& lo, const std::vector<int>& hi, TSearchWorkspace& ws);

/** Sub-pixel offset of the peak of a 2-D quadratic least-squares fit to the 3x3 scores s[dy][dx]
 * (dx, dy in -1..1). Returns false if the fit has no maximum or moves the peak by over 1 px. */
bool quadraticPeak(const float s[3][3], Vec2& offset);

/** Gauss-Newton refinement of a match position: minimizes
 * \f$ \sum_x (I(u + x) - a\,T(x) - b)^2 \f$ over the translation u and a photometric gain a and
 * offset b (the least-squares counterpart of maximizing ZNCC), with I bilinearly interpolated (all
 * template pixels share one sub-pixel phase, so the window is resampled with 4 fixed weights) and
 * its gradient by central differences. T is CV_32F. Starts at uv; returns false (uv unchanged) if
 * the window leaves the image, the normal equations are singular or a step exceeds 2 px. */
bool refineTranslation(const cv::Mat& grey, const cv::Mat& T, Vec2& uv, int maxIter,
                       std::vector<float>& win);
}  // namespace immslam::frontend::detail
