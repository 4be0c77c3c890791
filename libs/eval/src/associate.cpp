/* imm-monoslam — nearest-timestamp one-to-one association. */
#include <immslam/eval/associate.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <tuple>

namespace immslam::eval
{
namespace
{
/** Indices of the poses with finite timestamps, sorted by timestamp (then index). */
std::vector<size_t> sortedFinite(const core::TTrajectory& t)
{
  std::vector<size_t> idx;
  idx.reserve(t.size());
  for (size_t i = 0; i < t.size(); ++i)
    if (std::isfinite(t[i].timestamp)) idx.push_back(i);
  std::stable_sort(idx.begin(), idx.end(),
                   [&](size_t x, size_t y) { return t[x].timestamp < t[y].timestamp; });
  return idx;
}

struct TCandidate
{
  double dt;
  size_t ia, ib;
  bool operator<(const TCandidate& o) const { return std::tie(dt, ia, ib) < std::tie(o.dt, o.ia, o.ib); }
};

/** For every pose of `from`, its predecessor and successor in `to` (sorted indices) within maxDt. */
template <typename Emit>
void neighbours(const core::TTrajectory& from, const std::vector<size_t>& fromIdx, const core::TTrajectory& to,
                const std::vector<size_t>& toIdx, double maxDt, Emit&& emit)
{
  std::vector<double> toT(toIdx.size());
  for (size_t k = 0; k < toIdx.size(); ++k) toT[k] = to[toIdx[k]].timestamp;
  for (size_t i : fromIdx)
  {
    const double t = from[i].timestamp;
    const size_t pos = static_cast<size_t>(std::lower_bound(toT.begin(), toT.end(), t) - toT.begin());
    for (size_t k : {pos - 1, pos})  // pos - 1 wraps to SIZE_MAX when pos == 0: skipped below
    {
      if (k >= toT.size()) continue;
      const double dt = std::abs(toT[k] - t);
      if (dt <= maxDt) emit(dt, i, toIdx[k]);
    }
  }
}
}  // namespace

std::vector<std::pair<size_t, size_t>> associateByTimestamp(const core::TTrajectory& a, const core::TTrajectory& b,
                                                            double maxDt)
{
  if (!(maxDt >= 0)) throw std::invalid_argument("associateByTimestamp: maxDt must be >= 0");
  const std::vector<size_t> ia = sortedFinite(a), ib = sortedFinite(b);
  std::vector<TCandidate> cand;
  cand.reserve(2 * (ia.size() + ib.size()));
  neighbours(a, ia, b, ib, maxDt, [&](double dt, size_t i, size_t j) { cand.push_back({dt, i, j}); });
  neighbours(b, ib, a, ia, maxDt, [&](double dt, size_t j, size_t i) { cand.push_back({dt, i, j}); });
  std::sort(cand.begin(), cand.end());

  // Greedy: closest pairs first, each pose used once.
  std::vector<char> usedA(a.size(), 0), usedB(b.size(), 0);
  std::vector<std::pair<size_t, size_t>> out;
  for (const auto& c : cand)
  {
    if (usedA[c.ia] || usedB[c.ib]) continue;
    usedA[c.ia] = usedB[c.ib] = 1;
    out.emplace_back(c.ia, c.ib);
  }
  std::sort(out.begin(), out.end(), [&](const auto& x, const auto& y) {
    return std::make_pair(a[x.first].timestamp, x.first) < std::make_pair(a[y.first].timestamp, y.first);
  });
  return out;
}
}  // namespace immslam::eval
