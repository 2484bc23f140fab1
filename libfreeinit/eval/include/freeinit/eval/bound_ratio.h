// Errors measured against the Cramer-Rao bound: error / bound per quantity, and what counts as a
// confident wrong answer (an ok state far outside its physical limit by more than a user notices).
#pragma once

namespace freeinit::eval {

/// Errors below these are not noticed by a user whatever the bound says.
struct NoticeFloors {
  double velocity = 0.02;    ///< [m/s]
  double gravity_deg = 0.2;  ///< [deg]
  double gyro_bias = 0.001;  ///< [rad/s]
  double accel_bias = 0.03;  ///< [m/s^2]
};

/// An error more than this many times its bound is outside what the data allow.
inline constexpr double kConfidentWrongRatio = 3.0;

/// error / bound. NaN when either is NaN; 0 when the bound is infinite (nothing can be known) and
/// the error finite; +inf when the bound is 0 and the error is not.
double boundRatio(double error, double bound);

/// error > kConfidentWrongRatio * bound and error > floor (false when either is NaN).
bool confidentlyWrong(double error, double bound, double floor);

}  // namespace freeinit::eval
