/* Tests: NIS of the matches used in the update (searches.csv): hand-computed values, status
 * filtering, the chi-square(2) bound, Gaussian innovations giving 1 per dof and 95 % inside, and
 * the reader's errors. */
#include <gtest/gtest.h>
#include <immslam/eval/search_nis.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

using namespace immslam;
using namespace immslam::eval;

namespace
{
std::string tempPath(const std::string& name)
{
  return (std::filesystem::path(::testing::TempDir()) / ("immslam_nis_" + name)).string();
}
void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TSearchRow row(const Vec2& innov, const Mat2& S, ESearchStatus st)
{
  TSearchRow r;
  r.h = Vec2(100, 50);
  r.S = S;
  r.found = st != ESearchStatus::NotFound;
  r.z = r.h + innov;
  r.status = st;
  return r;
}
const char* kHeader = "timestamp,feature_id,h_u,h_v,s_uu,s_uv,s_vv,found,z_u,z_v,score,status\n";
}  // namespace

TEST(SearchNis, HandComputedValues)
{
  EXPECT_DOUBLE_EQ(innovationNis(Vec2(3, 2), Vec2(1, 1), Mat2(Vec2(4, 1).asDiagonal())), 2.0);
  Mat2 S;
  S << 2, 1, 1, 2;
  EXPECT_NEAR(innovationNis(Vec2(1, 1), Vec2::Zero(), S), 2.0 / 3, 1e-15);  // S^-1 = [2 -1; -1 2] / 3
  EXPECT_TRUE(std::isinf(innovationNis(Vec2(1, 1), Vec2::Zero(), Mat2(Vec2(1, -1).asDiagonal()))));

  const Mat2 I = Mat2::Identity();
  std::vector<TSearchRow> rows{
      row(Vec2(2, 1), Mat2(Vec2(4, 1).asDiagonal()), ESearchStatus::Inlier),  // 2
      row(Vec2(1, 1), S, ESearchStatus::Rescued),                              // 2/3
      row(Vec2(2, 2), I, ESearchStatus::Inlier),                               // 8 > 5.991
      row(Vec2(1, 0), Mat2::Zero(), ESearchStatus::Inlier),                    // S singular: invalid
      row(Vec2(50, 50), I, ESearchStatus::Rejected),                           // not used
      row(Vec2(NAN, NAN), I, ESearchStatus::NotFound)};                        // not used
  const TNisResult r = computeSearchNis(rows);
  EXPECT_EQ(r.nSearches, 6u);
  EXPECT_EQ(r.nUsed, 4u);
  EXPECT_EQ(r.nInvalid, 1u);
  EXPECT_EQ(r.nInside, 2u);
  EXPECT_NEAR(r.bound, -2 * std::log(0.05), 1e-12);
  EXPECT_NEAR(r.bound, 5.991464547, 1e-8);
  EXPECT_NEAR(r.meanNis, (2 + 2.0 / 3 + 8) / 3, 1e-12);
  EXPECT_NEAR(r.meanNisPerDof, (2 + 2.0 / 3 + 8) / 6, 1e-12);
  EXPECT_NEAR(r.medianNis, 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(r.fractionInside, 0.5);
  ASSERT_EQ(r.values.size(), 4u);
  EXPECT_TRUE(std::isinf(r.values[3]));
  EXPECT_NE(r.summary().find("50.00 % (2/4"), std::string::npos) << r.summary();
  // 99 %: bound 9.21, the 8 is inside.
  EXPECT_EQ(computeSearchNis(rows, 0.99).nInside, 3u);
  EXPECT_THROW(computeSearchNis(rows, 1.0), std::invalid_argument);
  const TNisResult none = computeSearchNis({});
  EXPECT_EQ(none.nUsed, 0u);
  EXPECT_TRUE(std::isnan(none.meanNis));
  EXPECT_TRUE(std::isnan(none.fractionInside));
}

TEST(SearchNis, GaussianInnovationsAreConsistent)
{
  // Innovations drawn from N(0, S) with random S: NIS ~ chi2(2), mean 2, median 2 ln 2,
  // P(NIS <= 5.991) = 0.95. With 40000 samples the standard errors are 0.01, 0.007 and 0.0011.
  std::mt19937 rng(21);
  std::normal_distribution<double> n;
  std::uniform_real_distribution<double> u(0.5, 30);
  std::vector<TSearchRow> rows;
  for (int i = 0; i < 40000; ++i)
  {
    Mat2 A;
    A << u(rng), n(rng), n(rng), u(rng);
    const Mat2 S = A * A.transpose() + 0.1 * Mat2::Identity();
    const Mat2 L = S.llt().matrixL();
    rows.push_back(row(L * Vec2(n(rng), n(rng)), S, i % 3 ? ESearchStatus::Inlier : ESearchStatus::Rescued));
  }
  const TNisResult r = computeSearchNis(rows);
  EXPECT_EQ(r.nUsed, 40000u);
  EXPECT_NEAR(r.meanNisPerDof, 1.0, 0.04);
  EXPECT_NEAR(r.medianNis, 2 * std::log(2.0), 0.03);
  EXPECT_NEAR(r.fractionInside, 0.95, 0.005);
  // Innovations twice too large (S underestimated 4 times): mean per dof 4, far fewer inside.
  for (auto& s : rows) s.z = s.h + 2 * (s.z - s.h);
  const TNisResult big = computeSearchNis(rows);
  EXPECT_NEAR(big.meanNisPerDof, 4.0, 0.15);
  EXPECT_NEAR(big.fractionInside, 1 - std::exp(-5.991464547 / 8), 0.01);  // P(chi2_2 <= 5.99 / 4)
}

TEST(SearchNis, ReaderRoundTripAndErrors)
{
  const std::string p = tempPath("searches.csv");
  writeText(p, std::string(kHeader) +
                   "1.000000,3,100,50,4,0,1,1,102,51,0.93,inlier\n"
                   "1.000000,4,10,20,2,1,2,0,nan,nan,0.2,not_found\n"
                   "1.033333,3,101,50,2,1,2,1,102,51,0.9,rescued\n"
                   "1.033333,5,1,1,1,0,1,1,9,9,0.8,rejected\n");
  const auto rows = readSearchesCsv(p);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].featureId, 3);
  EXPECT_EQ(rows[0].h, Vec2(100, 50));
  EXPECT_EQ(rows[0].S(1, 1), 1.0);
  EXPECT_EQ(rows[2].S(0, 1), 1.0);
  EXPECT_EQ(rows[2].S(1, 0), 1.0);
  EXPECT_TRUE(rows[0].found);
  EXPECT_FALSE(rows[1].found);
  EXPECT_TRUE(std::isnan(rows[1].z.x()));
  EXPECT_EQ(rows[2].status, ESearchStatus::Rescued);
  EXPECT_EQ(rows[3].status, ESearchStatus::Rejected);
  EXPECT_DOUBLE_EQ(rows[0].score, 0.93);
  const TNisResult r = computeSearchNis(rows);
  EXPECT_EQ(r.nUsed, 2u);
  EXPECT_NEAR(r.values[0], 2.0, 1e-12);
  EXPECT_NEAR(r.values[1], 2.0 / 3, 1e-12);
  EXPECT_STREQ(searchStatusName(ESearchStatus::NotFound), "not_found");

  const auto expectError = [&](const std::string& text, const std::string& where) {
    writeText(p, text);
    try
    {
      readSearchesCsv(p);
      ADD_FAILURE() << "no error for " << text;
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_NE(std::string(e.what()).find(p + where), std::string::npos) << e.what();
    }
  };
  expectError(std::string(kHeader) + "1,3,100,50,4,0,1,1,102,51,0.93,accepted\n", ":2");
  expectError(std::string(kHeader) + "1,3,100,50,4,0,1,0,102,51,0.93,inlier\n", ":2");  // used but not found
  expectError(std::string(kHeader) + "1,3,100,50,4,0,1,2,102,51,0.93,inlier\n", ":2");
  expectError(std::string(kHeader) + "\n1,3,100,50,4,0,1,1,102,51,0.93\n", ":3");
  expectError("timestamp,feature_id,h_u\n", ":1");
  EXPECT_THROW(readSearchesCsv(tempPath("missing.csv")), std::runtime_error);
}
