/* Fuzz target: calib.txt parsing (camera::parseCalibLine, camera::loadCalibFile). */
#include "fuzz_common.h"

#include <immslam/camera/CCameraModel.h>

#include <cmath>
#include <sstream>

namespace immslam::fuzz
{
namespace
{
/** A model that parsed: it prints a line that parses back to the same model, and it can project
 * and unproject its principal point. */
void checkModel(const camera::CCameraModel& cam, const std::string& context)
{
  const std::string line = cam.toCalibLine();
  camera::CCameraModel::Ptr again;
  try
  {
    again = camera::parseCalibLine(line, "round trip");
  }
  catch (const std::exception& e)
  {
    fail(context + ": toCalibLine() '" + line + "' does not parse back: " + e.what());
  }
  if (again->modelName() != cam.modelName() || again->width() != cam.width() || again->height() != cam.height() ||
      again->parameters() != cam.parameters())
    fail(context + ": '" + line + "' parses back to '" + again->toCalibLine() + "'");
  const Vec2 c(cam.cx(), cam.cy());
  Mat32 J_b_uv;
  const math::Bearing b = cam.unproject(c, &J_b_uv);
  if (!b.unitVector().allFinite()) fail(context + ": unproject(principal point) is not finite for '" + line + "'");
  Vec2 uv;
  Mat23 J;
  cam.project(Vec3(0.01, -0.02, 1.0), uv, &J);
  (void)cam.isInImage(uv, 3.0);
  try
  {
    (void)cam.scaled(0.5);
  }
  catch (const std::exception& e)
  {
    // Only a parameter that overflows when rescaled (e.g. davison kd1 = 1e308: kd1 / s^2) may refuse,
    // and the error must say which model and which scale.
    requireMentions(e, cam.modelName() + " camera: scaling by 0.5", context + " scaled(0.5)");
  }
}
}  // namespace

int fuzzCalib(const std::uint8_t* data, std::size_t size)
{
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::istringstream in(text);
  std::string line;
  for (int n = 1; std::getline(in, line) && n <= 64; ++n)
  {
    const std::string ctx = "fuzz-calib:" + std::to_string(n);
    camera::CCameraModel::Ptr cam;
    try
    {
      cam = camera::parseCalibLine(line, ctx);
    }
    catch (const std::exception& e)
    {
      requireMentions(e, ctx, "parseCalibLine");
      continue;
    }
    checkModel(*cam, ctx);
  }
  const std::string path = fuzzTempDir() + "/calib.txt";
  writeFile(path, text);
  camera::CCameraModel::Ptr cam;
  try
  {
    cam = camera::loadCalibFile(path);
  }
  catch (const std::exception& e)
  {
    requireMentions(e, path, "loadCalibFile");
    return 0;
  }
  checkModel(*cam, path);
  return 0;
}
}  // namespace immslam::fuzz
