/* Tests: motion segmentation accuracy (families, exclusion around label changes, ties, confusion)
 * and the readers of model_probabilities.csv and motion_labels.txt, on hand-made known answers. */
#include <gtest/gtest.h>
#include <immslam/eval/segmentation.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace immslam;
using namespace immslam::eval;

namespace
{
std::string tempPath(const std::string& name)
{
  return (std::filesystem::path(::testing::TempDir()) / ("immslam_seg_" + name)).string();
}
void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

const std::vector<std::string> kModels{"stationary", "rotation_0.1px", "rotation_1px", "general_0.1px", "general_1px"};

/** 30 frames at 10 Hz from t = 100 s: stationary (0-9), rotation (10-19), general (20-29); each
 * frame's whole probability on the first model of its label's family, except four frames:
 *  - 0 (stationary): stationary 0.4 < rotation 0.35 + 0.25  -> decided rotation (wrong);
 *  - 9 (stationary, near the change at 101 s): general 1     -> wrong, excluded with 0.25 s;
 *  - 14 (rotation): rotation 0.5 = general 0.5 (tie)         -> rotation (earlier family), right;
 *  - 25 (general): stationary 1                              -> wrong. */
struct TCase
{
  std::vector<double> times;
  std::vector<std::string> labels;
  MatX probs;
};
TCase makeCase()
{
  TCase c;
  c.probs = MatX::Zero(30, 5);
  for (int k = 0; k < 30; ++k)
  {
    c.times.push_back(100.0 + k / 10.0);
    c.labels.push_back(k < 10 ? "stationary" : k < 20 ? "rotation" : "general");
    c.probs(k, k < 10 ? 0 : k < 20 ? 1 : 3) = 1.0;
  }
  c.probs.row(0) << 0.4, 0.35, 0.25, 0, 0;
  c.probs.row(9) << 0, 0, 0, 0, 1;
  c.probs.row(14) << 0, 0.25, 0.25, 0.25, 0.25;
  c.probs.row(25) << 1, 0, 0, 0, 0;
  return c;
}
}  // namespace

TEST(Segmentation, ModelFamilyAndFamilySums)
{
  EXPECT_EQ(modelFamily("rotation_0.5px"), "rotation");
  EXPECT_EQ(modelFamily("stationary"), "stationary");
  EXPECT_EQ(modelFamily("general_1px_2"), "general");
  EXPECT_EQ(modelFamily(""), "");
  MatX p(2, 5);
  p << 0.1, 0.2, 0.3, 0.15, 0.25,  //
      1, 0, 0, 0, 0;
  const TFamilyProbabilities f = familyProbabilities(kModels, p);
  ASSERT_EQ(f.families, (std::vector<std::string>{"stationary", "rotation", "general"}));
  EXPECT_DOUBLE_EQ(f.probs(0, 0), 0.1);
  EXPECT_DOUBLE_EQ(f.probs(0, 1), 0.2 + 0.3);
  EXPECT_DOUBLE_EQ(f.probs(0, 2), 0.15 + 0.25);
  EXPECT_DOUBLE_EQ(f.probs(1, 0), 1.0);
  EXPECT_THROW(familyProbabilities({"a"}, p), std::invalid_argument);
}

TEST(Segmentation, KnownAccuracyWithExclusionTiesAndConfusion)
{
  const TCase c = makeCase();
  const TSegmentationResult r = segmentationAccuracy(c.times, kModels, c.probs, c.labels, 0.25);
  ASSERT_EQ(r.transitions.size(), 2u);
  EXPECT_DOUBLE_EQ(r.transitions[0], c.times[10]);
  EXPECT_DOUBLE_EQ(r.transitions[1], c.times[20]);
  // Excluded: frames 8-12 and 18-22 (within 0.25 s of 101 s and 102 s).
  EXPECT_EQ(r.nFrames, 30u);
  EXPECT_EQ(r.nExcluded, 10u);
  EXPECT_EQ(r.nCounted, 20u);
  EXPECT_EQ(r.nUnlabelled, 0u);
  EXPECT_EQ(r.nCorrect, 18u);
  EXPECT_DOUBLE_EQ(r.accuracy, 0.9);
  ASSERT_EQ(r.classes, (std::vector<std::string>{"stationary", "rotation", "general"}));
  EXPECT_EQ(r.count("stationary", "stationary"), 7u);
  EXPECT_EQ(r.count("stationary", "rotation"), 1u);
  EXPECT_EQ(r.count("rotation", "rotation"), 5u);  // includes the tie of frame 14
  EXPECT_EQ(r.count("general", "general"), 6u);
  EXPECT_EQ(r.count("general", "stationary"), 1u);
  EXPECT_EQ(r.count("general", "nonsense"), 0u);
  EXPECT_EQ(r.labelled("stationary"), 8u);
  EXPECT_DOUBLE_EQ(r.recall("stationary"), 7.0 / 8);
  EXPECT_DOUBLE_EQ(r.recall("rotation"), 1.0);
  EXPECT_DOUBLE_EQ(r.recall("general"), 6.0 / 7);
  EXPECT_TRUE(std::isnan(r.recall("nonsense")));
  const std::string s = r.summary();
  EXPECT_NE(s.find("accuracy 90.00 % (18/20 frames counted; 10 within 0.25 s of one of 2 label changes"),
            std::string::npos)
      << s;
  std::ostringstream os;
  os << r;
  EXPECT_EQ(os.str(), s);

  // No exclusion: all 30 frames count, frame 9 is a third error.
  const TSegmentationResult all = segmentationAccuracy(c.times, kModels, c.probs, c.labels, 0.0);
  EXPECT_EQ(all.nCounted, 30u);
  EXPECT_EQ(all.nCorrect, 27u);
  // Wide exclusion: only frames farther than 0.65 s from 101 and 102 s: 0-3 and 27-29.
  const TSegmentationResult wide = segmentationAccuracy(c.times, kModels, c.probs, c.labels, 0.65);
  EXPECT_EQ(wide.nCounted, 7u);
  EXPECT_EQ(wide.nCorrect, 6u);  // frame 0 wrong
}

TEST(Segmentation, UnlabelledFramesAndLabelsThatAreNoFamily)
{
  TCase c = makeCase();
  c.labels[5] = "";
  c.labels[10] = "";  // the change is now seen at frame 11
  const TSegmentationResult r = segmentationAccuracy(c.times, kModels, c.probs, c.labels, 0.25);
  EXPECT_EQ(r.nUnlabelled, 2u);
  ASSERT_EQ(r.transitions.size(), 2u);
  EXPECT_DOUBLE_EQ(r.transitions[0], c.times[11]);
  EXPECT_EQ(r.nExcluded + r.nCounted + r.nUnlabelled, 30u);

  // A single general model: stationary and rotation frames are always wrong.
  MatX one = MatX::Ones(30, 1);
  const TSegmentationResult g = segmentationAccuracy(c.times, {"general_1px"}, one, makeCase().labels, 0.0);
  ASSERT_EQ(g.classes, (std::vector<std::string>{"general", "stationary", "rotation"}));
  EXPECT_EQ(g.nCorrect, 10u);
  EXPECT_EQ(g.count("stationary", "general"), 10u);
  EXPECT_DOUBLE_EQ(g.accuracy, 1.0 / 3);

  EXPECT_THROW(segmentationAccuracy(c.times, kModels, c.probs, {"general"}, 0.5), std::invalid_argument);
  EXPECT_THROW(segmentationAccuracy(c.times, kModels, c.probs, c.labels, -1), std::invalid_argument);
  const TSegmentationResult none = segmentationAccuracy({}, kModels, MatX(0, 5), {}, 0.5);
  EXPECT_TRUE(std::isnan(none.accuracy));
}

TEST(Segmentation, ReadersAndAssociationByTimestamp)
{
  const TCase c = makeCase();
  // model_probabilities.csv as the app writes it (6 decimals for time, %.9g for values).
  std::ostringstream csv;
  csv << "timestamp";
  for (const auto& m : kModels) csv << ',' << m;
  csv << '\n';
  char buf[64];
  for (int k = 0; k < 30; ++k)
  {
    std::snprintf(buf, sizeof buf, "%.6f", c.times[k]);
    csv << buf;
    for (int j = 0; j < 5; ++j) csv << ',' << c.probs(k, j);
    csv << '\n';
  }
  const std::string probsPath = tempPath("probs.csv");
  writeText(probsPath, csv.str());
  // Labels 50 us late (within the 100 us association tolerance), frame 29 missing.
  std::ostringstream lab;
  lab << "# true camera motion\n# timestamp label\n";
  for (int k = 0; k < 29; ++k)
  {
    std::snprintf(buf, sizeof buf, "%.6f", c.times[k] + 5e-5);
    lab << buf << ' ' << c.labels[k] << "\n";
  }
  const std::string labelsPath = tempPath("labels.txt");
  writeText(labelsPath, lab.str());

  const TModelProbabilities p = readModelProbabilitiesCsv(probsPath);
  EXPECT_EQ(p.modelNames, kModels);
  ASSERT_EQ(p.times.size(), 30u);
  EXPECT_DOUBLE_EQ(p.times[3], 100.3);
  EXPECT_DOUBLE_EQ(p.probs(0, 1), 0.35);
  const TMotionLabels l = readMotionLabels(labelsPath);
  ASSERT_EQ(l.labels.size(), 29u);
  EXPECT_EQ(l.labels[12], "rotation");
  const std::vector<std::string> at = labelsAtTimes(l, p.times);
  EXPECT_EQ(at[0], "stationary");
  EXPECT_EQ(at[29], "");
  EXPECT_EQ(labelsAtTimes(l, {100.0 + 2e-4}).at(0), "");  // 150 us off: no label

  const TSegmentationResult r = segmentationAccuracy(p, l, 0.25);
  EXPECT_EQ(r.nUnlabelled, 1u);
  EXPECT_EQ(r.nCounted, 19u);
  EXPECT_EQ(r.nCorrect, 17u);
  TMotionLabels far = l;
  for (auto& t : far.times) t += 10;
  EXPECT_THROW(segmentationAccuracy(p, far), std::runtime_error);

  // Errors name file and line.
  const auto expectError = [](const std::string& path, const std::string& text, const std::string& where,
                              bool labels) {
    writeText(path, text);
    try
    {
      if (labels)
        readMotionLabels(path);
      else
        readModelProbabilitiesCsv(path);
      ADD_FAILURE() << "no error for " << text;
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_NE(std::string(e.what()).find(path + where), std::string::npos) << e.what();
    }
  };
  const std::string bad = tempPath("bad.txt");
  expectError(bad, "0.0 stationary\n\n# c\n0.1 walking\n", ":4", true);
  expectError(bad, "0.0 stationary extra\n", ":1", true);
  expectError(bad, "0.0 stationary\nabc rotation\n", ":2", true);
  expectError(bad, "time,stationary\n0,1\n", ":1", false);
  expectError(bad, "timestamp\n", ":1", false);
  expectError(bad, "timestamp,a,b\n0,0.5,0.5\n1,0.5\n", ":3", false);
  expectError(bad, "timestamp,a,b\n0,0.5,x\n", ":2", false);
  expectError(bad, "timestamp,a,b\n0,0.5,nan\n", ":2", false);
  expectError(bad, "", "", false);
  EXPECT_THROW(readMotionLabels(tempPath("missing.txt")), std::runtime_error);
}
