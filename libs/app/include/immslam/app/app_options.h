/* imm-monoslam — options of the application itself: [input] and [output]. */
#pragma once

#include <mrpt/config/CLoadableOptions.h>

#include <string>

namespace immslam::app
{
/** Section [input]: where frames come from when no INPUT/--live is given. */
struct TInputOptions : public mrpt::config::CLoadableOptions
{
  /** `synthetic` (the built-in renderer), or a .rawlog / dataset folder path (relative paths are
   * resolved against the config file's folder, then the current folder). */
  std::string source = "synthetic";
  /** Scenario of the synthetic source (a file like ini/scenarios/handheld.ini); empty: the built-in default scene. */
  std::string scenario;
  /** Frame rate assumed for live sources without timestamps (image_dir, ffmpeg). */
  double live_frame_rate_hz = 30;
  bool live_paced = false;          ///< --live: deliver a replayed source (image_dir, ffmpeg file, rawlog) at its frame rate
  /** The camera of a rawlog holding the images of several sensors (their `sensorLabel`); empty: the
   * first one in the file (io::CRawlogSource). */
  std::string rawlog_sensor_label;
  /** Images wider than this are processed at half, quarter, ... size (the smallest power-of-two
   * reduction that fits, area-averaged, after dropping the last columns/rows it does not divide; the
   * calibration scaled with them). 0 (default): every size as it is; sharp 1280x960 images track
   * better at full size (doc/usage.md), soft or blown-up HD video may find corners only reduced. */
  int max_image_width = 0;
  /** A folder of per-frame masks of pixels to leave out (non-zero: excluded; e.g. known moving
   * objects): no new feature starts and no SLAM match is accepted there. The layout of imm-render's
   * and imm-composite's outputs: rgb.txt (`timestamp rgb/NAME`) and masks/NAME, the mask of the frame
   * with that timestamp. Empty (default): none. With a rendered folder's truth this is the
   * MonoSLAMBOT paper's Fig. 5(a) baseline, the dynamic features disabled (doc/shadow.md). */
  std::string exclusion_masks;
  /** A file of measured point tracks, `timestamp point_id kind x y z u v` per line (the format of
   * monoslammot_synth19's points_groundtruth.txt; x y z are not used): known data association. The
   * images are still read (timestamps, overlays) but the filters take these measurements instead of
   * searching the images (CMonoSlamSystem::processMeasurements): the MonoSLAMBOT paper's Fig. 5
   * experiment, "data association performed manually". Lines are matched to frames by timestamp
   * (within 0.1 ms). Empty (default): the image front end. */
  std::string known_association;
  /** Which tracks of known_association are used: `all` (default), or the kind of its third column
   * (`static`: the dynamic points disabled, Fig. 5(a)). */
  std::string known_association_kinds = "all";
  /** With known_association: true (default), SLAM treats the given matches as its active search
   * would (a match outside its search ellipse is not found, 1-point RANSAC, deletion, handovers);
   * false, it uses every one (the paper's classic MonoSLAM with manual association). */
  bool known_association_robust = true;
  /** With known_association: `all` (default) tracks may start the first map; `static`: only those of
   * kind static, the paper's start (Sec. II: SLAM starts on static features "before perceiving
   * dynamic features"); moving tracks in view then start later, in the shadow filter. */
  std::string known_association_first_map = "all";

  void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
  void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override;
};

/** Section [output]: optional outputs beyond the per-frame files. */
struct TOutputOptions : public mrpt::config::CLoadableOptions
{
  bool scene = true;        ///< write scene.3Dscene at the end
  int scene_every_n = 0;    ///< also scene_NNNNNN.3Dscene (+ .png snapshot) every N frames (0: never)
  bool overlays = false;    ///< write overlay images (search ellipses, matches, classes)
  int overlay_every_n = 1;  ///< every N frames
  bool overlay_video = false;  ///< also overlays.avi
  int gui_scene_every_n = 10;  ///< live 3-D window refresh period (frames), when windows are open
  bool search_log = false;  ///< searches.csv (and shadow_log.csv): every search / shadow feature of every frame
  /** relative_poses.csv: every frame, the camera's motion over the last N frames with the SLAM filter's
   * covariance, from pose clones in the state (CSlamTracker::setRelativePoseLag): slam-eval
   * relative-nees checks it against ground truth. 0: none. */
  int relative_pose_lag = 0;
  bool refine_trajectory = false;  ///< trajectory_refined.txt: a bundle adjustment of the run's own matches at the end
  bool smooth_trajectory = true;  ///< trajectory_smoothed.txt: the online keyframe smoother (its own thread)

  void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
  void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override;
};
}  // namespace immslam::app
