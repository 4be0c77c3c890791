/* Tests: the slam-eval program (built binary, SLAM_EVAL_EXE) run on small files written here: every
 * subcommand with a known answer, the old imm-eval form, exit codes 0 / 1 (bad input: the message
 * names file:line) / 2 (usage). The dataset folder imitates imm-render's output (rgb.txt, masks/). */
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace
{
/** A fresh folder for the calling test (tests may run concurrently as separate processes). */
fs::path testDir()
{
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path d = fs::path(::testing::TempDir()) / (std::string("slam_eval_cli_") + info->name());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void writeText(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

std::string readText(const fs::path& p)
{
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string quote(const std::string& s)
{
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

struct TRun
{
  int rc = -1;
  std::string out, err;
};

/** Runs the program with these arguments; captures exit status, stdout and stderr. */
TRun run(const fs::path& dir, const std::vector<std::string>& args)
{
  std::string cmd = quote(SLAM_EVAL_EXE);
  for (const auto& a : args) cmd += " " + quote(a);
  cmd += " > " + quote((dir / "stdout.txt").string()) + " 2> " + quote((dir / "stderr.txt").string());
  const int st = std::system(cmd.c_str());
  TRun r;
  r.rc = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  r.out = readText(dir / "stdout.txt");
  r.err = readText(dir / "stderr.txt");
  return r;
}

/** The number after `label` in a report (NaN if absent). */
double number(const std::string& text, const std::string& label)
{
  const auto i = text.find(label);
  return i == std::string::npos ? NAN : std::strtod(text.c_str() + i + label.size(), nullptr);
}

#define EXPECT_CONTAINS(text, part) EXPECT_NE((text).find(part), std::string::npos) << "missing '" << (part) << "' in:\n" << (text)
}  // namespace

TEST(SlamEvalCli, Help)
{
  const auto d = testDir();
  const TRun r = run(d, {"--help"});
  EXPECT_EQ(r.rc, 0);
  EXPECT_CONTAINS(r.out, "Usage:");
  for (const char* c : {"ate", "segmentation", "classification", "nis"}) EXPECT_CONTAINS(r.out, c);
  EXPECT_EQ(run(d, {}).rc, 2);
  EXPECT_EQ(run(d, {"nis", "--help"}).rc, 0);
}

TEST(SlamEvalCli, AteSim3Se3OldFormAndKnownError)
{
  const auto d = testDir();
  // Ground truth: 20 non-collinear positions at t = k s; est = 2 gt + (10, 0, 0), 1 ms late:
  // Sim3 ATE 0 with scale 0.5. shifted = gt + (0.01, 0, 0): ATE without alignment 0.01.
  std::string gt = "# ground truth\n", est, shifted, bad = "# comment\n0 0 0 0 0 0 0 1\n1 0 0 oops 0 0 0 1\n";
  for (int k = 0; k < 20; ++k)
  {
    const int x = k, y = (k * k) % 5, z = (3 * k) % 4;
    char buf[160];
    std::snprintf(buf, sizeof buf, "%d.000000 %d %d %d 0 0 0 1\n", k, x, y, z);
    gt += buf;
    std::snprintf(buf, sizeof buf, "%d.001 %d %d %d 0 0 0 1\n", k, 2 * x + 10, 2 * y, 2 * z);
    est += buf;
    std::snprintf(buf, sizeof buf, "%d.000000 %.2f %d %d 0 0 0 1\n", k, x + 0.01, y, z);
    shifted += buf;
  }
  writeText(d / "gt.txt", gt);
  writeText(d / "est.txt", est);
  writeText(d / "shifted.txt", shifted);
  writeText(d / "bad.txt", bad);
  const std::string G = (d / "gt.txt").string(), E = (d / "est.txt").string();

  TRun r = run(d, {"ate", E, G});
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_CONTAINS(r.out, "pairs                 : 20\n");
  EXPECT_CONTAINS(r.out, "scale                 : 0.5\n");
  EXPECT_CONTAINS(r.out, "ATE rmse              : ");
  EXPECT_CONTAINS(r.out, "rotation RMSE");
  const TRun old = run(d, {E, G});  // the imm-eval form
  EXPECT_EQ(old.rc, 0);
  EXPECT_EQ(old.out, r.out);

  r = run(d, {"ate", E, G, "--json", "--max-dt", "0.005", "--rpe", "1"});
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_CONTAINS(r.out, "\"n_pairs\": 20,");
  EXPECT_CONTAINS(r.out, "\"scale\": 0.5");
  EXPECT_CONTAINS(r.out, "\"rpe_delta\": 1");
  EXPECT_CONTAINS(run(d, {"ate", E, G, "--se3"}).out, "scale                 : 1\n");

  r = run(d, {"ate", (d / "shifted.txt").string(), G, "--no-align"});
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_CONTAINS(r.out, "ATE rmse              : 0.01\n");
  EXPECT_CONTAINS(r.out, "ATE max               : 0.01\n");
  r = run(d, {"ate", G, G});
  EXPECT_LT(number(r.out, "ATE rmse              : "), 1e-12) << r.out;

  r = run(d, {"ate", E, G, "--max-dt=0.0001"});
  EXPECT_EQ(r.rc, 1);
  EXPECT_CONTAINS(r.err, "est.txt");
  r = run(d, {"ate", E, (d / "bad.txt").string()});
  EXPECT_EQ(r.rc, 1);
  EXPECT_CONTAINS(r.err, "bad.txt:3");
  r = run(d, {"ate", (d / "missing.txt").string(), G});
  EXPECT_EQ(r.rc, 1);
  EXPECT_CONTAINS(r.err, "missing.txt");
  EXPECT_EQ(run(d, {"ate", E, G, "--se3", "--no-align"}).rc, 2);
  EXPECT_EQ(run(d, {"ate", E, G, "--frobnicate"}).rc, 2);
  EXPECT_EQ(run(d, {"ate", E}).rc, 2);
}

TEST(SlamEvalCli, Segmentation)
{
  const auto d = testDir();
  // 10 frames at 10 Hz: stationary (0-4), rotation (5-9). Frame 0 is decided rotation (summed
  // 0.3 + 0.3 > 0.4), frame 7 general; --exclude 0.15 drops frames 4, 5 and 6: 5/7 right.
  std::string probs = "timestamp,stationary,rotation_0.1px,rotation_1px,general_1px\n", labels = "# timestamp label\n";
  for (int k = 0; k < 10; ++k)
  {
    char buf[128];
    const char* row = k == 0 ? "0.4,0.3,0.3,0" : k == 7 ? "0,0.1,0.1,0.8" : k < 5 ? "0.97,0.01,0.01,0.01" : "0.01,0.9,0.08,0.01";
    std::snprintf(buf, sizeof buf, "%.6f,%s\n", 100 + k / 10.0, row);
    probs += buf;
    std::snprintf(buf, sizeof buf, "%.6f %s\n", 100 + k / 10.0, k < 5 ? "stationary" : "rotation");
    labels += buf;
  }
  writeText(d / "model_probabilities.csv", probs);
  writeText(d / "motion_labels.txt", labels);
  const std::string P = (d / "model_probabilities.csv").string(), L = (d / "motion_labels.txt").string();
  TRun r = run(d, {"segmentation", P, L, "--exclude", "0.15"});
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_CONTAINS(r.out, "accuracy 71.43 % (5/7 frames counted; 3 within 0.15 s of one of 1 label changes excluded");
  r = run(d, {"segmentation", P, L, "--exclude=0"});
  EXPECT_CONTAINS(r.out, "accuracy 80.00 % (8/10 frames counted");
  r = run(d, {"segmentation", P, L});  // default 0.5 s: only frame 0 (exactly 0.5 s away) remains
  EXPECT_CONTAINS(r.out, "accuracy 0.00 % (0/1 frames counted");

  writeText(d / "bad_labels.txt", labels + "101.000000 flying\n");
  r = run(d, {"segmentation", P, (d / "bad_labels.txt").string()});
  EXPECT_EQ(r.rc, 1);
  EXPECT_CONTAINS(r.err, "bad_labels.txt:12");
  writeText(d / "bad_probs.csv", probs + "101.0,0.5,0.5\n");
  r = run(d, {"segmentation", (d / "bad_probs.csv").string(), L});
  EXPECT_EQ(r.rc, 1);
  EXPECT_CONTAINS(r.err, "bad_probs.csv:12");
  EXPECT_EQ(run(d, {"segmentation", P, L, "--exclude", "abc"}).rc, 2);
  EXPECT_EQ(run(d, {"segmentation", P}).rc, 2);
}

TEST(SlamEvalCli, ClassificationAgainstMasksAndPoints)
{
  const auto d = testDir();
  // A rendered-like dataset folder: rgb.txt + masks/ with two 40 x 30 masks (object 1 at
  // x 10..19, y 5..14 in frame 0; object 2 at x 20..29 in frame 1).
  fs::create_directories(d / "dataset" / "masks");
  cv::Mat m0(30, 40, CV_8UC1, cv::Scalar(0)), m1(30, 40, CV_8UC1, cv::Scalar(0));
  m0(cv::Rect(10, 5, 10, 10)).setTo(1);
  m1(cv::Rect(20, 5, 10, 10)).setTo(2);
  ASSERT_TRUE(cv::imwrite((d / "dataset" / "masks" / "000000.png").string(), m0));
  ASSERT_TRUE(cv::imwrite((d / "dataset" / "masks" / "000001.png").string(), m1));
  writeText(d / "dataset" / "rgb.txt", "# timestamp filename\n1.000000 rgb/000000.png\n1.033333 rgb/000001.png\n");
  writeText(d / "classifications.csv",
            "timestamp,feature_id,class,u,v\n"
            "1.000000,1,dynamic,12,7\n"      // moving, dynamic
            "1.000000,2,static,9,7\n"        // next to the object (radius 1): moving, static
            "1.000000,3,static,25,7\n"       // static, static
            "1.033333,1,dynamic,12,7\n"      // the object left: static, dynamic
            "1.033333,4,dynamic,25,10\n"     // moving, dynamic
            "1.033333,5,static,35,20\n"      // static, static
            "2.000000,6,static,1,1\n");      // no frame: unmatched
  const std::string C = (d / "classifications.csv").string();
  TRun r = run(d, {"classification", C, "--masks", (d / "dataset").string()});
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_CONTAINS(r.out, "moving->static rate : 33.33 % (1/3)");
  EXPECT_CONTAINS(r.out, "static->dynamic rate: 33.33 % (1/3)");
  EXPECT_CONTAINS(r.out, "unmatched decisions : 1");
  r = run(d, {"classification", C, "--masks", (d / "dataset").string(), "--radius", "0"});
  EXPECT_CONTAINS(r.out, "moving->static rate : 0.00 % (0/2)");

  // Ground-truth points: the nearest within 3 px decides; farther decisions are unmatched.
  writeText(d / "points_groundtruth.txt",
            "# timestamp point_id kind x y z u v\n"
            "1.000000 0 moving 0 0 5 12 8\n"
            "1.000000 1 static 0 0 5 9 7\n"
            "1.000000 2 static 0 0 5 25 7\n"
            "1.033333 0 moving 0 0 5 25 10\n"
            "1.033333 1 static 0 0 5 12 7\n");
  const std::string PT = (d / "points_groundtruth.txt").string();
  r = run(d, {"classification", C, "--points", PT});
  EXPECT_EQ(r.rc, 0) << r.err;
  // 12,7: moving (1 px) dyn; 9,7: static; 25,7: static; 12,7 @1.03: static dyn; 25,10: moving dyn;
  // 35,20: unmatched; 2.0 s: unmatched.
  EXPECT_CONTAINS(r.out, "moving->static rate : 0.00 % (0/2)");
  EXPECT_CONTAINS(r.out, "static->dynamic rate: 33.33 % (1/3)");
  EXPECT_CONTAINS(r.out, "unmatched decisions : 2");
  r = run(d, {"classification", C, "--points", PT, "--radius", "0.5"});
  EXPECT_CONTAINS(r.out, "unmatched decisions : 3");

  writeText(d / "bad.csv", "timestamp,feature_id,class,u,v\n1.0,1,static,1,2\n1.0,2,unsure,1,2\n");
  r = run(d, {"classification", (d / "bad.csv").string(), "--points", PT});
  EXPECT_EQ(r.rc, 1);
  EXPECT_CONTAINS(r.err, "bad.csv:3");
  r = run(d, {"classification", C, "--masks", (d / "nowhere").string()});
  EXPECT_EQ(r.rc, 1);
  EXPECT_CONTAINS(r.err, "nowhere");
  EXPECT_EQ(run(d, {"classification", C}).rc, 2);
  EXPECT_EQ(run(d, {"classification", C, "--masks", "x", "--points", "y"}).rc, 2);
}

TEST(SlamEvalCli, Nis)
{
  const auto d = testDir();
  // Used: NIS 2 (inlier), 2/3 (rescued), 8 (inlier, outside 5.991); rejected/not found ignored.
  writeText(d / "searches.csv",
            "timestamp,feature_id,h_u,h_v,s_uu,s_uv,s_vv,found,z_u,z_v,score,status\n"
            "1.000000,1,100,50,4,0,1,1,102,51,0.95,inlier\n"
            "1.000000,2,10,10,2,1,2,1,11,11,0.9,rescued\n"
            "1.000000,3,10,10,1,0,1,1,12,12,0.9,inlier\n"
            "1.000000,4,10,10,1,0,1,1,60,60,0.9,rejected\n"
            "1.000000,5,10,10,1,0,1,0,nan,nan,0.1,not_found\n");
  TRun r = run(d, {"nis", (d / "searches.csv").string()});
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_CONTAINS(r.out, "3 of 5 searches");
  EXPECT_CONTAINS(r.out, "mean NIS            : 3.556 (1.778 per dof");
  EXPECT_CONTAINS(r.out, "66.67 % (2/3 below chi2_2(0.95) = 5.991");
  writeText(d / "bad.csv", "timestamp,feature_id,h_u,h_v,s_uu,s_uv,s_vv,found,z_u,z_v,score,status\n"
                           "1.0,1,100,50,4,0,1,1,102,51,0.95,maybe\n");
  r = run(d, {"nis", (d / "bad.csv").string()});
  EXPECT_EQ(r.rc, 1);
  EXPECT_CONTAINS(r.err, "bad.csv:2");
  EXPECT_EQ(run(d, {"nis"}).rc, 2);
}
