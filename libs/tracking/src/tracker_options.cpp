/* imm-monoslam — options of the SLAM tracker ([slam]). */
#include <immslam/core/config.h>
#include <immslam/math/chi2.h>
#include <immslam/tracking/CSlamTracker.h>

#include <cmath>

namespace immslam::slam
{
void CSlamTracker::TOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
  IMMSLAM_LOAD_DOUBLE(sigma_pixel);
  IMMSLAM_LOAD_BOOL(adaptive_pixel_noise);
  IMMSLAM_LOAD_BOOL(adaptive_motion_noise);
  IMMSLAM_LOAD_BOOL(adaptive_shake);
  IMMSLAM_LOAD_DOUBLE(max_sigma_pixel);
  IMMSLAM_LOAD_DOUBLE(init_rho);
  IMMSLAM_LOAD_DOUBLE(init_rho_std);
  IMMSLAM_LOAD_DOUBLE(frame_rate_hz);
  IMMSLAM_LOAD_INT(fast_threshold);
  IMMSLAM_LOAD_INT(grid_cols);
  IMMSLAM_LOAD_INT(grid_rows);
  IMMSLAM_LOAD_INT(min_visible_features);
  IMMSLAM_LOAD_INT(max_new_features_per_frame);
  IMMSLAM_LOAD_INT(initial_features);
  IMMSLAM_LOAD_INT(max_map_features);
  IMMSLAM_LOAD_BOOL(convert_to_xyz);
  IMMSLAM_LOAD_BOOL(relocalise);
  IMMSLAM_LOAD_INT(num_threads);
  IMMSLAM_LOAD_INT(seed);
  validate(s);
}

void CSlamTracker::TOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
  MRPT_SAVE_CONFIG_VAR_COMMENT(sigma_pixel, "image measurement noise std (px); the initial value if adaptive");
  MRPT_SAVE_CONFIG_VAR_COMMENT(adaptive_pixel_noise, "estimate the measurement noise online from post-fit residuals");
  MRPT_SAVE_CONFIG_VAR_COMMENT(adaptive_motion_noise,
                               "raise the loosest motion models' angular acceleration noise when the camera turns more abruptly");
  MRPT_SAVE_CONFIG_VAR_COMMENT(adaptive_shake,
                               "raise the camera's angular shake above [imm] shake_px when the image shows more (median innovation)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(max_sigma_pixel, "upper bound of the adaptive noise (px)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(init_rho, "inverse-depth prior mean (dimensionless: 1 = unit depth)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(init_rho_std, "inverse-depth prior std (its 95% region must include rho = 0)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(frame_rate_hz, "nominal frame rate (Hz); 0 = from the first timestamps");
  MRPT_SAVE_CONFIG_VAR_COMMENT(fast_threshold, "FAST corner threshold (grey levels)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(grid_cols, "new features go to empty cells of a grid_cols x grid_rows grid");
  MRPT_SAVE_CONFIG_VAR_COMMENT(grid_rows, "rows of that grid");
  MRPT_SAVE_CONFIG_VAR_COMMENT(min_visible_features, "add features when fewer are predicted in the image");
  MRPT_SAVE_CONFIG_VAR_COMMENT(max_new_features_per_frame, "at most this many new features per frame");
  MRPT_SAVE_CONFIG_VAR_COMMENT(initial_features, "features initialised at the first frame");
  MRPT_SAVE_CONFIG_VAR_COMMENT(max_map_features, "map size bound (longest-unseen features evicted)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(convert_to_xyz, "convert inverse depth to XYZ when linear");
  MRPT_SAVE_CONFIG_VAR_COMMENT(relocalise, "when tracking is lost, keep the map and find it again (PnP on its templates)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(num_threads, "worker threads of the IMM bank (1 = no threads)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(seed, "random seed (1-point RANSAC)");
}

void CSlamTracker::TOptions::validate(const std::string& s) const
{
  core::requirePositive(sigma_pixel, s, "sigma_pixel");
  core::requireInRange(adaptive_noise_rate, 0, 1, s, "adaptive_noise_rate");
  core::requirePositive(min_sigma_pixel, s, "min_sigma_pixel");
  core::requireInRange(max_sigma_pixel, min_sigma_pixel, 1e3, s, "max_sigma_pixel");
  core::requirePositive(init_rho_std, s, "init_rho_std");
  core::requireNonNegative(init_rho, s, "init_rho");  // rho < 0 puts every new feature behind the camera
  core::requireNonNegative(init_linear_velocity_std_px, s, "init_linear_velocity_std_px");
  core::requireNonNegative(init_angular_velocity_std_px, s, "init_angular_velocity_std_px");
  core::requireNonNegative(frame_rate_hz, s, "frame_rate_hz");
  core::requireInRange(patch_half_size, 2, 15, s, "patch_half_size");
  core::requireInRange(min_ncc, -1, 1, s, "min_ncc");
  core::requireInRange(search_probability, 0.5, 0.99999, s, "search_probability");
  core::requirePositive(max_search_half_extent_px, s, "max_search_half_extent_px");
  core::requireInRange(expand_search_factor, 1, 10, s, "expand_search_factor");
  core::requireInRange(expand_below_fraction, 0, 1, s, "expand_below_fraction");
  core::requireInRange(fast_threshold, 1, 255, s, "fast_threshold");
  core::requireInRange(grid_cols, 1, 100, s, "grid_cols");
  core::requireInRange(grid_rows, 1, 100, s, "grid_rows");
  core::requireNonNegative(min_corner_distance_px, s, "min_corner_distance_px");
  core::requireInRange(border_px, 0, 1000, s, "border_px");
  core::requireNonNegative(min_shi_tomasi, s, "min_shi_tomasi");
  core::requireInRange(min_visible_features, 0, 10000, s, "min_visible_features");
  core::requireInRange(max_new_features_per_frame, 0, 10000, s, "max_new_features_per_frame");
  core::requireInRange(initial_features, 1, 10000, s, "initial_features");
  core::requireInRange(max_map_features, 1, 100000, s, "max_map_features");
  core::requireInRange(delete_min_predictions, 1, 1000000, s, "delete_min_predictions");
  core::requireInRange(relocalise_min_inliers, 4, 10000, s, "relocalise_min_inliers");
  core::requireInRange(relocalise_max_frames, 0, 1000000, s, "relocalise_max_frames");
  core::requireInRange(relocalise_after_gap, 0, 1e9, s, "relocalise_after_gap");
  core::requireInRange(relocalise_patience, 1, 1000000, s, "relocalise_patience");
  core::requireInRange(delete_min_match_ratio, 0, 1, s, "delete_min_match_ratio");
  core::requirePositive(linearity_threshold, s, "linearity_threshold");
  core::requireInRange(num_threads, 1, 64, s, "num_threads");
}
}  // namespace immslam::slam
