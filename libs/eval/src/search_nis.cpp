/* imm-monoslam — NIS of the matches used in the SLAM update (searches.csv). */
#include <immslam/eval/search_nis.h>

#include <immslam/eval/consistency.h>
#include <immslam/eval/statistics.h>
#include <immslam/math/chi2.h>

#include "table_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <ostream>
#include <stdexcept>

namespace immslam::eval
{
const char* searchStatusName(ESearchStatus s)
{
  switch (s)
  {
    case ESearchStatus::NotFound: return "not_found";
    case ESearchStatus::Inlier: return "inlier";
    case ESearchStatus::Rescued: return "rescued";
    case ESearchStatus::Rejected: return "rejected";
  }
  return "?";
}

std::vector<TSearchRow> readSearchesCsv(const std::string& path)
{
  static const std::vector<std::string> kHead{"timestamp", "feature_id", "h_u", "h_v", "s_uu", "s_uv",
                                              "s_vv",      "found",      "z_u", "z_v", "score", "status"};
  detail::CTableReader r(path, detail::CTableReader::ESeparator::Comma, "searches file");
  if (!r.next())
    throw std::runtime_error(path + ": empty file (expected a header 'timestamp,feature_id,h_u,h_v,s_uu,s_uv,s_vv,"
                                    "found,z_u,z_v,score,status')");
  if (r.fields().size() < kHead.size() || !std::equal(kHead.begin(), kHead.end(), r.fields().begin()))
    r.fail("expected a header starting 'timestamp,feature_id,h_u,h_v,s_uu,s_uv,s_vv,found,z_u,z_v,score,status'");
  const std::size_t nCols = r.fields().size();
  std::vector<TSearchRow> out;
  while (r.next())
  {
    if (r.fields().size() != nCols)
      r.fail("expected " + std::to_string(nCols) + " fields like the header, got " + std::to_string(r.fields().size()));
    TSearchRow s;
    s.timestamp = r.number(0, "timestamp");
    s.featureId = r.integer(1, "feature_id");
    s.h = Vec2(r.anyNumber(2, "h_u"), r.anyNumber(3, "h_v"));
    const double suu = r.anyNumber(4, "s_uu"), suv = r.anyNumber(5, "s_uv"), svv = r.anyNumber(6, "s_vv");
    s.S << suu, suv, suv, svv;
    const std::int64_t found = r.integer(7, "found");
    if (found != 0 && found != 1) r.fail("found: expected 0 or 1, got '" + r.fields()[7] + "'");
    s.found = found == 1;
    s.z = Vec2(r.anyNumber(8, "z_u"), r.anyNumber(9, "z_v"));
    s.score = r.anyNumber(10, "score");
    const std::string& st = r.fields()[11];
    bool known = false;
    for (const ESearchStatus e :
         {ESearchStatus::NotFound, ESearchStatus::Inlier, ESearchStatus::Rescued, ESearchStatus::Rejected})
      if (st == searchStatusName(e)) s.status = e, known = true;
    if (!known) r.fail("unknown status '" + st + "' (expected not_found, inlier, rescued or rejected)");
    if (s.usedInUpdate() && !s.found) r.fail("status " + st + " but found = 0");
    out.push_back(s);
  }
  return out;
}

double innovationNis(const Vec2& z, const Vec2& h, const Mat2& S)
{
  return nees(VecX(z - h), MatX(S));
}

TNisResult computeSearchNis(const std::vector<TSearchRow>& rows, double confidence)
{
  if (!(confidence > 0 && confidence < 1))
    throw std::invalid_argument("computeSearchNis: need 0 < confidence < 1");
  TNisResult r;
  r.confidence = confidence;
  r.bound = math::chi2Quantile(confidence, 2);
  r.nSearches = rows.size();
  std::vector<double> valid;
  for (const auto& s : rows)
  {
    if (!s.usedInUpdate()) continue;
    const double v = innovationNis(s.z, s.h, s.S);
    r.values.push_back(v);
    ++r.nUsed;
    if (!std::isfinite(v))
    {
      ++r.nInvalid;
      continue;
    }
    valid.push_back(v);
    if (v <= r.bound) ++r.nInside;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  r.meanNis = valid.empty() ? nan : mean(valid);
  r.meanNisPerDof = r.meanNis / 2;
  r.medianNis = valid.empty() ? nan : median(valid);
  r.fractionInside = r.nUsed ? static_cast<double>(r.nInside) / static_cast<double>(r.nUsed) : nan;
  return r;
}

std::string TNisResult::summary() const
{
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "NIS of the matches used in the update (2 dof): %zu of %zu searches (%zu with a non-positive-definite "
                "S)\n"
                "  mean NIS            : %.4g (%.4g per dof; consistent: 2, i.e. 1 per dof)\n"
                "  median NIS          : %.4g (consistent: 1.386)\n"
                "  inside %.0f %% bound   : %.2f %% (%zu/%zu below chi2_2(%.2f) = %.4g; consistent: %.0f %%)\n",
                nUsed, nSearches, nInvalid, meanNis, meanNisPerDof, medianNis, 100 * confidence, 100 * fractionInside,
                nInside, nUsed, confidence, bound, 100 * confidence);
  return buf;
}

std::ostream& operator<<(std::ostream& os, const TNisResult& r) { return os << r.summary(); }
}  // namespace immslam::eval
