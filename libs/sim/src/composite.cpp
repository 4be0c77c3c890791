/* imm-monoslam — imm-composite (see composite.h). */
#include <immslam/io/CDatasetFolderSource.h>
#include <immslam/io/CDatasetWriter.h>
#include <immslam/sim/composite.h>

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
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace immslam::sim
{
namespace
{
/** A prepared object: texture (the frame's channel count, float) and its feathered elliptical
 * alpha, both at texture resolution. */
struct TPrepared
{
  cv::Mat texture;  ///< CV_32FC1 or CV_32FC3
  cv::Mat alpha;    ///< CV_32FC1 in [0, 1]
  std::shared_ptr<io::CDatasetFolderSource> video;  ///< a video object's frames (texture/alpha per frame)
};

/** The object's crop of an image (`name` for messages).
 * \throws std::invalid_argument if it is not inside the image or smaller than 4x4 px. */
cv::Rect cropOf(const TCompositeObject& o, std::size_t k, const cv::Mat& img, const std::string& name)
{
  const int w = o.cropW > 0 ? o.cropW : img.cols - o.cropX, h = o.cropH > 0 ? o.cropH : img.rows - o.cropY;
  if (w < 4 || h < 4 || o.cropX + w > img.cols || o.cropY + h > img.rows)
    throw std::invalid_argument("object " + std::to_string(k + 1) + ": crop " + std::to_string(o.cropX) + "," +
                                std::to_string(o.cropY) + "," + std::to_string(w) + "," + std::to_string(h) +
                                " is not inside '" + name + "' (" + std::to_string(img.cols) + "x" +
                                std::to_string(img.rows) + ", at least 4x4 px)");
  return cv::Rect(o.cropX, o.cropY, w, h);
}

/** Texture and alpha of a video object's frame j (false once the video has ended). The alpha is the
 * frame's mask, closed (a 9 px disc: parts of the object whose grey level matched the background
 * are kept) and feathered (Gaussian, 0.7 px). */
bool loadVideoFrame(const TCompositeObject& o, std::size_t k, TPrepared& p, std::size_t j, int channels)
{
  const auto& entries = p.video->entries();
  if (j >= entries.size()) return false;
  const std::string imgPath = p.video->imagePath(entries[j]);
  const std::string maskPath =
      (fs::path(o.video) / "masks" / fs::path(entries[j].path).filename()).string();
  const cv::Mat img = cv::imread(imgPath, channels == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
  const cv::Mat mask = cv::imread(maskPath, cv::IMREAD_GRAYSCALE);
  if (img.empty()) throw std::runtime_error("object " + std::to_string(k + 1) + ": cannot read video frame '" + imgPath + "'");
  if (mask.empty() || mask.size() != img.size())
    throw std::runtime_error("object " + std::to_string(k + 1) + ": no mask of the frame's size at '" + maskPath +
                             "' (a video object needs masks/, e.g. from imm-rotate)");
  const cv::Rect r = cropOf(o, k, img, o.video);
  img(r).convertTo(p.texture, channels == 1 ? CV_32FC1 : CV_32FC3);
  cv::Mat m = mask(r) > 0;
  cv::morphologyEx(m, m, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, {19, 19}));
  m.convertTo(p.alpha, CV_32FC1, 1.0 / 255.0);
  cv::GaussianBlur(p.alpha, p.alpha, {0, 0}, 0.7);
  return true;
}

void validate(const TCompositeObject& o, std::size_t k)
{
  const std::string what = "object " + std::to_string(k + 1) + " (" + (o.video.empty() ? o.image : o.video) + "): ";
  if (!(o.scaleFirst > 0) || !(o.scaleLast > 0)) throw std::invalid_argument(what + "scale must be > 0");
  if (!(o.wavePeriodFrames > 0)) throw std::invalid_argument(what + "wave period must be > 0 frames");
  if (!std::isfinite(o.waveAmplitudePx)) throw std::invalid_argument(what + "wave amplitude must be finite");
  if (o.firstFrame > o.lastFrame) throw std::invalid_argument(what + "span first frame after its last");
  if (o.cropX < 0 || o.cropY < 0 || o.cropW < 0 || o.cropH < 0)
    throw std::invalid_argument(what + "crop values must be >= 0");
  if (o.from.allFinite() != o.to.allFinite())
    throw std::invalid_argument(what + "give both ends of the path or neither");
}

TPrepared prepare(const TCompositeObject& o, std::size_t k, int channels)
{
  if (!o.video.empty())
  {
    TPrepared p;
    try
    {
      p.video = std::make_shared<io::CDatasetFolderSource>(o.video);
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error("object " + std::to_string(k + 1) + ": " + e.what());
    }
    if (!loadVideoFrame(o, k, p, o.videoStart, channels))
      throw std::invalid_argument("object " + std::to_string(k + 1) + ": video start " + std::to_string(o.videoStart) +
                                  " is past the end of " + o.video);
    return p;
  }
  const cv::Mat img = cv::imread(o.image, channels == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
  if (img.empty()) throw std::runtime_error("cannot read texture image '" + o.image + "'");
  const cv::Rect crop = cropOf(o, k, img, o.image);
  const int w = crop.width, h = crop.height;
  TPrepared p;
  img(crop).convertTo(p.texture, channels == 1 ? CV_32FC1 : CV_32FC3);
  // Elliptical silhouette inscribed in the crop, edge feathered over ~1.5 texture pixels centred on
  // the ellipse (a real object's edge is blurred by the optics, not a hard step; alpha 0.5 on it).
  p.alpha.create(h, w, CV_32FC1);
  const double a = 0.5 * w, b = 0.5 * h, feather = 1.5;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
    {
      const double dx = (x + 0.5 - a) / a, dy = (y + 0.5 - b) / b;
      const double r = std::sqrt(dx * dx + dy * dy);  // 1 on the ellipse
      p.alpha.at<float>(y, x) = static_cast<float>(std::clamp(0.5 + (1.0 - r) * std::min(a, b) / feather, 0.0, 1.0));
    }
  return p;
}

/** Centre pixel and scale of object o at output frame i (i inside its span). */
void placement(const TCompositeObject& o, std::size_t i, std::size_t last, const cv::Size& image, Vec2& centre,
               double& scale)
{
  const double span = static_cast<double>(last - o.firstFrame);
  const double s = span > 0 ? static_cast<double>(i - o.firstFrame) / span : 0.0;
  Vec2 from = o.from, to = o.to;
  if (!from.allFinite())
  {
    // A still texture crosses the image; a video object already moves: it stays centred.
    from = o.video.empty() ? Vec2(0.0, 0.5 * (image.height - 1)) : Vec2(0.5 * (image.width - 1), 0.5 * (image.height - 1));
    to = o.video.empty() ? Vec2(image.width - 1.0, from.y()) : from;
  }
  const Vec2 d = to - from;
  const Vec2 n = d.norm() > 0 ? Vec2(-d.y() / d.norm(), d.x() / d.norm()) : Vec2(0, 1);
  const double phase = 2 * M_PI * static_cast<double>(i - o.firstFrame) / o.wavePeriodFrames;
  centre = from + s * d + o.waveAmplitudePx * std::sin(phase) * n;
  scale = o.scaleFirst + s * (o.scaleLast - o.scaleFirst);
}

/** Pastes object k (prepared as p) into frame i: the texture blended into `img` (float) by its
 * alpha, its mask value k + 1 into `mask`. c, s: the centre pixel and scale it got; false when its
 * video has no frame for i (nothing pasted). */
bool pasteObject(const TCompositeObject& o, std::size_t k, TPrepared& p, std::size_t i, std::size_t last, int channels,
                 cv::Mat& img, cv::Mat& mask, Vec2& c, double& s)
{
  placement(o, i, last, img.size(), c, s);
  if (p.video && !loadVideoFrame(o, k, p, o.videoStart + (i - o.firstFrame), channels)) return false;
  // Texture pixel (x, y) (centres at integers) goes to image pixel s (x - (w-1)/2) + c.
  const cv::Matx23d A(s, 0, c.x() - s * 0.5 * (p.texture.cols - 1), 0, s, c.y() - s * 0.5 * (p.texture.rows - 1));
  cv::Mat tex, alpha;
  cv::warpAffine(p.texture, tex, A, img.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::warpAffine(p.alpha, alpha, A, img.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::Mat alphaN;
  if (channels == 1)
    alphaN = alpha;
  else
    cv::merge(std::vector<cv::Mat>{alpha, alpha, alpha}, alphaN);
  cv::Mat keep;
  cv::subtract(cv::Scalar::all(1.0), alphaN, keep);
  img = img.mul(keep) + tex.mul(alphaN);
  mask.setTo(static_cast<int>(k + 1), alpha >= 0.5f);
  return true;
}

/** A frame's mask in the statistics: the fraction of the image the objects cover. */
void addCoverage(const cv::Mat& mask, TCompositeStats& st)
{
  if (const int covered = cv::countNonZero(mask); covered > 0)
  {
    const double cov = static_cast<double>(covered) / static_cast<double>(mask.total());
    ++st.objectFrames;
    st.meanCoverage += cov;
    st.maxCoverage = std::max(st.maxCoverage, cov);
  }
}

/** The source's own calibration and ground truth into `out`, byte for byte (timestamps are
 * unchanged). */
void copySourceTruth(const std::string& sourceFolder, const fs::path& out)
{
  for (const char* name : {"calib.txt", "groundtruth.txt"})
  {
    const fs::path from = fs::path(sourceFolder) / name;
    if (fs::exists(from)) fs::copy_file(from, out / name, fs::copy_options::overwrite_existing);
  }
}
}  // namespace

TCompositeStats compositeMovingObjects(const std::string& sourceFolder, const std::string& outFolder,
                                       const std::vector<TCompositeObject>& objects)
{
  if (objects.empty()) throw std::invalid_argument("no object to paste");
  if (objects.size() > 255) throw std::invalid_argument("at most 255 objects (8-bit masks)");
  for (std::size_t k = 0; k < objects.size(); ++k) validate(objects[k], k);
  std::error_code same;
  if (fs::equivalent(fs::path(sourceFolder), fs::path(outFolder), same))
    throw std::invalid_argument("the output folder '" + outFolder + "' is the source folder");

  io::CDatasetFolderSource src(sourceFolder);
  if (!src.calibration()) throw std::runtime_error(sourceFolder + ": no calib.txt (a composite needs the camera)");
  const std::size_t nEntries = src.sizeHint();

  io::CDatasetWriter writer(outFolder, *src.calibration(),
                            "composite of " + sourceFolder + " with " + std::to_string(objects.size()) +
                                " pasted moving object(s) (imm-composite; masks/ and objects.txt are the truth)");
  const fs::path out(outFolder);
  std::error_code ec;
  fs::create_directories(out / "masks", ec);
  if (ec) throw std::runtime_error("cannot create " + (out / "masks").string() + ": " + ec.message());
  const std::string objectsTxt = (out / "objects.txt").string();
  std::ofstream objFile(objectsTxt, std::ios::trunc);
  if (!objFile) throw std::runtime_error("cannot write " + objectsTxt);
  objFile << "# pasted objects (imm-composite " << sourceFolder << "): centre pixel and scale per frame\n"
          << "# timestamp object_id u v scale\n";

  std::vector<TPrepared> prepared;
  int channels = 0;
  TCompositeStats st;
  io::TFrame f;
  std::string why;
  for (;;)
  {
    const io::ENextStatus status = src.next(f, why);
    if (status == io::ENextStatus::End) break;
    if (status == io::ENextStatus::Skipped)
    {
      ++st.skipped;
      continue;
    }
    cv::Mat frame = f.colour.empty() ? f.grey.clone() : f.colour.clone();
    if (prepared.empty())
    {
      channels = frame.channels();
      for (std::size_t k = 0; k < objects.size(); ++k) prepared.push_back(prepare(objects[k], k, channels));
    }
    if (frame.channels() != channels)  // a grey frame in a colour sequence or the reverse
      cv::cvtColor(frame, frame, channels == 1 ? cv::COLOR_BGR2GRAY : cv::COLOR_GRAY2BGR);

    const std::size_t i = st.frames;
    cv::Mat mask = cv::Mat::zeros(frame.size(), CV_8UC1);
    cv::Mat img;
    frame.convertTo(img, channels == 1 ? CV_32FC1 : CV_32FC3);
    for (std::size_t k = 0; k < objects.size(); ++k)
    {
      const TCompositeObject& o = objects[k];
      const std::size_t last = std::min(o.lastFrame, nEntries > 0 ? nEntries - 1 : o.lastFrame);
      if (i < o.firstFrame || i > last) continue;
      Vec2 c;
      double s = 1;
      if (!pasteObject(o, k, prepared[k], i, last, channels, img, mask, c, s)) continue;
      char line[160];
      std::snprintf(line, sizeof(line), "%.6f %zu %.3f %.3f %.5f\n", f.timestamp, k + 1, c.x(), c.y(), s);
      objFile << line;
    }
    img.convertTo(frame, channels == 1 ? CV_8UC1 : CV_8UC3);  // rounds and saturates
    const std::string rel = writer.addFrame(f.timestamp, frame);
    const std::string maskPath = (out / "masks" / fs::path(rel).filename()).string();
    if (!cv::imwrite(maskPath, mask)) throw std::runtime_error("cannot write '" + maskPath + "'");
    addCoverage(mask, st);
    ++st.frames;
  }
  writer.close();
  if (!objFile.flush()) throw std::runtime_error("write error in " + objectsTxt);
  if (st.objectFrames > 0) st.meanCoverage /= static_cast<double>(st.objectFrames);
  copySourceTruth(sourceFolder, out);
  return st;
}

std::string compositeAppUsage()
{
  return "Usage: imm-composite SOURCE_FOLDER OUT_FOLDER (--object IMAGE | --object-video FOLDER) [object options] ...\n"
         "Pastes moving objects cut from real images into a dataset folder (a real camera's sequence) and\n"
         "writes the result with the truth: rgb/ rgb.txt calib.txt [groundtruth.txt] masks/ (0 static\n"
         "world, k moving object k) objects.txt (centre pixel and scale per frame).\n"
         "  --object IMAGE          a still texture; the object is the ellipse inscribed in its crop\n"
         "  --object-video FOLDER   what moves in another video: a dataset folder with masks/ (a still\n"
         "                          camera's video through imm-rotate); its frame k pasted where its mask is\n"
         "Object options (apply to the last object):\n"
         "  --crop X,Y,W,H          part of IMAGE (or of the video's frames) to use (default: all)\n"
         "  --video-start N         first frame of the video object used (default 0)\n"
         "  --scale S | S0,S1       texture-to-image scale, constant or changing linearly over the span\n"
         "  --path U0,V0,U1,V1      centre pixel at the first and last frame of the span (default: left\n"
         "                          edge to right edge at mid-height)\n"
         "  --span A,B              first and last output frame (0-based) the object is in (default: all)\n"
         "  --wave AMP,PERIOD       sinusoidal offset perpendicular to the path, pixels and frames\n"
         "  --help                  this text\n"
         "Exit status: 0 success, 1 bad input or failure, 2 bad usage.\n";
}

namespace
{
/** Object option `a` with value `v` (--crop, --scale, --path, --span, --video-start, --wave) into
 * `o`; the usage error, or "" when it is fine. */
std::string applyObjectOption(const std::string& a, const std::string& v, TCompositeObject& o)
{
  std::vector<double> x;
  if (a == "--crop")
  {
    if (!parseNumbers(v, 4, x) || std::any_of(x.begin(), x.end(), [](double t) { return t < 0 || t != std::floor(t); }))
      return "--crop needs X,Y,W,H (integers >= 0), got '" + v + "'";
    o.cropX = static_cast<int>(x[0]), o.cropY = static_cast<int>(x[1]);
    o.cropW = static_cast<int>(x[2]), o.cropH = static_cast<int>(x[3]);
  }
  else if (a == "--scale")
  {
    if (parseNumbers(v, 1, x))
      o.scaleFirst = o.scaleLast = x[0];
    else if (parseNumbers(v, 2, x))
      o.scaleFirst = x[0], o.scaleLast = x[1];
    else
      return "--scale needs S or S0,S1, got '" + v + "'";
    if (!(o.scaleFirst > 0 && o.scaleLast > 0)) return "--scale must be > 0, got '" + v + "'";
  }
  else if (a == "--path")
  {
    if (!parseNumbers(v, 4, x)) return "--path needs U0,V0,U1,V1, got '" + v + "'";
    o.from = Vec2(x[0], x[1]), o.to = Vec2(x[2], x[3]);
  }
  else if (a == "--span")
  {
    if (!parseNumbers(v, 2, x) || x[0] < 0 || x[1] < x[0] || x[0] != std::floor(x[0]) || x[1] != std::floor(x[1]))
      return "--span needs A,B (integers, 0 <= A <= B), got '" + v + "'";
    o.firstFrame = static_cast<std::size_t>(x[0]), o.lastFrame = static_cast<std::size_t>(x[1]);
  }
  else if (a == "--video-start")
  {
    if (!parseNumbers(v, 1, x) || x[0] < 0 || x[0] != std::floor(x[0]))
      return "--video-start needs a frame index >= 0, got '" + v + "'";
    if (o.video.empty()) return "--video-start applies to an --object-video";
    o.videoStart = static_cast<std::size_t>(x[0]);
  }
  else if (a == "--wave")
  {
    if (!parseNumbers(v, 2, x) || !(x[1] > 0)) return "--wave needs AMP,PERIOD (period > 0), got '" + v + "'";
    o.waveAmplitudePx = x[0], o.wavePeriodFrames = x[1];
  }
  else
    return "unknown option '" + a + "'";
  return std::string();
}
}  // namespace

int runCompositeApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err)
{
  std::vector<std::string> positional;
  std::vector<TCompositeObject> objects;
  const auto usageError = [&](const std::string& msg) {
    err << "imm-composite: " << msg << "\n" << compositeAppUsage();
    return 2;
  };
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h")
    {
      out << compositeAppUsage();
      return 0;
    }
    if (a.size() < 2 || a[0] != '-')
    {
      positional.push_back(a);
      continue;
    }
    if (i + 1 >= args.size()) return usageError(a + " needs a value");
    const std::string v = args[++i];
    if (a == "--object" || a == "--object-video")
    {
      objects.emplace_back();
      (a == "--object" ? objects.back().image : objects.back().video) = v;
      continue;
    }
    if (objects.empty()) return usageError(a + " before any --object or --object-video");
    if (const std::string e = applyObjectOption(a, v, objects.back()); !e.empty()) return usageError(e);
  }
  if (positional.size() != 2) return usageError("expected SOURCE_FOLDER and OUT_FOLDER");
  if (objects.empty()) return usageError("give at least one --object IMAGE or --object-video FOLDER");
  try
  {
    const TCompositeStats s = compositeMovingObjects(positional[0], positional[1], objects);
    out << "imm-composite: wrote " << s.frames << " frames to " << positional[1] << " (" << s.skipped
        << " unreadable source frames skipped); objects in " << s.objectFrames << " frames, covering "
        << 100.0 * s.meanCoverage << " % of the image on average, " << 100.0 * s.maxCoverage << " % at most\n";
    return 0;
  }
  catch (const std::exception& e)
  {
    err << "imm-composite: error: " << e.what() << "\n";
    return 1;
  }
}
}  // namespace immslam::sim
