/* imm-monoslam — colours shared by the 3-D scenes, and the overlays. */
#pragma once

#include <cstdint>

namespace immslam::viz
{
/** An 8-bit RGB colour (library-neutral: converted to MRPT's TColor or OpenCV's BGR Scalar where
 * it is used). */
struct TColour
{
  std::uint8_t r = 0;  ///< red
  std::uint8_t g = 0;  ///< green
  std::uint8_t b = 0;  ///< blue

  constexpr TColour() = default;
  constexpr TColour(std::uint8_t red, std::uint8_t green, std::uint8_t blue)
      : r(red), g(green), b(blue)
  {
  }
  constexpr bool operator==(const TColour& o) const { return r == o.r && g == o.g && b == o.b; }
  constexpr bool operator!=(const TColour& o) const { return !(*this == o); }
};

/** The project's palette. Feature classes follow MonoSLAMBOT Fig. 4 (static blue, dynamic green,
 * features waiting for a decision red); search outcomes use colours distinct from those three. */
namespace palette
{
constexpr TColour kStatic{30, 120, 255};       ///< static feature (blue)
constexpr TColour kDynamic{0, 200, 0};         ///< dynamic feature / track (green)
constexpr TColour kPending{235, 20, 20};       ///< feature waiting for classification (red)
constexpr TColour kInlier{255, 230, 0};        ///< search ellipse whose match was used (yellow)
constexpr TColour kRescued{0, 230, 230};       ///< match rescued by a second pass (cyan)
constexpr TColour kRejected{255, 0, 255};      ///< match rejected as an outlier (magenta)
constexpr TColour kNotFound{175, 175, 175};    ///< predicted but not found (grey)
constexpr TColour kTrajectory{20, 60, 200};    ///< estimated camera trajectory (dark blue)
constexpr TColour kGroundTruth{0, 160, 60};    ///< ground-truth trajectory (green)
constexpr TColour kSmoothed{0, 180, 220};      ///< the keyframe smoother's trajectory (light blue)
constexpr TColour kCamera{20, 20, 20};         ///< current camera frustum (near black)
constexpr TColour kMapXyz{220, 30, 30};        ///< XYZ map feature (red)
constexpr TColour kMapIdKnown{240, 130, 0};    ///< inverse-depth feature with a depth (orange)
constexpr TColour kMapIdUnknown{140, 60, 200}; ///< inverse-depth feature without a depth (purple)
constexpr TColour kGrid{200, 200, 200};        ///< ground grid (light grey)
constexpr TColour kWhite{255, 255, 255};       ///< white
constexpr TColour kBlack{0, 0, 0};             ///< black
}  // namespace palette
}  // namespace immslam::viz
