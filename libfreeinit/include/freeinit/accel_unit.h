// Which unit an accelerometer stream is in, from its mean specific force over a short stretch:
// whatever the motion, it averages to about 1 g, so a mean magnitude near 1 means the numbers are
// in g. Shared by the rawlog validator and the bag importer so that both judge alike.
#pragma once

#include <freeinit/types.h>

namespace freeinit {

enum class AccelUnitMismatch {
  kNone,
  kDataInG,    ///< declared m/s^2, the data are in g
  kDataInMs2,  ///< declared g, the data (after multiplying by kGravity) were already in m/s^2
};

/// `mean_norm`: |mean of the accelerations| after the declared unit's conversion to m/s^2.
inline AccelUnitMismatch accelUnitMismatch(double mean_norm, bool declared_g) {
  if (!declared_g && mean_norm > 0.5 && mean_norm < 1.5) return AccelUnitMismatch::kDataInG;
  if (declared_g && mean_norm > 3.0 * kGravity) return AccelUnitMismatch::kDataInMs2;
  return AccelUnitMismatch::kNone;
}

}  // namespace freeinit
