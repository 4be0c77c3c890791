/* imm-monoslam — static/dynamic confusion matrix. */
#include <immslam/eval/classification.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <ostream>

namespace immslam::eval
{
namespace
{
double frac(size_t num, size_t den)
{
  return den ? static_cast<double>(num) / static_cast<double>(den) : std::numeric_limits<double>::quiet_NaN();
}

std::string pct(double v)
{
  if (std::isnan(v)) return "n/a";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f %%", 100.0 * v);
  return buf;
}
}  // namespace

void TConfusionMatrix::add(EMotionClass truth, EMotionClass decided)
{
  if (truth == EMotionClass::Static)
    ++(decided == EMotionClass::Static ? staticAsStatic : staticAsDynamic);
  else
    ++(decided == EMotionClass::Static ? dynamicAsStatic : dynamicAsDynamic);
}

TConfusionMatrix& TConfusionMatrix::operator+=(const TConfusionMatrix& o)
{
  staticAsStatic += o.staticAsStatic;
  staticAsDynamic += o.staticAsDynamic;
  dynamicAsStatic += o.dynamicAsStatic;
  dynamicAsDynamic += o.dynamicAsDynamic;
  return *this;
}

size_t TConfusionMatrix::total() const { return trulyStatic() + trulyDynamic(); }
double TConfusionMatrix::movingAsStaticRate() const { return frac(dynamicAsStatic, trulyDynamic()); }
double TConfusionMatrix::staticAsDynamicRate() const { return frac(staticAsDynamic, trulyStatic()); }
double TConfusionMatrix::accuracy() const { return frac(staticAsStatic + dynamicAsDynamic, total()); }
double TConfusionMatrix::precision() const { return frac(dynamicAsDynamic, dynamicAsDynamic + staticAsDynamic); }
double TConfusionMatrix::recall() const { return frac(dynamicAsDynamic, trulyDynamic()); }

double TConfusionMatrix::f1() const
{
  const double p = precision(), r = recall();
  if (std::isnan(p) || std::isnan(r)) return std::numeric_limits<double>::quiet_NaN();
  return p + r > 0 ? 2 * p * r / (p + r) : 0.0;
}

std::string TConfusionMatrix::summary() const
{
  char buf[512];
  std::string s;
  std::snprintf(buf, sizeof buf,
                "static/dynamic classification: %zu decisions\n"
                "                  classified static  classified dynamic\n"
                "  truly static    %17zu  %18zu\n"
                "  truly dynamic   %17zu  %18zu\n",
                total(), staticAsStatic, staticAsDynamic, dynamicAsStatic, dynamicAsDynamic);
  s += buf;
  s += "  moving->static rate : " + pct(movingAsStaticRate()) + " (" + std::to_string(dynamicAsStatic) +
       "/" + std::to_string(trulyDynamic()) + ")\n";
  s += "  static->dynamic rate: " + pct(staticAsDynamicRate()) + " (" + std::to_string(staticAsDynamic) +
       "/" + std::to_string(trulyStatic()) + ")\n";
  s += "  accuracy            : " + pct(accuracy()) + "\n";
  s += "  precision (dynamic) : " + pct(precision()) + "\n";
  s += "  recall (dynamic)    : " + pct(recall()) + "\n";
  s += "  F1 (dynamic)        : " + pct(f1()) + "\n";
  return s;
}

std::ostream& operator<<(std::ostream& os, const TConfusionMatrix& m) { return os << m.summary(); }
}  // namespace immslam::eval
