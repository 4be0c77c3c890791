/* imm-monoslam — image front end: corner detection in empty image regions, feature patches with
 * predicted appearance (warping), and active search inside an innovation ellipse (IMM paper
 * Sec. IV-1: the search region is the 95 % ellipse of the innovation covariance S_i).
 *
 * Pure image processing on 8-bit grey cv::Mat; knows nothing about filters.
 * Pixel convention (doc/conventions.md): (u, v) = (0, 0) is the centre of the top-left pixel. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/math/types.h>

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <vector>

namespace immslam::frontend
{
/** A corner candidate. */
struct TCorner
{
  Vec2 uv = Vec2::Zero();  ///< integer pixel position of the FAST corner
  double score = 0;        ///< normalized Shi-Tomasi response (normalizedShiTomasi); higher: better
};

/** Detector options (loaded by the caller's options class). */
struct TDetectorParams
{
  int fastThreshold = 20;     ///< FAST threshold (grey levels): the absolute contrast test
  int gridCols = 8;           ///< image split into gridCols x gridRows cells...
  int gridRows = 6;           ///< ...new corners go to cells with no tracked feature
  double minDistancePx = 12;  ///< min distance of a new corner to occupied points and to others
  /** Corners closer than this to the border are ignored (at least shiTomasiHalfWindow + 1 is
   * used). 12 lets CFeaturePatch::extract(halfSize 5), whose region needs 11 px, always succeed. */
  int borderPx = 12;
  /** Minimum normalized Shi-Tomasi response (see normalizedShiTomasi; units 1/px^2, invariant to
   * the image's contrast and brightness): rejects edges and blurred blobs. Measured: an ideal sharp
   * 90-degree corner scores 0.16, blurred with sigma = 1 px 0.09, a straight edge < 0.001; FAST
   * corners of the shared real sequences have median 0.10-0.15 and 5 % quantile 0.02-0.04.
   * (Not the raw eigenvalue: a threshold like 1e-4 on intensities in [0, 1] would depend on the
   * image's contrast.) */
  double minShiTomasi = 0.01;
  int shiTomasiHalfWindow = 3;  ///< the structure tensor is averaged over (2*this+1)^2 pixels
  /** Optional CV_8UC1 mask of the image's size: corners only where it is non-zero (empty: the whole
   * image). See lensMask(): keeps corners off a fisheye's black corners and its image circle. */
  cv::Mat validMask;
};

/** Where the lens images the world: the pixels whose ray (unproject) projects back onto them (within
 * 0.05 px), eroded by `margin` px (so a patch around an allowed pixel holds only imaged pixels), as a
 * CV_8UC1 mask (255 allowed). Empty when every pixel is imaged (pinhole, the usual radial
 * distortions): nothing to mask. Non-empty for a fisheye whose corners lie beyond 90 degrees or
 * beyond its distortion's fold (CFisheyeCamera, COpenCVCamera), whose corners are black in real
 * images and whose image circle would give corners that do not belong to the world. The models'
 * limits are radii about the principal point, so when every border pixel is imaged the mask is
 * empty without visiting the inside. */
cv::Mat lensMask(const camera::CCameraModel& cam, int margin);

/** An exclusion mask (non-zero: excluded) grown by `radius` px in a square: a patch of half size
 * `radius` centred on a pixel left free does not overlap an excluded pixel. CV_8UC1 (255 excluded);
 * empty for an empty mask. \throws std::invalid_argument if not CV_8UC1 or radius < 0. */
cv::Mat growExclusion(const cv::Mat& excluded, int radius);

/** True if the pixel nearest uv (lround) is inside the image of `mask` and non-zero there; false for
 * an empty mask or a non-finite uv. */
bool maskedAt(const cv::Mat& mask, const Vec2& uv);

/** Contrast-normalized Shi-Tomasi response at the integer pixel (u, v):
 * \f$ s = \lambda_{min}(M) / (\sigma_I^2 + 1) \f$, where
 * \f$ M = \frac{1}{n}\sum_{w} \nabla I \nabla I^\top \f$ is the structure tensor averaged over the
 * (2 halfWindow + 1)^2 window w (central-difference gradients, grey levels per pixel) and
 * \f$ \sigma_I^2 \f$ the intensity variance over the same window (grey levels^2; the +1 only guards
 * flat windows). Multiplying the image by a gain and adding an offset leaves s unchanged, so a
 * threshold on s measures the *shape* of the corner (sharp, two-directional structure) while the
 * absolute contrast is tested by FAST's threshold. Units: 1/px^2. Ranking by s prefers sharp,
 * well-localized structure over merely strong contrast. Computed only where asked: at the FAST
 * candidates this costs ~0.1 ms per 1000 candidates, less than cv::cornerMinEigenVal over a whole
 * 320x240 image (~0.3 ms) or 640x480 image (~1.3 ms).
 * \return 0 if the window (plus one pixel for the gradients) does not fit inside the image. */
double normalizedShiTomasi(const cv::Mat& grey, int u, int v, int halfWindow = 3);

/** Detects up to maxNew corners in the image cells that hold none of `occupied` (the predicted or
 * measured positions of the features already tracked; positions outside the image are ignored),
 * strongest first, at most one per cell per call, each at least minDistancePx from the occupied
 * points and from each other, and at least borderPx from the border.
 * FAST (OpenCV, non-maximum suppression) candidates are scored by normalizedShiTomasi (computed
 * only at the candidates), those below minShiTomasi dropped, then chosen greedily by decreasing
 * score (ties broken by position: deterministic); a cell whose best candidate is too close to an
 * already chosen corner may get its next best. With p.validMask, only where the mask is non-zero.
 * \throws std::runtime_error if grey is not a non-empty CV_8UC1 image, the grid is empty, or
 * p.validMask is neither empty nor a CV_8UC1 image of grey's size. */
std::vector<TCorner> detectInEmptyCells(
    const cv::Mat& grey, const std::vector<Vec2>& occupied, int maxNew, const TDetectorParams& p);

/** The stored appearance of a feature: the image region around its first observation, large
 * enough to predict (warp) a (2*halfSize+1)^2 template under a 2x2 affine map of moderate scale
 * change and any rotation.
 *
 * The region has half size 2*halfSize+1 (23x23 for halfSize 5, so it fits wherever the detector's
 * default borderPx = 12 allows a corner): any rotation combined with a shrink (feature now looking
 * smaller) of up to ~1.45x, or a shrink of up to 2x without rotation, is resampled from stored
 * pixels; beyond that the template's outer pixels replicate the region's border (the template
 * degrades gracefully: tested at 0.75x with 45 degrees of rotation). Enlargements of any size are
 * supported. Copies share the (never modified) region buffer. */
class CFeaturePatch
{
 public:
  CFeaturePatch() = default;

  /** Extracts the region centred at uv (rounded to the nearest pixel; the sub-pixel remainder is
   * kept and compensated when predicting). \param halfSize template half size (5 -> 11x11).
   * \return false (patch left unchanged) if the region does not fit inside the image or uv is not
   * finite. \throws std::runtime_error if grey is not CV_8UC1 or halfSize < 1. */
  bool extract(const cv::Mat& grey, const Vec2& uv, int halfSize);

  /** The template as it should look in the current image: A maps a small offset around the feature
   * in the first image to the offset in the current image (du_now = A du_first); A = identity gives
   * the original patch. Template pixel offset d (from the template centre) is sampled at region
   * offset A^{-1} d from the original sub-pixel position, by bilinear interpolation; returns CV_32F
   * (2*halfSize+1)^2 in grey levels.
   * Saturation: a non-finite A is replaced by the identity; the singular values of A are clamped to
   * [0.25, 4] (so a singular A gives a strongly foreshortened but usable template); samples falling
   * outside the stored region take the value of the nearest region pixel.
   * \throws std::runtime_error if the patch is not valid(). */
  cv::Mat predictTemplate(const Mat2& A) const;

  /** As predictTemplate(A), writing into `out` (reallocated only if its size/type differ: no heap
   * allocation when the same buffer is reused for features of the same halfSize). */
  void predictTemplate(const Mat2& A, cv::Mat& out) const;

  /** The unwarped template, CV_32F: the image bilinearly interpolated on the (2*halfSize+1)^2 grid
   * centred at the extraction position uv (what cv::getRectSubPix returns). */
  cv::Mat originalTemplate() const { return predictTemplate(Mat2::Identity()); }

  int halfSize() const { return m_half; }
  bool valid() const { return !m_region.empty(); }

  /** Half size of the stored region (2*halfSize+1). */
  int regionHalfSize() const { return m_regionHalf; }
  /** The stored region, CV_32F, (2*regionHalfSize()+1)^2, centred at the rounded position. */
  const cv::Mat& region() const { return m_region; }
  /** Extraction position minus the rounded region centre (each coordinate in [-0.5, 0.5]). */
  const Vec2& subpixelOffset() const { return m_subpixel; }

 private:
  cv::Mat m_region;                ///< CV_32F, (2*m_regionHalf+1)^2 around the rounded centre
  Vec2 m_subpixel = Vec2::Zero();  ///< uv minus the rounded centre
  int m_half = 0;                  ///< template half size
  int m_regionHalf = 0;            ///< 2*m_half+1
};

/** Local affine map between the first and the current image for a feature lying on a small plane
 * through p_W with normal n_W (usually the direction back to the first camera), imaged by `cam` at
 * poses T_W_C0 = (r0, q0) and T_W_Ck = (rk, qk) (quaternions [qw qx qy qz]).
 * Computed from the projection Jacobians (the local linearization of the plane-induced homography,
 * distortion included):
 * \f[ A = J^{k}_{uv,p}\, R_{Ck W}\; t\,\Big(I - \frac{d\,n^\top}{n^\top d}\Big)\,
 *       R_{W C0}\, J^{0}_{b,uv} \f]
 * with \f$ u_0 \f$ the projection of p_W in view 0, \f$ J^{0}_{b,uv} \f$ the Jacobian of the
 * unprojected unit bearing at u_0, \f$ d = R_{WC0} b \f$ that ray in W, and
 * \f$ t = n^\top (p_W - r_0) / n^\top d \f$ the distance along the ray to the plane
 * (a pixel offset in view 0 moves the ray's intersection with the plane, which moves the projection
 * in view k). n_W need not be unit; a zero n_W means the plane facing camera 0 (n = d).
 * Returns identity if the point is not in front of either camera, or the plane is seen edge-on
 * from camera 0 (|n.d| < 1e-6), or the result is not finite. */
Mat2 patchWarp(const camera::CCameraModel& cam, const Vec3& r0, const Vec4& q0, const Vec3& rk,
               const Vec4& qk, const Vec3& p_W, const Vec3& n_W);

/** Options of the active search. */
struct TSearchParams
{
  double gateChi2 = 5.991;       ///< ellipse: (uv - h)^T S^-1 (uv - h) <= gateChi2 (95 %, 2 dof)
  double minScore = 0.80;        ///< minimum zero-mean normalized cross-correlation to accept
  double maxHalfExtentPx = 60;   ///< the search box is clipped to this half extent (pathological S)
  /** Templates whose intensity standard deviation is below this (grey levels) never match: their
   * ZNCC is undefined or dominated by noise. */
  double minTemplateStd = 1.0;
  /** Ambiguity check, off when <= 0: reject the match if a second, distinct peak inside the ellipse
   * (a 3x3 local maximum of the scores at least 3 px, Chebyshev distance, from the best) scores
   * >= best - ambiguityMargin. Off by default because it costs recall. Measured
   * (frontend_unittest Search.AmbiguityCheckTradeOff, 1000 px^2 ellipses, prediction error drawn
   * from S): on a real image (monoslam_testseq) margin 0.02 lowers recall 0.906 -> 0.887 and
   * removes its 2 wrong matches (0.05: recall 0.868); on a repetitive texture it turns 124 wrong
   * matches out of 140 into 6 (0 at 0.05). 0.02 suits scenes with repeated structure. */
  double ambiguityMargin = 0.0;
  /** Gauss-Newton iterations polishing the sub-pixel position after the quadratic fit (0: quadratic
   * fit only). The quadratic fit of ZNCC scores sampled at 1 px is biased on sharp peaks (measured
   * on synthetic corners: median 0.09 px, max 0.33 px in the same image; max 0.45 px under a
   * 30 deg / 1.3x warp); the polish minimizes sum_x (I(u + x) - a T(x) - b)^2 over the
   * translation u and a photometric gain/offset (a, b), with I bilinearly interpolated, and is kept
   * only if it stays within 1 px of the integer peak (measured: max 0.09 px for a sub-pixel
   * shift, 0.05 px under the warp). Usually converges (step < 1e-3 px) in 3 iterations (~3 us). */
  int refineIterations = 5;
  /** Score with cv::matchTemplate (TM_CCOEFF_NORMED, DFT-based, may use OpenCV's thread pool) over
   * the ellipse's bounding box instead of the built-in direct ZNCC, which computes the same scores
   * (to float rounding; tested) only at the positions inside the ellipse and their 8-neighbours,
   * single-threaded and without heap allocation. The direct one is the faster (measured per
   * search, 11x11 template: 8 us vs 17 us for a 100 px^2 ellipse, 31 us vs 55 us for 1000 px^2;
   * frontend_unittest Timing.*); this switch is kept as the reference. */
  bool useMatchTemplate = false;
};

/** Result of searching one feature. */
struct TSearchResult
{
  bool found = false;
  Vec2 uv = Vec2::Zero();   ///< refined sub-pixel position of the best match (if evaluated > 0)
  double score = -1;        ///< its ZNCC (at the best integer position)
  int evaluated = 0;        ///< number of candidate positions tested (inside the ellipse)
  double secondScore = -1;  ///< best distinct second peak inside the ellipse (-1: none)
};

/** Reusable buffers for searchInEllipse: keep one per thread and pass it to every call; after the
 * first few calls the search allocates nothing (direct ZNCC path). Contents are scratch. */
struct TSearchWorkspace
{
  cv::Mat scores;                       ///< score map over the ellipse's box (+1 px)
  cv::Mat roi;                          ///< matchTemplate path: the ROI as float
  cv::Mat templ32;                      ///< an 8-bit template converted to float
  std::vector<float> window;            ///< resampled image window of the sub-pixel polish
  std::vector<float> roiFloat;          ///< direct path: the ROI as float
  std::vector<float> zeroMeanTemplate;  ///< direct path: template minus its mean
  std::vector<float> accumulator;       ///< direct path: cross-correlation of one row
  std::vector<std::int64_t> integral, integralSq;  ///< direct path: sums of I and I^2 over the ROI
  std::vector<int> rowLo, rowHi;        ///< direct path: columns to score in each row
  std::vector<float> scoreBuffer;       ///< direct path: storage of `scores`
};

/** Active search (the paper's search ellipses): evaluates ZNCC (the zero-mean normalized
 * cross-correlation of cv::matchTemplate TM_CCOEFF_NORMED; 0 where the image window is flat)
 * of `templ` at every integer position inside the gate ellipse of S centred at `h` (clipped to the
 * image, to the box of half extent maxHalfExtentPx around h, and to positions where the whole
 * template lies inside the image), takes the best, refines it to sub-pixel by a 2-D quadratic fit
 * of the 3x3 neighbourhood of scores (the integer peak is kept when the fit is not a maximum, moves
 * it by more than 1 px or the neighbourhood leaves the image) and polishes it by Gauss-Newton
 * (TSearchParams::refineIterations), accepts if score >= minScore, the refined
 * position is still inside the ellipse and (if enabled) the peak is not ambiguous.
 * A template with std below minTemplateStd is never found (evaluated is then 0).
 * \param templ CV_32F (as from CFeaturePatch) or CV_8U, odd width and height.
 * \throws std::runtime_error on a non-CV_8UC1 image, a bad template or an S that is not finite and
 * positive definite. */
TSearchResult searchInEllipse(const cv::Mat& grey, const cv::Mat& templ, const Vec2& h,
                              const Mat2& S, const TSearchParams& p);

/** As above, reusing the buffers of `ws`. */
TSearchResult searchInEllipse(const cv::Mat& grey, const cv::Mat& templ, const Vec2& h,
                              const Mat2& S, const TSearchParams& p, TSearchWorkspace& ws);

/** Area of the gate ellipse: pi * gateChi2 * sqrt(det S) (pixels^2; CONTRACT.md frame_stats).
 * Returns 0 if det S <= 0. */
double ellipseArea(const Mat2& S, double gateChi2 = 5.991);
}  // namespace immslam::frontend
