/* imm-monoslam — [input] and [output] options. */
#include <immslam/app/app_options.h>
#include <immslam/core/config.h>

#include <stdexcept>

namespace immslam::app
{
void TInputOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
  IMMSLAM_LOAD_STRING(source);
  IMMSLAM_LOAD_STRING(scenario);
  IMMSLAM_LOAD_DOUBLE(live_frame_rate_hz);
  IMMSLAM_LOAD_BOOL(live_paced);
  IMMSLAM_LOAD_STRING(rawlog_sensor_label);
  IMMSLAM_LOAD_INT(max_image_width);
  IMMSLAM_LOAD_STRING(exclusion_masks);
  IMMSLAM_LOAD_STRING(known_association);
  IMMSLAM_LOAD_STRING(known_association_kinds);
  IMMSLAM_LOAD_BOOL(known_association_robust);
  IMMSLAM_LOAD_STRING(known_association_first_map);
  if (known_association_first_map != "all" && known_association_first_map != "static")
    throw std::runtime_error("[" + s + "] known_association_first_map = '" + known_association_first_map +
                             "': expected all or static");
  if (known_association_kinds != "all" && known_association_kinds != "static" && known_association_kinds != "moving")
    throw std::runtime_error("[" + s + "] known_association_kinds = '" + known_association_kinds +
                             "': expected all, static or moving");
  core::requireNonNegative(max_image_width, s, "max_image_width");
  core::requirePositive(live_frame_rate_hz, s, "live_frame_rate_hz");
  if (source.empty()) throw std::runtime_error("[" + s + "] source: empty (use 'synthetic' or a path)");
}

void TInputOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
  MRPT_SAVE_CONFIG_VAR_COMMENT(source, "synthetic | path of a .rawlog or dataset folder");
  MRPT_SAVE_CONFIG_VAR_COMMENT(scenario, "scenario of the synthetic source (empty: built-in default)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(live_frame_rate_hz, "frame rate of live sources without timestamps");
  MRPT_SAVE_CONFIG_VAR_COMMENT(live_paced, "--live: deliver a replay of files (image_dir, ffmpeg on a file, rawlog) at its frame rate, as the camera would");
  MRPT_SAVE_CONFIG_VAR_COMMENT(rawlog_sensor_label, "camera (sensorLabel) of a rawlog with several (empty: the first)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(max_image_width, "wider images are processed at 1/2, 1/4, ... size (0: never, the default)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(exclusion_masks, "folder with rgb.txt and masks/: per-frame masks of pixels with no new feature or SLAM match (empty: none)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(known_association, "file of point tracks 'timestamp id kind x y z u v': known data association instead of image search (empty: none)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(known_association_kinds, "tracks of known_association used: all | static | moving");
  MRPT_SAVE_CONFIG_VAR_COMMENT(known_association_first_map, "known_association: tracks that may start the first map: all | static (the paper's start)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(known_association_robust, "known_association: gate, 1-point RANSAC and delete as for images (false: use every match)");
}

void TOutputOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
  IMMSLAM_LOAD_BOOL(scene);
  IMMSLAM_LOAD_INT(scene_every_n);
  IMMSLAM_LOAD_BOOL(overlays);
  IMMSLAM_LOAD_INT(overlay_every_n);
  IMMSLAM_LOAD_BOOL(overlay_video);
  IMMSLAM_LOAD_BOOL(search_log);
  IMMSLAM_LOAD_INT(relative_pose_lag);
  core::requireInRange(relative_pose_lag, 0, 100, s, "relative_pose_lag");
  IMMSLAM_LOAD_BOOL(refine_trajectory);
  IMMSLAM_LOAD_BOOL(smooth_trajectory);
  IMMSLAM_LOAD_INT(gui_scene_every_n);
  core::requirePositive(gui_scene_every_n, s, "gui_scene_every_n");
  core::requireNonNegative(scene_every_n, s, "scene_every_n");
  core::requirePositive(overlay_every_n, s, "overlay_every_n");
}

void TOutputOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
  MRPT_SAVE_CONFIG_VAR_COMMENT(scene, "write scene.3Dscene (SceneViewer3D) at the end");
  MRPT_SAVE_CONFIG_VAR_COMMENT(scene_every_n, "also a scene every N frames (0: never)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(overlays, "write overlay images into overlays/");
  MRPT_SAVE_CONFIG_VAR_COMMENT(overlay_every_n, "overlay every N frames");
  MRPT_SAVE_CONFIG_VAR_COMMENT(overlay_video, "also overlays.avi (MJPG)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(gui_scene_every_n, "live 3-D window refresh period (frames; windows need a display, no --no-gui)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(search_log, "write searches.csv (every active search of every frame)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(relative_pose_lag, "write relative_poses.csv: the camera's motion over the last N frames with the filter's covariance (pose clones in the state; 0: none)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(refine_trajectory,
                               "at the end, bundle-adjust the run's own matches: trajectory_refined.txt (offline)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(smooth_trajectory,
                               "keyframe-window bundle adjustment in a background thread: trajectory_smoothed.txt");
}
}  // namespace immslam::app
