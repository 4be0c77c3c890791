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
  if (!(o.foregroundGrey > 0) || o.foregroundGrey > 255) throw std::invalid_argument("foreground threshold must be in (0, 255]");
  if (o.dilatePx < 0 || o.dilatePx > 100) throw std::invalid_argument("dilation must be 0-100 px");
  if (!(o.fps >= 0) || !std::isfinite(o.fps)) throw std::invalid_argument("fps must be >= 0 (0 = the video's)");
}

/** Background of a still camera. A temporal median fails where the moving things stay more than half
 * of the time (an arm held over the table), so each pixel's background is its most frequent *stable*
 * grey level: a frame counts for a pixel when the pixel changes by less than `kStable` grey levels
 * over `kLag` frames before and after it (a moving hand or object changes it; the world behind does
 * not). Levels are histogrammed in bins of 8; the background is the mean of the fullest bin (the
 * plain histogram when no frame was stable). Streams the video once with a 2 kLag + 1 frame window. */
cv::Mat stableBackground(const std::string& source, const TRotatedViewOptions& o)
{
  constexpr int kLag = 3, kStable = 6, kBins = 32;
  const io::CImageSource::Ptr rd = openSource(source, o.fps);
  std::vector<cv::Mat> window;  // the last 2 kLag + 1 grey frames
  cv::Mat count, sum, countAll, sumAll;  // per pixel x bin: CV_32S counts, CV_32F sums
  std::size_t n = 0, skipped = 0;
  io::TFrame f;
  const auto accumulate = [&](const cv::Mat& g, bool stableOnly, const cv::Mat& prev, const cv::Mat& next) {
    for (int y = 0; y < g.rows; ++y)
      for (int x = 0; x < g.cols; ++x)
      {
        const int v = g.at<unsigned char>(y, x);
        const int idx = (y * g.cols + x) * kBins + v / (256 / kBins);
        countAll.at<int>(idx) += 1;
        sumAll.at<float>(idx) += static_cast<float>(v);
        if (stableOnly && std::abs(v - prev.at<unsigned char>(y, x)) < kStable &&
            std::abs(v - next.at<unsigned char>(y, x)) < kStable)
        {
          count.at<int>(idx) += 1;
          sum.at<float>(idx) += static_cast<float>(v);
        }
      }
  };
  while ((o.maxFrames == 0 || n < o.maxFrames) && nextFrame(*rd, f, skipped))
  {
    if (count.empty())
    {
      const int cells = f.grey.rows * f.grey.cols * kBins;
      count = cv::Mat::zeros(1, cells, CV_32S), countAll = count.clone();
      sum = cv::Mat::zeros(1, cells, CV_32F), sumAll = sum.clone();
    }
    if (!window.empty() && f.grey.size() != window.front().size()) continue;  // (checked when written)
    window.push_back(f.grey.clone());
    // Each frame is counted once: the first kLag (no past to test) as they come, the others when
    // they are the window's centre, the last kLag (no future) after the loop.
    if (n < static_cast<std::size_t>(kLag)) accumulate(window.back(), false, window.back(), window.back());
    if (window.size() == 2 * kLag + 1)
    {
      accumulate(window[kLag], true, window.front(), window.back());
      window.erase(window.begin());
    }
    ++n;
  }
  if (window.empty()) throw std::runtime_error("no readable frame in " + source);
  const std::size_t firstLeft = std::max<std::size_t>(kLag, n >= static_cast<std::size_t>(kLag) ? n - kLag : 0);
  for (std::size_t k = 0; k < window.size(); ++k)
    if (n - window.size() + k >= firstLeft) accumulate(window[k], false, window[k], window[k]);
  const cv::Size size = window.back().size();
  cv::Mat bg(size, CV_8UC1);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x)
    {
      const int base = (y * size.width + x) * kBins;
      const bool anyStable = [&] {
        for (int b = 0; b < kBins; ++b)
          if (count.at<int>(base + b) > 0) return true;
        return false;
      }();
      const cv::Mat& c = anyStable ? count : countAll;
      const cv::Mat& s = anyStable ? sum : sumAll;
      int best = 0;
      for (int b = 1; b < kBins; ++b)
        if (c.at<int>(base + b) > c.at<int>(base + best)) best = b;
      bg.at<unsigned char>(y, x) = cv::saturate_cast<unsigned char>(s.at<float>(base + best) / c.at<int>(base + best));
    }
  return bg;
}

/** Pixels that differ from the background: threshold, 3x3 opening (sensor noise), dilation. */
cv::Mat movingMask(const cv::Mat& grey, const cv::Mat& background, const TRotatedViewOptions& o)
{
  cv::Mat diff, mask;
  cv::absdiff(grey, background, diff);
  cv::threshold(diff, mask, o.foregroundGrey, 1, cv::THRESH_BINARY);
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

/** The mask of what moves in a still source's frame (`grey` against `background`), remapped into
 * the virtual view and written to `file`; returns the fraction of the view it covers. */
double writeMovingMask(const cv::Mat& grey, const cv::Mat& background, const TRotatedViewOptions& o,
                       const cv::Mat& mapU, const cv::Mat& mapV, const std::string& file)
{
  const cv::Mat maskSrc = movingMask(grey, background, o);
  cv::Mat mask;
  cv::remap(maskSrc, mask, mapU, mapV, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
  if (!cv::imwrite(file, mask)) throw std::runtime_error("cannot write " + file);
  return cv::countNonZero(mask) / (mapU.cols * static_cast<double>(mapU.rows));
}

/** The output folder of a still source: masks/ and background.png. */
void prepareStillOutputs(const std::string& outFolder, const cv::Mat& background)
{
  fs::create_directories(fs::path(outFolder) / "masks");
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

  cv::Mat background;
  if (o.still) background = stableBackground(source, o);

  fs::create_directories(outFolder);
  if (o.still) prepareStillOutputs(outFolder, background);
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
      movingSum += writeMovingMask(fr.grey, background, o, mapU, mapV,
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
         "has one), and for a still source motion_labels.txt, masks/ (1 = pixel differs from the background,\n"
         "its most frequent stable grey level: what moves) and background.png.\n"
         "SOURCE: a video file (any format OpenCV/FFmpeg decodes), a dataset folder or a .rawlog.\n"
         "Options:\n"
         "  --calib FILE            the source's calibration (calib.txt format; required for a video)\n"
         "  --size W,H              virtual image size (default 0.8 x the source's)\n"
         "  --focal F               virtual focal length, px (default the source's fx)\n"
         "  --rotate PAN,TILT,ROLL  amplitudes in degrees (default 3,2,1.5; 0,0,0 = a still camera)\n"
         "  --period FRAMES         period of the pan (default 120; tilt 1.37x, roll 1.83x)\n"
         "  --moving-source         the source camera moved: no masks (the background is not still)\n"
         "  --threshold GREY        grey difference to the background that marks a moving pixel (default 30)\n"
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
    else if (a == "--threshold" && x.size() == 1)
      o.foregroundGrey = x[0];
    else if (a == "--dilate" && x.size() == 1 && isCount(x[0]))
      o.dilatePx = static_cast<int>(x[0]);
    else if (a == "--frames" && x.size() == 1 && isCount(x[0]) && x[0] > 0)
      o.maxFrames = static_cast<std::size_t>(x[0]);
    else if (a == "--fps" && x.size() == 1 && x[0] > 0)
      o.fps = x[0];
    else if (a == "--focal" || a == "--rotate" || a == "--period" || a == "--threshold" || a == "--dilate" ||
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
