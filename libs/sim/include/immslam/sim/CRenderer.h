/* imm-monoslam — per-pixel ray casting of a CWorld through any camera model. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/sim/CWorld.h>
#include <immslam/sim/types.h>

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <optional>
#include <vector>

namespace immslam::sim
{
/** What to render and how. */
struct TRenderOptions
{
  /** Gaussian pixel noise (grey levels; drawn from a table of 4096 normal quantiles); 0: none. */
  double noise_sigma_grey = 0.0;
  /** Gaussian blur before the noise (pixels); 0: none. */
  double blur_sigma_px = 0.0;
  /** Seed of the pixel noise (one stream per image row: the result does not depend on threads). */
  std::uint64_t noise_seed = 0;
  /** Also render the colour image. */
  bool colour = false;
  /** Also output the depth image (z in the camera frame, CV_32F, 0 where nothing is hit). */
  bool depth = false;
  /** Only the mask (and depth): skip texturing, blur and noise. */
  bool mask_only = false;
};

/** The images of one frame. */
struct TRenderedImages
{
  cv::Mat grey;    ///< CV_8UC1 (empty with mask_only)
  cv::Mat colour;  ///< CV_8UC3 BGR when requested
  cv::Mat mask;    ///< CV_8UC1: 0 static world (and objects standing still), k moving object k
  cv::Mat depth;   ///< CV_32FC1 when requested
};

/** Renders images of a world seen by one camera model: every pixel's ray is the model's
 * unprojection of the pixel (so the distortion is exact), cached once at construction; rays are
 * intersected analytically with the room and the boxes (nearest hit), and the texture is looked up
 * trilinearly with a mip level from the pixel's footprint on the surface
 * (range x pixel angle / sqrt(|cos incidence|)). Rows are split over `threads` std::threads; each
 * pixel and each row's noise stream are independent of the split, so the output is bitwise
 * deterministic. Boxes are culled per 16x16 tile (bounding sphere vs the tile's cone of rays). */
class CRenderer
{
 public:
  /** \param threads number of threads (0: hardware concurrency). */
  CRenderer(camera::CCameraModel::Ptr cam, int threads);

  const camera::CCameraModel::Ptr& camera() const { return m_cam; }

  /** Renders `boxes` (CWorld::boxesAt) with the camera at T_W_C. */
  TRenderedImages render(const CWorld& world, const std::vector<TBox>& boxes, const TPose& T_W_C,
                         const TRenderOptions& opts) const;

  /** The first surface hit by the ray of pixel uv (any real coordinates; the ray is the model's
   * unprojection of uv), or nothing if the ray escapes (impossible inside a closed room) or uv's
   * unprojection is invalid. Same arithmetic as render(): raycast at integer pixels reproduces the
   * mask exactly. */
  std::optional<TRayHit> raycast(const std::vector<TBox>& boxes, const TPose& T_W_C, const Vec2& uv) const;

  /** Cached unit bearing (camera frame) of pixel (u, v). */
  const Vec3& bearing(int u, int v) const { return m_bearings[static_cast<std::size_t>(v) * m_w + u]; }

 private:
  struct TInstance;
  struct THit;
  std::vector<TInstance> prepare(const std::vector<TBox>& boxes, const TPose& T_W_C) const;
  static bool intersect(const std::vector<TInstance>& inst, std::uint64_t candidates, const Vec3& b_C, THit& hit);
  /** Per image tile, the boxes that may be seen in it (bit i = box i; the room is always the
   * fallback). */
  std::vector<std::uint64_t> tileCandidates(const std::vector<TInstance>& inst) const;
  /** The 8-bit image of the linear radiance `value` (1 or 3 channels), with the options' pixel noise. */
  cv::Mat quantized(const cv::Mat& value, bool colour, const TRenderOptions& opts) const;

  camera::CCameraModel::Ptr m_cam;
  int m_w, m_h, m_threads;
  std::vector<Vec3> m_bearings;
  std::vector<double> m_alpha;
  std::vector<std::uint8_t> m_valid;
  int m_tilesX, m_tilesY;
  std::vector<Vec3> m_tileAxis;
  std::vector<double> m_tileHalfAngle;
  std::vector<float> m_noiseTable;
};
}  // namespace immslam::sim
