/* imm-monoslam — imm-rotate (see rotated_view.h). */
#include <immslam/camera/CPinholeCamera.h>
#include <immslam/io/CDatasetWriter.h>
#include <immslam/io/CImageSource.h>
#include <immslam/io/CVideoFileSource.h>
#include <immslam/math/quaternion.h>
#include <immslam/sim/rotated_view.h>

#include "number_list.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/background_segm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace immslam::sim
{
namespace
{
constexpr double kPi = 3.14159265358979323846;

/** Opens a dataset folder, a rawlog or a video file (frame rate `fps` for a video; 0 = its own). */
io::CImageSource::Ptr openSource(const std::string& source, double fps)
{
  std::error_code ec;
  if (!fs::exists(source, ec)) throw std::runtime_error("source not found: " + source);
  if (!fs::is_directory(source, ec) && io::isVideoFile(source)) return std::make_unique<io::CVideoFileSource>(source, fps);
  return io::openImageSource(source);
}

/** Next frame of `src`; unreadable entries are skipped and counted. False at the end. */
bool nextFrame(io::CImageSource& src, io::TFrame& f, std::size_t& skipped)
{
  for (;;)
  {
    std::string why;
    const io::ENextStatus s = src.next(f, why);
    if (s == io::ENextStatus::Frame) return true;
    if (s == io::ENextStatus::End) return false;
    ++skipped;
  }
}

void validate(const TRotatedViewOptions& o)
{
  if (o.width < 0 || o.height < 0) throw std::invalid_argument("virtual image size must be >= 0 (0 = default)");
  if (!(o.focal >= 0) || !std::isfinite(o.focal)) throw std::invalid_argument("focal length must be >= 0 (0 = the source's)");
  for (double a : {o.panDeg, o.tiltDeg, o.rollDeg})
    if (!std::isfinite(a) || std::abs(a) > 45) throw std::invalid_argument("rotation amplitudes must be within +-45 degrees");
  if (!(o.periodFrames > 0) || !std::isfinite(o.periodFrames)) throw std::invalid_argument("period must be > 0 frames");
  if (!(o.varThreshold > 0) || !std::isfinite(o.varThreshold))
    throw std::invalid_argument("background-subtraction threshold must be > 0 (squared sigmas)");
  if (o.dilatePx < 0 || o.dilatePx > 100) throw std::invalid_argument("dilation must be 0-100 px");
  if (!(o.fps >= 0) || !std::isfinite(o.fps)) throw std::invalid_argument("fps must be >= 0 (0 = the video's)");
}

/** OpenCV's Gaussian-mixture background subtractor (Zivkovic 2004, `cv::BackgroundSubtractorMOG2`) for
 * a still camera, learned over the whole video before any frame is labelled. Pass 1 feeds every frame
 * in order with learning rate 1 / (k + 1) at frame k: each mode's weight is then the fraction of the
 * frames so far in which the pixel showed it (a running mean with every frame weighed alike), so a
 * person who stands still for a while stays a small mode instead of becoming the background as with
 * a fixed short history. Pass 2 (writeMovingMask) labels each frame with learning rate 0 against
 * that one model. The background is the largest modes up to `kBackgroundRatio` = 0.5 of the frames
 * (OpenCV's default 0.9 would also take any mode seen in more than 10 % of the frames: on box.mp4 the
 * arm, which lies over the same part of the image for much of the video); so a pixel is foreground
 * while it shows something it shows in less than half of the video's frames. The `history` only
 * bounds OpenCV's automatic learning rate, which is not used. Shadows (a darker copy of the
 * background's colour) are detected and count as background: a shadow is no object. */
cv::Ptr<cv::BackgroundSubtractorMOG2> learnBackground(const std::string& source, const TRotatedViewOptions& o)
{
  constexpr double kBackgroundRatio = 0.5;
  // Lower bound of a mode's variance, grey levels squared: 25 (sigma >= 5) instead of OpenCV's 4. The
  // videos are compressed and the camera's exposure breathes; on box.mp4's bright white table the
  // default marks patches of the table as moving whenever the box comes near.
  constexpr double kMinVariance = 25;
  const io::CImageSource::Ptr rd = openSource(source, o.fps);
  cv::Ptr<cv::BackgroundSubtractorMOG2> mog = cv::createBackgroundSubtractorMOG2(1000, o.varThreshold, true);
  mog->setBackgroundRatio(kBackgroundRatio);
  mog->setVarMin(kMinVariance);
  std::size_t n = 0, skipped = 0;
  io::TFrame f;
  cv::Mat fg;
  cv::Size size;
  while ((o.maxFrames == 0 || n < o.maxFrames) && nextFrame(*rd, f, skipped))
  {
    const cv::Mat& in = f.colour.empty() ? f.grey : f.colour;
    if (n > 0 && in.size() != size) continue;  // (checked when written)
    size = in.size();
    mog->apply(in, fg, 1.0 / static_cast<double>(n + 1));
    ++n;
  }
  if (n == 0) throw std::runtime_error("no readable frame in " + source);
  return mog;
}

/** What moves in `frame` by the learned model (learning rate 0: the model stays the whole video's):
 * MOG2's foreground (255; shadows, 127, are background), a 3x3 opening (isolated noise), small holes
 * filled, dilated. */
cv::Mat movingMask(const cv::Mat& frame, cv::BackgroundSubtractorMOG2& mog, const TRotatedViewOptions& o)
{
  cv::Mat fg, mask;
  mog.apply(frame, fg, 0.0);
  cv::threshold(fg, mask, 254, 1, cv::THRESH_BINARY);
  cv::morphologyEx(mask, mask, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  // Holes inside a moving region smaller than 1 % of the image are parts of it whose grey level
  // happens to match the background (a moving object is solid); larger ones are world seen through.
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(mask.clone(), contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_SIMPLE);
  const double maxHole = 0.01 * mask.rows * mask.cols;
  for (std::size_t k = 0; k < contours.size(); ++k)
    if (hierarchy[k][3] >= 0 && cv::contourArea(contours[k]) < maxHole)
      cv::drawContours(mask, contours, static_cast<int>(k), cv::Scalar(1), cv::FILLED);
  if (o.dilatePx > 0)
    cv::dilate(mask, mask,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * o.dilatePx + 1, 2 * o.dilatePx + 1}));
  return mask;
}

}  // namespace

Vec4 rotatedViewQuaternion(const TRotatedViewOptions& o, std::size_t i)
{
  const double t = 2 * kPi * static_cast<double>(i) / o.periodFrames;
  const double deg = kPi / 180;
  const Vec4 qPan = math::quatFromRotationVector(Vec3(0, o.panDeg * deg * std::sin(t), 0));
  const Vec4 qTilt = math::quatFromRotationVector(Vec3(o.tiltDeg * deg * std::sin(t / 1.37), 0, 0));
  const Vec4 qRoll = math::quatFromRotationVector(Vec3(0, 0, o.rollDeg * deg * std::sin(t / 1.83)));
  return math::quatMultiply(math::quatMultiply(qPan, qTilt), qRoll);
}

namespace
{
/** The remap of a virtual frame: each virtual pixel's ray (`rays`) rotated by R into the source
 * camera and projected with its lens (-1e4 outside the source image); returns how many fall outside. */
std::size_t rotatedMaps(const camera::CCameraModel& src, const Mat3& R, const std::vector<Vec3>& rays, cv::Mat& mapU,
                        cv::Mat& mapV)
{
  const int W = mapU.cols, H = mapU.rows;
  std::size_t outside = 0;
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u)
    {
      Vec2 uv;
      const bool ok = src.project(R * rays[static_cast<std::size_t>(v) * W + u], uv) && src.isInImage(uv);
      mapU.at<float>(v, u) = ok ? static_cast<float>(uv.x()) : -1e4f;
      mapV.at<float>(v, u) = ok ? static_cast<float>(uv.y()) : -1e4f;
      outside += ok ? 0 : 1;
    }
  return outside;
}

/** Ground truth of the virtual camera at time t, rotated by q: in the source's world (the source's
 * pose within 1 ms), or the identity for a still source; false when there is none. */
bool virtualGroundTruth(const std::optional<core::TTrajectory>& sourceGt, double t, const Vec4& q, bool still,
                        core::TStampedPose& gt)
{
  gt.timestamp = t;
  gt.q_W_C = q;
  bool haveGt = still;
  if (sourceGt && !sourceGt->empty())
  {
    const auto best = std::min_element(sourceGt->begin(), sourceGt->end(), [&](const auto& a, const auto& b) {
      return std::abs(a.timestamp - t) < std::abs(b.timestamp - t);
    });
    if (std::abs(best->timestamp - t) < 1e-3)
    {
      gt.p_W_C = best->p_W_C;
      gt.q_W_C = math::quatMultiply(best->q_W_C, q);
      haveGt = true;
    }
  }
  return haveGt;
}

/** The mask of what moves in a still source's frame (by the learned model `mog`), remapped into the
 * virtual view and written to `file`; returns the fraction of the view it covers. */
double writeMovingMask(const cv::Mat& frame, cv::BackgroundSubtractorMOG2& mog, const TRotatedViewOptions& o,
                       const cv::Mat& mapU, const cv::Mat& mapV, const std::string& file)
{
  const cv::Mat maskSrc = movingMask(frame, mog, o);
  cv::Mat mask;
  cv::remap(maskSrc, mask, mapU, mapV, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
  if (!cv::imwrite(file, mask)) throw std::runtime_error("cannot write " + file);
  return cv::countNonZero(mask) / (mapU.cols * static_cast<double>(mapU.rows));
}

/** The output folder of a still source: masks/ and background.png (the learned model's background). */
void prepareStillOutputs(const std::string& outFolder, const cv::BackgroundSubtractorMOG2& mog)
{
  fs::create_directories(fs::path(outFolder) / "masks");
  cv::Mat background;
  mog.getBackgroundImage(background);
  const std::string bgFile = (fs::path(outFolder) / "background.png").string();
  if (!cv::imwrite(bgFile, background)) throw std::runtime_error("cannot write " + bgFile);
}

/** The unit rays of the virtual camera's pixels (row-major). */
std::vector<Vec3> pixelRays(const camera::CPinholeCamera& virt)
{
  const int W = virt.width(), H = virt.height();
  std::vector<Vec3> rays(static_cast<std::size_t>(W) * static_cast<std::size_t>(H));
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) rays[static_cast<std::size_t>(v) * W + u] = virt.unproject(Vec2(u, v)).unitVector();
  return rays;
}
}  // namespace

TRotatedViewStats rotateStillVideo(const std::string& source, const std::string& outFolder,
                                   const TRotatedViewOptions& o)
{
  validate(o);
  {
    std::error_code ec;
    if (fs::exists(outFolder, ec) && fs::equivalent(source, outFolder, ec))
      throw std::runtime_error("the output folder " + outFolder + " is the source folder");
  }
  const io::CImageSource::Ptr reader = openSource(source, o.fps);
  camera::CCameraModel::Ptr src = o.calibFile.empty() ? reader->calibration() : camera::loadCalibFile(o.calibFile);
  if (!src) throw std::runtime_error(source + " has no calibration: give --calib FILE (calib.txt format)");
  const auto sourceGt = reader->groundTruth();
  const int W = o.width > 0 ? o.width : 2 * static_cast<int>(std::lround(0.4 * src->width()));
  const int H = o.height > 0 ? o.height : 2 * static_cast<int>(std::lround(0.4 * src->height()));
  if (W > src->width() || H > src->height())
    throw std::runtime_error("virtual image " + std::to_string(W) + "x" + std::to_string(H) +
                             " is larger than the source's " + std::to_string(src->width()) + "x" +
                             std::to_string(src->height()));
  const double f = o.focal > 0 ? o.focal : src->fx();
  const camera::CPinholeCamera virt(W, H, f, f, 0.5 * (W - 1), 0.5 * (H - 1));

  cv::Ptr<cv::BackgroundSubtractorMOG2> mog;
  if (o.still) mog = learnBackground(source, o);

  fs::create_directories(outFolder);
  if (o.still) prepareStillOutputs(outFolder, *mog);
  std::ostringstream comment;
  comment << "imm-rotate: " << source << " seen by a camera rotating about its optical centre (pan " << o.panDeg
          << ", tilt " << o.tiltDeg << ", roll " << o.rollDeg << " deg, period " << o.periodFrames << " frames)";
  io::CDatasetWriter writer(outFolder, virt, comment.str());
  // Motion labels only for a still source (a moving one's motion class is not known here).
  const std::string labelsFile = (fs::path(outFolder) / "motion_labels.txt").string();
  std::ofstream labels;
  if (o.still)
  {
    labels.open(labelsFile);
    if (!labels) throw std::runtime_error("cannot write " + labelsFile);
    labels << "# true camera motion since the previous frame (frame 0: stationary): stationary, rotation, general\n"
              "# timestamp label\n";
  }
  const bool rotates = o.panDeg != 0 || o.tiltDeg != 0 || o.rollDeg != 0;

  TRotatedViewStats st;
  cv::Mat mapU(H, W, CV_32FC1), mapV(H, W, CV_32FC1);
  // The virtual pixels' rays, once; each frame only rotates and projects them.
  const std::vector<Vec3> rays = pixelRays(virt);
  io::TFrame fr;
  std::size_t n = 0;
  double movingSum = 0;
  while ((o.maxFrames == 0 || n < o.maxFrames) && nextFrame(*reader, fr, st.skipped))
  {
    if (fr.grey.cols != src->width() || fr.grey.rows != src->height())
      throw std::runtime_error(source + ": frame " + std::to_string(fr.index) + " is " + std::to_string(fr.grey.cols) +
                               "x" + std::to_string(fr.grey.rows) + ", the calibration " +
                               std::to_string(src->width()) + "x" + std::to_string(src->height()));
    const Vec4 q = rotatedViewQuaternion(o, n);
    const Mat3 R = math::quatToRotation(q);
    st.maxAngleDeg = std::max(st.maxAngleDeg, 2 * std::acos(std::min(1.0, std::abs(q[0]))) * 180 / kPi);
    const std::size_t outside = rotatedMaps(*src, R, rays, mapU, mapV);
    st.maxOutsideFraction = std::max(st.maxOutsideFraction, static_cast<double>(outside) / (W * static_cast<double>(H)));
    const cv::Mat& in = fr.colour.empty() ? fr.grey : fr.colour;
    cv::Mat out;
    cv::remap(in, out, mapU, mapV, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    core::TStampedPose gt;
    const bool haveGt = virtualGroundTruth(sourceGt, fr.timestamp, q, o.still, gt);
    const std::string name = writer.addFrame(fr.timestamp, out, haveGt ? &gt : nullptr);
    char stamp[64];
    std::snprintf(stamp, sizeof(stamp), "%.6f", fr.timestamp);
    if (o.still) labels << stamp << ' ' << (n > 0 && rotates ? "rotation" : "stationary") << '\n';
    if (o.still)
      movingSum += writeMovingMask(in, *mog, o, mapU, mapV,
                                   (fs::path(outFolder) / "masks" / fs::path(name).filename()).string());
    ++n;
  }
  writer.close();
  if (o.still && !labels) throw std::runtime_error("write error in " + labelsFile);
  if (n == 0) throw std::runtime_error("no readable frame in " + source);
  st.frames = n;
  st.meanMovingFraction = movingSum / static_cast<double>(n);
  return st;
}

std::string rotateAppUsage()
{
  return "Usage: imm-rotate SOURCE OUT_FOLDER [options]\n"
         "Makes a rotating camera's video from a real one (a still camera: tripod, webcam) and writes it as\n"
         "a dataset folder with the truth: each frame is what a virtual camera with the same optical centre,\n"
         "rotated by a scripted R(t), sees (a homography for a pure rotation, exact up to resampling); the\n"
         "virtual image is a centred crop of the real view. Writes rgb/ rgb.txt calib.txt (pinhole, the\n"
         "virtual camera) groundtruth.txt (the rotation; composed with the source's own ground truth if it\n"
         "has one), and for a still source motion_labels.txt, masks/ (1 = what moves: foreground of OpenCV's\n"
         "MOG2 background subtractor learned over the whole video, shadows excluded) and background.png.\n"
         "SOURCE: a video file (any format OpenCV/FFmpeg decodes), a dataset folder or a .rawlog.\n"
         "Options:\n"
         "  --calib FILE            the source's calibration (calib.txt format; required for a video)\n"
         "  --size W,H              virtual image size (default 0.8 x the source's)\n"
         "  --focal F               virtual focal length, px (default the source's fx)\n"
         "  --rotate PAN,TILT,ROLL  amplitudes in degrees (default 3,2,1.5; 0,0,0 = a still camera)\n"
         "  --period FRAMES         period of the pan (default 120; tilt 1.37x, roll 1.83x)\n"
         "  --moving-source         the source camera moved: no masks (the background is not still)\n"
         "  --var-threshold D2      squared distance to the background, in sigmas, that marks a moving pixel\n"
         "                          (MOG2's varThreshold, default 16)\n"
         "  --dilate PX             mask dilation radius (default 4)\n"
         "  --frames N              stop after N frames\n"
         "  --fps F                 frame rate of a video source (default the container's)\n"
         "  --help                  this text\n"
         "Exit status: 0 success, 1 bad input or failure, 2 bad usage.\n";
}

int runRotateApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err)
{
  const auto usageError = [&](const std::string& msg) {
    err << "imm-rotate: " << msg << "\n" << rotateAppUsage();
    return 2;
  };
  TRotatedViewOptions o;
  std::vector<std::string> positional;
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h")
    {
      out << rotateAppUsage();
      return 0;
    }
    if (a == "--moving-source")
    {
      o.still = false;
      continue;
    }
    if (a.rfind("--", 0) != 0)
    {
      positional.push_back(a);
      continue;
    }
    if (i + 1 >= args.size()) return usageError(a + " needs a value");
    const std::string& v = args[++i];
    if (a == "--calib")
    {
      o.calibFile = v;
      continue;
    }
    std::vector<double> x;
    if (!parseNumberList(v, x)) return usageError(a + ": '" + v + "' is not a number list");
    const auto isCount = [](double d) { return d >= 0 && d == std::floor(d) && d < 1e9; };
    if (a == "--size")
    {
      if (x.size() != 2 || !isCount(x[0]) || !isCount(x[1]) || x[0] < 16 || x[1] < 16)
        return usageError("--size needs W,H (integers >= 16), got '" + v + "'");
      o.width = static_cast<int>(x[0]), o.height = static_cast<int>(x[1]);
    }
    else if (a == "--focal" && x.size() == 1 && x[0] > 0)
      o.focal = x[0];
    else if (a == "--rotate" && x.size() == 3)
      o.panDeg = x[0], o.tiltDeg = x[1], o.rollDeg = x[2];
    else if (a == "--period" && x.size() == 1 && x[0] > 0)
      o.periodFrames = x[0];
    else if (a == "--var-threshold" && x.size() == 1)
      o.varThreshold = x[0];
    else if (a == "--dilate" && x.size() == 1 && isCount(x[0]))
      o.dilatePx = static_cast<int>(x[0]);
    else if (a == "--frames" && x.size() == 1 && isCount(x[0]) && x[0] > 0)
      o.maxFrames = static_cast<std::size_t>(x[0]);
    else if (a == "--fps" && x.size() == 1 && x[0] > 0)
      o.fps = x[0];
    else if (a == "--focal" || a == "--rotate" || a == "--period" || a == "--var-threshold" || a == "--dilate" ||
             a == "--frames" || a == "--fps")
      return usageError("bad value for " + a + ": '" + v + "'");
    else
      return usageError("unknown option '" + a + "'");
  }
  if (positional.size() != 2) return usageError("expected SOURCE and OUT_FOLDER");
  try
  {
    const TRotatedViewStats s = rotateStillVideo(positional[0], positional[1], o);
    out << "imm-rotate: wrote " << s.frames << " frames to " << positional[1] << " (" << s.skipped
        << " unreadable source frames skipped); rotation up to " << s.maxAngleDeg << " deg, at most "
        << 100.0 * s.maxOutsideFraction << " % of a virtual image outside the real one";
    if (o.still) out << "; " << 100.0 * s.meanMovingFraction << " % of the image marked moving on average";
    out << "\n";
    return 0;
  }
  catch (const std::exception& e)
  {
    err << "imm-rotate: error: " << e.what() << "\n";
    return 1;
  }
}
}  // namespace immslam::sim
