/* imm-monoslam — moving objects pasted into a real image sequence (imm-composite).
 *
 * The shadow filter's claims (MonoSLAMBOT, Figs. 4-5) need real video of something moving in front
 * of a moving camera, with the truth of which pixels move. compositeMovingObjects() makes such a
 * sequence from any dataset folder: the real camera motion, background, noise and blur stay; one or
 * more textured objects cut from real images (an elliptical cut-out with a feathered edge), or real
 * moving things cut from another real video by its masks (a hand moving a box, filmed by a still
 * camera), move across the image on a scripted 2D path, independently of the camera, and every frame gets the
 * object mask in the renderer's format (masks/NAME: 0 static world, k moving object k), so
 * `slam-eval classification --masks` scores the decisions and the same sequence without the objects
 * is the reference trajectory (doc/shadow.md, "Real video with a pasted moving object"). */
#pragma once

#include <immslam/math/types.h>

#include <cstddef>
#include <iosfwd>
#include <limits>
#include <string>
#include <vector>

namespace immslam::sim
{
/** One pasted object: a texture, its path in the image and the frames it is present. */
struct TCompositeObject
{
  std::string image;        ///< texture file (any image OpenCV reads); unused for a video object
  /** A video object instead of a still texture: a dataset folder with masks/ (e.g. a still camera's
   * video written by imm-rotate), of which frame `videoStart + (i - firstFrame)` is pasted in output
   * frame i, its pixels where its mask is non-zero (closed over 9 px so that parts of the object that
   * matched the background are kept, edge feathered); the object leaves when the video ends. */
  std::string video;
  std::size_t videoStart = 0;  ///< first frame of the video used
  int cropX = 0;            ///< crop of the texture: left column
  int cropY = 0;            ///< top row
  int cropW = 0;            ///< width (0 = to the right edge)
  int cropH = 0;            ///< height (0 = to the bottom edge)
  double scaleFirst = 1.0;  ///< texture-to-image scale at the first frame of the span
  double scaleLast = 1.0;   ///< ... at the last frame (linear in between: an object approaching)
  /** Centre pixel at the first and last frame of the span (linear in between; may lie off the
   * image, then the object enters or leaves). NaN = from the left edge to the right edge, mid-height
   * (a video object: fixed at the image centre). */
  Vec2 from = Vec2::Constant(std::numeric_limits<double>::quiet_NaN());
  Vec2 to = Vec2::Constant(std::numeric_limits<double>::quiet_NaN());  ///< see from
  std::size_t firstFrame = 0;  ///< span: first output frame (0-based) the object is in
  std::size_t lastFrame = std::numeric_limits<std::size_t>::max();  ///< last one (clamped to the sequence)
  double waveAmplitudePx = 0;    ///< sinusoidal offset perpendicular to the path (a waving hand), px
  double wavePeriodFrames = 30;  ///< its period in frames
};

/** What compositeMovingObjects() wrote. */
struct TCompositeStats
{
  std::size_t frames = 0;         ///< frames written
  std::size_t skipped = 0;        ///< input entries skipped (unreadable images), not written
  std::size_t objectFrames = 0;   ///< frames with at least one object pixel
  double meanCoverage = 0;        ///< mean fraction of the image covered by objects, over objectFrames
  double maxCoverage = 0;         ///< largest such fraction
};

/** Writes `outFolder` (created; CDatasetWriter layout): rgb/NNNNNN.png with the objects pasted,
 * rgb.txt with the source timestamps, calib.txt, groundtruth.txt copied when the source has one,
 * masks/NNNNNN.png (8-bit; object k of `objects` = k + 1, later objects drawn over earlier ones) and
 * objects.txt (`timestamp object_id u v scale`, the centre pixel of each object in each frame it
 * is in). Grey sources get grey objects; colour sources colour ones. Sub-pixel positions (bilinear).
 * \throws std::invalid_argument for a bad object (crop outside its texture, scale <= 0, period
 *         <= 0, span first > last), std::runtime_error naming the file for an unreadable source
 *         folder, texture or an output that cannot be written; a source without calib.txt. */
TCompositeStats compositeMovingObjects(const std::string& sourceFolder, const std::string& outFolder,
                                       const std::vector<TCompositeObject>& objects);

/** `imm-composite SOURCE_FOLDER OUT_FOLDER (--object IMAGE | --object-video FOLDER) [object options]... [--help]`.
 * \return 0 on success, 1 on bad input or failure (the message names the file), 2 on bad usage. */
int runCompositeApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

/** The usage text. */
std::string compositeAppUsage();
}  // namespace immslam::sim
