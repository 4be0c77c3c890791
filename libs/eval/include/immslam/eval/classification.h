/* imm-monoslam — static/dynamic feature classification scores (shadow filter evaluation). */
#pragma once

#include <cstddef>
#include <iosfwd>
#include <string>

namespace immslam::eval
{
/** Class of a feature: on the static world or on a moving object. */
enum class EMotionClass
{
  Static,
  Dynamic
};

/** Binary confusion matrix of static/dynamic decisions ("dynamic" is the positive class).
 * Rates whose denominator is 0 are NaN (printed "n/a"). */
struct TConfusionMatrix
{
  size_t staticAsStatic = 0;    ///< truly static, classified static (true negatives)
  size_t staticAsDynamic = 0;   ///< truly static, classified dynamic (false positives)
  size_t dynamicAsStatic = 0;   ///< truly moving, classified static (false negatives)
  size_t dynamicAsDynamic = 0;  ///< truly moving, classified dynamic (true positives)

  /** Counts one decision. */
  void add(EMotionClass truth, EMotionClass decided);
  /** Adds another matrix's counts. */
  TConfusionMatrix& operator+=(const TConfusionMatrix& o);

  size_t total() const;
  size_t trulyStatic() const { return staticAsStatic + staticAsDynamic; }
  size_t trulyDynamic() const { return dynamicAsStatic + dynamicAsDynamic; }

  /** Moving features classified static / all moving features (the dangerous error: moving points
   * promoted into the SLAM map). Equals 1 - recall(). */
  double movingAsStaticRate() const;
  /** Static features classified dynamic / all static features (false-positive rate). */
  double staticAsDynamicRate() const;
  /** Correct decisions / all decisions. */
  double accuracy() const;
  /** Precision of the "dynamic" class: dynamicAsDynamic / classified dynamic. */
  double precision() const;
  /** Recall of the "dynamic" class: dynamicAsDynamic / truly dynamic. */
  double recall() const;
  /** Harmonic mean of precision and recall. */
  double f1() const;

  /** Multi-line human-readable table with the counts and the rates in percent. */
  std::string summary() const;
};

/** Prints TConfusionMatrix::summary(). */
std::ostream& operator<<(std::ostream& os, const TConfusionMatrix& m);
}  // namespace immslam::eval
