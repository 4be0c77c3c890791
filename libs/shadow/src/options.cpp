/* imm-monoslam — options of the shadow filter (section [shadow]). */
#include <immslam/core/config.h>
#include <immslam/shadow/CShadowFilter.h>

#include <cmath>

namespace immslam::shadow
{
void CShadowFilter::TOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
  IMMSLAM_LOAD_DOUBLE(sigma_accel_px);
  IMMSLAM_LOAD_INT(max_features);
  IMMSLAM_LOAD_BOOL(decide_lone_dynamic);
  validate(s);
}

void CShadowFilter::TOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
  MRPT_SAVE_CONFIG_VAR_COMMENT(sigma_accel_px, "feature acceleration noise (px/frame^2 at unit depth)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(max_features, "maximum number of features held");
  MRPT_SAVE_CONFIG_VAR_COMMENT(decide_lone_dynamic,
                               "decide a translating camera's dynamic verdict at once even where no other feature nearby "
                               "moves (true: movers seen by one feature each, the papers' random points)");
}

void CShadowFilter::TOptions::validate(const std::string& s) const
{
  core::requirePositive(sigma_pixel, s, "sigma_pixel");
  if (!std::isfinite(init_rho)) core::requirePositive(init_rho, s, "init_rho");
  core::requirePositive(init_rho_std, s, "init_rho_std");
  core::requireNonNegative(init_velocity_std_px, s, "init_velocity_std_px");
  core::requireNonNegative(sigma_accel_px, s, "sigma_accel_px");
  core::requireInRange(patch_half_size, 1, 50, s, "patch_half_size");
  core::requireInRange(min_ncc, -1, 1, s, "min_ncc");
  core::requireInRange(search_probability, 0.5, 0.999999, s, "search_probability");
  core::requirePositive(max_search_half_extent_px, s, "max_search_half_extent_px");
  core::requireInRange(alpha, 1e-6, 0.5, s, "alpha");
  core::requireInRange(min_test_frames, 2, 1000000, s, "min_test_frames");
  core::requireInRange(dynamic_window, 1, 1000, s, "dynamic_window");
  core::requireInRange(dynamic_rejections, 1, dynamic_window, s, "dynamic_rejections");
  core::requireInRange(static_acceptances, 1, 1000000, s, "static_acceptances");
  core::requireInRange(static_min_frames, 2, 1000000, s, "static_min_frames");
  core::requirePositive(static_min_velocity_px, s, "static_min_velocity_px");
  core::requireInRange(static_power, 0.5, 0.999999, s, "static_power");
  core::requireInRange(still_camera_static_frames, 0, 1000000, s, "still_camera_static_frames");
  core::requireInRange(min_point_ncc, 0.0, 1.0, s, "min_point_ncc");
  core::requireInRange(max_pending_frames, 3, 1000000, s, "max_pending_frames");
  core::requireInRange(max_missed_frames, 0, 1000000, s, "max_missed_frames");
  core::requireInRange(dynamic_max_missed_frames, 0, 1000000, s, "dynamic_max_missed_frames");
  core::requireInRange(max_features, 1, 1000000, s, "max_features");
  core::requirePositive(min_inverse_distance, s, "min_inverse_distance");
}

TRayClassifierParams CShadowFilter::TOptions::classifierParams() const
{
  TRayClassifierParams p;
  p.alpha = alpha;
  p.sigmaPx = sigma_pixel;
  p.minTestFrames = min_test_frames;
  p.dynamicRejections = dynamic_rejections;
  p.dynamicWindow = dynamic_window;
  p.staticAcceptances = static_acceptances;
  p.staticMinFrames = static_min_frames;
  p.staticMinVelocityPx = static_min_velocity_px;
  p.staticPower = static_power;
  p.staticWorstCase = static_power_worst_case;
  p.maxInverseDistance = init_rho + 3 * init_rho_std;
  return p;
}
}  // namespace immslam::shadow
