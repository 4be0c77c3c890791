/* imm-monoslam — options of the shadow filter (section [shadow]). */
#include <immslam/core/config.h>
#include <immslam/shadow/CShadowFilter.h>

#include <cmath>

namespace immslam::shadow
{
void CShadowFilter::TOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
  IMMSLAM_LOAD_DOUBLE(init_velocity_std_px);
  IMMSLAM_LOAD_DOUBLE(sigma_accel_px);
  IMMSLAM_LOAD_DOUBLE(alpha);
  IMMSLAM_LOAD_INT(min_test_frames);
  IMMSLAM_LOAD_INT(dynamic_rejections);
  IMMSLAM_LOAD_INT(dynamic_window);
  IMMSLAM_LOAD_INT(static_acceptances);
  IMMSLAM_LOAD_INT(static_min_frames);
  IMMSLAM_LOAD_DOUBLE(static_min_velocity_px);
  IMMSLAM_LOAD_DOUBLE(static_power);
  IMMSLAM_LOAD_INT(max_pending_frames);
  IMMSLAM_LOAD_INT(max_missed_frames);
  IMMSLAM_LOAD_INT(dynamic_max_missed_frames);
  IMMSLAM_LOAD_INT(max_features);
  validate(s);
}

void CShadowFilter::TOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
  MRPT_SAVE_CONFIG_VAR_COMMENT(init_velocity_std_px, "feature velocity prior std (px/frame at unit depth)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(sigma_accel_px, "feature acceleration noise (px/frame^2 at unit depth)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(alpha, "significance of the three-ray test (static features called dynamic per test)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(min_test_frames, "first test once a feature's views span this many frames");
  MRPT_SAVE_CONFIG_VAR_COMMENT(dynamic_rejections, "dynamic when this many of the last dynamic_window tests reject");
  MRPT_SAVE_CONFIG_VAR_COMMENT(dynamic_window, "the number of recent tests dynamic_rejections counts in");
  MRPT_SAVE_CONFIG_VAR_COMMENT(static_acceptances, "static needs this many consecutive accepted tests,");
  MRPT_SAVE_CONFIG_VAR_COMMENT(static_min_frames, "a track spanning at least this many frames,");
  MRPT_SAVE_CONFIG_VAR_COMMENT(static_min_velocity_px, "and power against motions of this image speed (px/frame)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(static_power, "detection probability that defines that power");
  MRPT_SAVE_CONFIG_VAR_COMMENT(max_pending_frames, "undecided features are dropped after this many frames");
  MRPT_SAVE_CONFIG_VAR_COMMENT(max_missed_frames, "pending features dropped after this many misses in a row");
  MRPT_SAVE_CONFIG_VAR_COMMENT(dynamic_max_missed_frames, "dynamic features dropped after this many misses in a row");
  MRPT_SAVE_CONFIG_VAR_COMMENT(max_features, "maximum number of features held");
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
