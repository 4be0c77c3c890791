/* imm-monoslam — per-frame overlay images: search ellipses, matches, feature classes, text.
 *
 * What the papers show: the IMM paper's Fig. 5 (search ellipses of the same feature under IMM and
 * single-model predictions) and MonoSLAMBOT's Fig. 4 (static features blue, dynamic green, features
 * still waiting for a decision red).
 */
#pragma once

#include <immslam/math/types.h>
#include <immslam/viz/colours.h>

#include <opencv2/core.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace immslam::viz
{
/** Outcome of the active search of one predicted feature. */
enum class ESearchStatus
{
  NotFound,  ///< searched, no acceptable match
  Inlier,    ///< matched and used in the update
  Rescued,   ///< rejected at first, accepted again (e.g. by a second, rescue pass)
  Rejected   ///< matched inside the gate but rejected as an outlier
};

/** One search region: the gate \f$ (x-h)^\top S^{-1} (x-h) \le \chi^2 \f$ around the prediction. */
struct TSearchView
{
  Vec2 h = Vec2::Zero();    ///< predicted pixel (u, v)
  Mat2 S = Mat2::Identity(); ///< innovation covariance (px^2)
  double gateChi2 = 5.991;  ///< gate (chi-square quantile, 2 dof; 5.991 = 95 %)
  ESearchStatus status = ESearchStatus::NotFound;  ///< selects the colour
  std::optional<Vec2> z;    ///< measured pixel, if any
  std::int64_t id = -1;     ///< feature id (drawn if >= 0 and TOverlayStyle::drawIds)
};

/** Class of a feature (MonoSLAMBOT). */
enum class EFeatureClass
{
  Static,   ///< static (blue)
  Dynamic,  ///< dynamic (green)
  Pending   ///< waiting for classification (red)
};

/** One feature drawn as a marker. */
struct TFeatureView
{
  Vec2 uv = Vec2::Zero();                   ///< pixel (u, v)
  EFeatureClass cls = EFeatureClass::Static; ///< selects the colour
  std::int64_t id = -1;                     ///< drawn if >= 0 and TOverlayStyle::drawIds
};

/** What one overlay shows. */
struct TOverlayContent
{
  std::vector<TSearchView> searches;   ///< search ellipses and matches
  std::vector<TFeatureView> features;  ///< classified features
  std::vector<std::string> textLines;  ///< e.g. "frame 120", "28.3 fps", "mu: stationary 0.91"
};

/** A corner of an image. */
enum class ECorner
{
  TopLeft,     ///< top-left
  TopRight,    ///< top-right
  BottomLeft,  ///< bottom-left
  BottomRight  ///< bottom-right
};

/** Appearance of an overlay. Sizes (thickness, radius, font) are for an output up to 640 px wide
 * and grow in proportion for wider outputs. */
struct TOverlayStyle
{
  /** Integer upscaling of the image before drawing (nearest neighbour, so pixels stay sharp):
   * 0 = automatic (2 for images whose larger side is <= 400 px, else 1). */
  int upscale = 0;
  int lineThickness = 1;      ///< ellipse / marker line thickness in output pixels
  int ellipseSegments = 72;   ///< polygon vertices per ellipse
  double markerRadius = 4;    ///< feature marker radius in output pixels
  double fontScale = 0.45;    ///< OpenCV Hershey font scale of text, legend and ids
  bool drawIds = false;       ///< draw feature ids next to the markers
  bool drawLegend = true;     ///< legend box (bottom-left) with the colours in use
  bool drawMatchLines = true; ///< segment from prediction h to measurement z
  bool legendAllEntries = false; ///< legend lists every class, not only those present
  ECorner legendCorner = ECorner::BottomLeft;  ///< where the legend goes
  ECorner textCorner = ECorner::TopLeft;       ///< where the text lines go
  TColour staticColour = palette::kStatic;    ///< EFeatureClass::Static
  TColour dynamicColour = palette::kDynamic;  ///< EFeatureClass::Dynamic
  TColour pendingColour = palette::kPending;  ///< EFeatureClass::Pending
  TColour inlierColour = palette::kInlier;    ///< ESearchStatus::Inlier
  TColour rescuedColour = palette::kRescued;  ///< ESearchStatus::Rescued
  TColour rejectedColour = palette::kRejected; ///< ESearchStatus::Rejected
  TColour notFoundColour = palette::kNotFound; ///< ESearchStatus::NotFound
};

/** The gate ellipse \f$ \{h + \sqrt{\chi^2}\, L (\cos t, \sin t) \} \f$, \f$ S = L L^\top \f$
 * (Cholesky), as `n` vertices in input-image pixel coordinates. Every vertex x satisfies
 * \f$ (x-h)^\top S^{-1} (x-h) = \chi^2 \f$.
 * \return empty if S is not finite and positive definite or chi2 <= 0. */
std::vector<Vec2> gateEllipsePolygon(const Vec2& h, const Mat2& S, double chi2, int n = 72);

/** Area of the gate ellipse, \f$ \pi \chi^2 \sqrt{\det S} \f$ (px^2). */
double gateEllipseArea(const Mat2& S, double chi2);

/** The upscale factor drawOverlay() uses for an image of this size and style. */
int overlayScale(const cv::Size& imageSize, const TOverlayStyle& style);

/** Maps an input-image pixel (u, v) (pixel centres at integers) to the output image of an overlay
 * drawn at integer scale s: \f$ s (u + 0.5) - 0.5 \f$. */
inline Vec2 toOverlayPixel(const Vec2& uv, int s) { return s * (uv.array() + 0.5).matrix() - Vec2::Constant(0.5); }

/** Draws the content on a BGR copy of `image` (grey or BGRA inputs are converted; 16-bit inputs
 * are scaled to 8 bits), upscaled per style.upscale. Ellipses are drawn with sub-pixel precision
 * exactly along gateEllipsePolygon(). The input is not modified.
 * \throws std::runtime_error if the image is empty or of an unsupported type. */
cv::Mat drawOverlay(const cv::Mat& image, const TOverlayContent& content,
    const TOverlayStyle& style = TOverlayStyle());

/** Our colour as an OpenCV BGR scalar. */
inline cv::Scalar toBgr(const TColour& c) { return cv::Scalar(c.b, c.g, c.r); }
}  // namespace immslam::viz
