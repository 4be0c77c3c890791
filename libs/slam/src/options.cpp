/* imm-monoslam — options of the IMM bank ([imm]). */
#include <immslam/core/config.h>
#include <immslam/slam/TIMMBankOptions.h>

#include <cmath>
#include <sstream>

namespace immslam::slam
{
void TIMMBankOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
  IMMSLAM_LOAD_STRING(models);
  IMMSLAM_LOAD_VECTOR(transition_matrix);
  IMMSLAM_LOAD_VECTOR(prior);
  IMMSLAM_LOAD_DOUBLE(dormant_below);
  IMMSLAM_LOAD_DOUBLE(shake_px);
  core::requireInRange(shake_px, 0, 100, s, "shake_px");
  const int r = static_cast<int>(parseModels().size());
  transitionMatrix(r);  // validates
  priorProbabilities(r);
  core::requireInRange(probability_floor, 0, 0.99 / r, s, "probability_floor");
  core::requireInRange(dormant_below, 0, 0.5, s, "dormant_below");
}

namespace
{
std::string joinNumbers(const std::vector<double>& v)
{
  std::ostringstream o;
  o << "[";
  for (std::size_t i = 0; i < v.size(); ++i) o << (i ? " " : "") << v[i];
  o << "]";
  return o.str();
}
}  // namespace

void TIMMBankOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
  c.write(s, "models", models, mrpt::config::MRPT_SAVE_NAME_PADDING(), mrpt::config::MRPT_SAVE_VALUE_PADDING(),
          "stationary | rotation:SIGMA_PX | general:SIGMA_PX[:SIGMA_ANG_PX] (noise in px; the shake of every model is shake_px)");
  c.write(s, "transition_matrix", joinNumbers(transition_matrix), mrpt::config::MRPT_SAVE_NAME_PADDING(),
          mrpt::config::MRPT_SAVE_VALUE_PADDING(), "r x r Markov matrix, row-major, rows sum to 1 ([] = 0.995 on the diagonal, no switch into a general mode)");
  c.write(s, "prior", joinNumbers(prior), mrpt::config::MRPT_SAVE_NAME_PADDING(), mrpt::config::MRPT_SAVE_VALUE_PADDING(),
          "initial model probabilities ([] = uniform)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(dormant_below, "modes below this probability given the frame are not updated (0 = exact IMM)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(shake_px, "zero-mean angular shake of the camera in every model, px per frame (random walk; 0 = none)");
}

std::vector<motion::TMotionModel> TIMMBankOptions::parseModels() const
{
  std::vector<motion::TMotionModel> out;
  std::istringstream is(models);
  std::string spec;
  while (is >> spec)
  {
    std::vector<std::string> parts;
    std::string part;
    std::istringstream ps(spec);
    while (std::getline(ps, part, ':')) parts.push_back(part);
    motion::TMotionModel m;
    try
    {
      m.family = motion::familyFromName(parts.at(0));
      std::vector<double> sig;
      for (std::size_t i = 1; i < parts.size(); ++i)
      {
        std::size_t pos = 0;
        double v = 0;
        try
        {
          v = std::stod(parts[i], &pos);
        }
        catch (const std::exception&)
        {
          pos = 0;
        }
        if (pos == 0 || pos != parts[i].size() || !(v > 0) || !std::isfinite(v))
          throw std::invalid_argument("noise '" + parts[i] + "' is not a number > 0");
        sig.push_back(v);
      }
      if (m.family == motion::EMotionFamily::Stationary && !sig.empty())
        throw std::invalid_argument("stationary takes no value (the angular shake of every model, the still one too, is [imm] shake_px)");
      if (m.family == motion::EMotionFamily::Stationary) m.sigmaAngularPx = 0.0;  // its only noise is the shake
      if (m.family == motion::EMotionFamily::Rotation && sig.size() != 1)
        throw std::invalid_argument("rotation takes one noise value");
      if (m.family == motion::EMotionFamily::General && (sig.empty() || sig.size() > 2))
        throw std::invalid_argument("general takes one or two noise values");
      if (m.family == motion::EMotionFamily::Rotation) m.sigmaAngularPx = sig[0];
      if (m.family == motion::EMotionFamily::General)
      {
        m.sigmaLinearPx = sig[0];
        m.sigmaAngularPx = sig.size() > 1 ? sig[1] : sig[0];
      }
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error("[imm] models: bad model '" + spec + "': " + e.what());
    }
    m.shakePx = shake_px;
    m.name = m.displayName();
    // Identical models are allowed (e.g. to test that N identical models make one filter): number them.
    int copies = 0;
    for (const auto& o : out)
      if (o.name.rfind(m.name, 0) == 0) ++copies;
    if (copies) m.name += "_" + std::to_string(copies + 1);
    out.push_back(m);
  }
  if (out.empty()) throw std::runtime_error("[imm] models: no model given");
  return out;
}

MatX TIMMBankOptions::transitionMatrix(int r) const
{
  MatX pi(r, r);
  if (transition_matrix.empty())
  {
    core::requireInRange(transition_stay, 0, 1, "imm", "transition_stay");
    pi.setConstant(r > 1 ? (1.0 - transition_stay) / (r - 1) : 0.0);
    pi.diagonal().setConstant(r > 1 ? transition_stay : 1.0);
    // No Markov switch from a still or rotating mode (v = 0) into a general one: a general mode entered
    // by mixing would start from a zero velocity; the general modes keep their own velocity and win by
    // evidence (doc/imm.md).
    if (r > 1)
    {
      const auto models = parseModels();
      if (static_cast<int>(models.size()) != r) throw std::logic_error("[imm] transition matrix: r differs from the models");
      using F = motion::EMotionFamily;
      for (int j = 0; j < r; ++j)
      {
        if (models[j].family == F::General) continue;
        double rest = 1.0;
        for (int i = 0; i < r; ++i)
        {
          if (i != j && models[i].family == F::General) pi(j, i) = 0.0;
          if (i != j) rest -= pi(j, i);
        }
        pi(j, j) = rest;
      }
    }
    return pi;
  }
  if (static_cast<int>(transition_matrix.size()) != r * r)
  {
    std::ostringstream s;
    s << "[imm] transition_matrix: has " << transition_matrix.size() << " values, expected " << r * r << " (" << r
      << " models)";
    throw std::runtime_error(s.str());
  }
  for (int j = 0; j < r; ++j)
  {
    double sum = 0;
    for (int i = 0; i < r; ++i)
    {
      pi(j, i) = transition_matrix[j * r + i];
      if (!(pi(j, i) >= 0)) throw std::runtime_error("[imm] transition_matrix: negative entry in row " + std::to_string(j + 1));
      sum += pi(j, i);
    }
    if (std::abs(sum - 1.0) > 1e-6)
      throw std::runtime_error("[imm] transition_matrix: row " + std::to_string(j + 1) + " sums to " + std::to_string(sum) +
                               ", not 1");
    pi.row(j) /= sum;
  }
  return pi;
}

VecX TIMMBankOptions::priorProbabilities(int r) const
{
  if (prior.empty()) return VecX::Constant(r, 1.0 / r);
  if (static_cast<int>(prior.size()) != r)
    throw std::runtime_error("[imm] prior: has " + std::to_string(prior.size()) + " values, expected " + std::to_string(r));
  VecX p = Eigen::Map<const VecX>(prior.data(), r);
  if (!(p.array() >= 0).all() || std::abs(p.sum() - 1.0) > 1e-6)
    throw std::runtime_error("[imm] prior: values must be >= 0 and sum to 1");
  return p / p.sum();
}
}  // namespace immslam::slam
