/* imm-monoslam — a rendered scenario: camera, world, camera motion script and moving objects,
 * read from an MRPT-style ini file (ini/scenarios/ files). */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/math/types.h>
#include <immslam/sim/types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace mrpt::config
{
class CConfigFileBase;
}

namespace immslam::sim
{
/** One segment of the camera motion script: its type and duration. */
struct TMotionSegment
{
  EMotionLabel type = EMotionLabel::General;
  double duration_s = 1.0;
};

/** Path shapes of a moving object. */
enum class EObjectPath
{
  Linear,   ///< back and forth along `direction`: \f$ c + a\,d\,\sin(2\pi t/T + \varphi) \f$
  Circular  ///< a circle of radius a about `center` in the plane normal to `direction`
};

/** A moving textured box (section `[objectK]`, K = its id, 1..254). Its pose T_W_O(t) is an analytic
 * function of time (CWorld::objectPose()). */
struct TMovingObjectSpec
{
  int id = 1;
  /** Edge lengths along the object's x, y, z axes (units). */
  Vec3 size = Vec3(0.4, 0.4, 0.4);
  EObjectPath path = EObjectPath::Linear;
  /** Centre of the path in W. */
  Vec3 center = Vec3(0, 0, 2);
  /** Linear: the direction of travel; circular: the normal of the circle's plane (any length > 0). */
  Vec3 direction = Vec3(1, 0, 0);
  /** Linear: half the travel; circular: the radius (units). */
  double amplitude = 1.0;
  /** Period of the back-and-forth or of one turn (s). */
  double period_s = 6.0;
  /** Phase at t = 0 (deg). */
  double phase_deg = 0.0;
  /** Initial rotation about the world's y axis (deg). */
  double yaw_deg = 0.0;
  /** Constant angular velocity in W (deg/s). */
  Vec3 spin_deg_s = Vec3::Zero();
  /** The object stands still, where its path puts it at this time, until this time (s from the
   * first frame); then it moves. Masks and pixel truth mark it as moving only from then on. */
  double start_s = 0.0;
};

/** Everything that defines a rendered sequence. All keys have defaults except `[scenario] camera`
 * and `[motion] segments`; unknown sections or keys are an error naming them.
 *
 * The world frame W is the camera frame of the first frame (doc/conventions.md): the camera starts
 * at the origin looking along +z with y down, and the room and boxes are given in that frame
 * (the floor is at y = room_max.y). */
struct TScenario
{
  // ---- [scenario]
  /** Camera model, `camera = MODEL W H PARAMS...` in calib.txt syntax. */
  camera::CCameraModel::Ptr camera;
  /** Frame rate (Hz): frame k is at time start_time_s + k / fps. */
  double fps = 30.0;
  /** Master seed of every random choice (textures, layout, camera path, pixel noise). */
  std::uint64_t seed = 1;
  /** Timestamp of the first frame (s). */
  double start_time_s = 0.0;
  /** Render threads (rows are split; the output does not depend on it). 0: all cores. */
  int threads = 2;

  // ---- [render]
  /** Standard deviation of the Gaussian pixel noise (grey levels); 0 disables it. */
  double noise_sigma_grey = 2.0;
  /** Standard deviation of a Gaussian blur applied before the noise (pixels); 0 disables it. */
  double blur_sigma_px = 0.0;
  /** Also render a colour image (each face tinted); the grey image is then its luminance. */
  bool colour = false;
  /** Texture resolution (texels per unit length). */
  double texels_per_unit = 100.0;
  /** Density of the procedural texture shapes (per square unit of surface). */
  double shapes_per_unit2 = 16.0;
  /** The same for the moving objects: small and close to the camera, they need a denser texture to
   * show as many trackable corners per image area as the room does. */
  double object_shapes_per_unit2 = 96.0;
  /** Texture resolution of the moving objects (texels per unit length): they are seen close up. */
  double object_texels_per_unit = 400.0;

  // ---- [world]
  /** The room: an axis-aligned box in W (its six inner faces are textured). */
  Vec3 room_min = Vec3(-4.0, -1.5, -2.0);
  Vec3 room_max = Vec3(4.0, 1.5, 4.0);
  /** Number of static textured boxes (placed at random from the seed). */
  int n_boxes = 14;
  /** Edge length ranges of the static boxes (x, y = height, z). */
  Vec3 box_size_min = Vec3(0.3, 0.3, 0.3);
  Vec3 box_size_max = Vec3(1.0, 1.4, 1.0);
  /** Fraction of static boxes hung on the walls (cabinets, frames) instead of standing on the floor. */
  double wall_box_fraction = 0.35;
  /** Floor rectangle [x_min z_min x_max z_max] kept free of static boxes (the camera's and the
   * moving objects' space). */
  Vec4 keep_out = Vec4(-2.2, -1.2, 2.2, 2.6);

  // ---- [motion]
  /** The motion script, e.g. `segments = stationary 2, rotation 3, general 4`. */
  std::vector<TMotionSegment> segments;
  /** Time over which velocities ramp up/down at segment changes (s); bounds the acceleration. */
  double ramp_s = 0.3;
  /** Peak excursion of the hand-held target path per world axis (units). */
  Vec3 amplitude_units = Vec3(0.35, 0.12, 0.35);
  /** Peak excursion of the target orientation about the camera's x (tilt), y (pan) and z (roll)
   * axes (deg). */
  Vec3 amplitude_deg = Vec3(10.0, 25.0, 4.0);
  /** Caps on the speed along each world axis (units/s) and on the rotation rate about each
   * camera axis (deg/s): the path's amplitudes are scaled down when their rate bound exceeds them. */
  Vec3 max_speed_units_s = Vec3(0.35, 0.12, 0.35);
  Vec3 max_rate_deg_s = Vec3(12.0, 25.0, 5.0);
  /** Frequency range of the sinusoids of the hand-held target path (Hz). */
  Vec2 freq_hz = Vec2(0.1, 1.0);
  /** Sinusoids per axis. */
  int n_sinusoids = 3;
  /** Minimum distance kept by the camera centre from walls, boxes and moving objects (units);
   * a scenario that violates it is rejected with an error. */
  double min_clearance = 0.3;

  // ---- [objects] and [objectK]
  /** Render the moving objects (the camera path and the static world do not depend on it). */
  bool objects_enabled = true;
  std::vector<TMovingObjectSpec> objects;

  /** Where the scenario came from (file name), for messages. */
  std::string origin;

  /** Total duration of the motion script (s). */
  double duration() const;

  /** Number of frames: floor(duration * fps). */
  std::size_t frameCount() const;

  /** Checks ranges and consistency. \throws std::runtime_error naming origin, section and key. */
  void validate() const;

  /** Reads every section; unknown sections/keys and malformed values are errors naming
   * `origin`, the section and the key. */
  static TScenario fromConfig(const mrpt::config::CConfigFileBase& cfg, const std::string& origin);

  /** Reads an ini file, then applies overrides `SECTION.KEY=VALUE` (as `--set`). */
  static TScenario loadFile(const std::string& path, const std::vector<std::string>& overrides = {});

  /** Same for ini text held in memory (`origin` names it in errors). */
  static TScenario loadString(const std::string& text, const std::string& origin,
                              const std::vector<std::string>& overrides = {});

  /** The built-in default scenario (ini/scenarios/default.ini, compiled in): what the main app
   * renders when given no input, available without any file. */
  static TScenario builtinDefault(const std::vector<std::string>& overrides = {});

  /** The complete effective scenario as ini text (every key, commented): loading it gives the same
   * sequence. */
  std::string toIni() const;
};

/** The text of ini/scenarios/default.ini as compiled into the library. */
std::string builtinDefaultScenarioText();
}  // namespace immslam::sim
