#include <freeinit/eval/bound_ratio.h>

#include <cmath>
#include <limits>

namespace freeinit::eval {

double boundRatio(double error, double bound) {
  if (std::isnan(error) || std::isnan(bound)) return std::numeric_limits<double>::quiet_NaN();
  if (std::isinf(bound)) return std::isinf(error) ? std::numeric_limits<double>::quiet_NaN() : 0.0;
  if (bound <= 0) return error > 0 ? std::numeric_limits<double>::infinity() : 0.0;
  return error / bound;
}

bool confidentlyWrong(double error, double bound, double floor) {
  if (std::isnan(error) || std::isnan(bound)) return false;
  return error > kConfidentWrongRatio * bound && error > floor;
}

}  // namespace freeinit::eval
