// The sensors' white noise from the window's own data, the configured values a prior.
//
// One rule for every noise (gyro, accelerometer, Doppler): the parameter is the log-variance
// lambda = log sigma^2. Its prior is normal about the configured value with the configured value
// wrong by 10x either way at 95 % (spread s0 = 2 ln 10 / 1.96 = 2.35); the data give an estimate
// sigma_hat with an effective number of degrees of freedom nu, i.e. log sigma_hat^2 with variance
// 2 / nu. The posterior of lambda is normal (precision w = 1/s0^2 + nu/2), and the variance used
// is its predictive second moment E[sigma^2] = exp(m + 1/(2w)): few samples inflate it rather
// than trusting a noisy estimate. The configured value's share of m is 5.7 % at nu = 6, 1.8 % at
// 20, 0.4 % at 100: a 10x wrong value is outweighed by twenty samples.
//
// At rest the IMU's white noise is read from the first differences of its samples (a slow bias
// drift leaves them alone), and whether the IMU is at rest at all from the von Neumann ratio of
// the samples (sum of squared differences over sum of squared deviations): about 2 for white
// noise of any level, far below for a motion slower than the sample rate. Neither uses the
// configured noise: rest is decided by the data's shape, not by a level.
//
// While the IMU moves, its white noise is read from a ladder of differences (imuMotionNoise):
// the k-th differences of the samples, scaled by 1/sqrt(C(2k, k)), have the variance sigma^2 of
// white noise at every order k, while a smooth motion adds (w^(k) h^k)^2 / C(2k, k), falling fast
// with k. Where successive orders agree the motion is gone from them (a plateau). An IMU's own
// low-pass filter colours its noise: the ladder then flattens below the noise the integration
// sees; the same ladder over every other sample (mid rather than high frequencies) must reach
// the same level. Where either fails, the data cannot tell and the configured value is kept.
#pragma once

#include <freeinit/initial_state.h>
#include <freeinit/types.h>

#include <array>
#include <cstddef>
#include <limits>
#include <vector>

#include "imu_screen.h"

namespace freeinit::detail {

/// [-] the configured noise is taken to be right within this factor either way at 95 %.
constexpr double kNoisePriorSpread = 10.0;

/// A noise level from the data combined with its prior (see the file's comment).
struct NoisePosterior {
  double sigma = 0;      ///< the value to use (sqrt of the predictive second moment)
  double rel_sigma = 0;  ///< relative 1-sigma of sigma (half the log-variance's std)
  double upper99 = 0;    ///< the posterior's 99 % upper quantile of sigma
};
/// The noise to use from the configured value `declared` and an estimate `estimate` with `dof`
/// effective degrees of freedom (dof <= 0 or estimate <= 0: the prior alone).
NoisePosterior combineNoise(double declared, double estimate, double dof);

/// The std of a zero-mean normal whose values within +-cut have the mean square `mean_square`
/// (a gate at cut keeps only those): sigma^2 = mean_square / t(cut / sigma), t(a) = 1 - 2 a
/// phi(a) / (2 Phi(a) - 1) the truncated normal's second moment (t(3) = 0.9733). The correction
/// is capped at t = 0.3 (a cut below ~1 sigma says little of what it cut).
double untruncatedSigma(double mean_square, double cut);

/// First differences of a 3-axis signal: their sum of squares and count, the white noise per
/// sample they give (sigma^2 = sum / (2 * 3 * count)) and its effective degrees of freedom
/// (2 count: neighbouring differences share a sample).
struct DifferenceSums {
  double squares = 0;
  std::size_t count = 0;
  void add(const Vec3& difference) {
    squares += difference.squaredNorm();
    ++count;
  }
  double sigma() const;
  double dof() const { return 2.0 * static_cast<double>(count); }
};

/// What an IMU span says about rest (imuRestEvidence).
struct ImuRestEvidence {
  bool still = false;        ///< both sensors show white noise at a plausible level
  bool gyro_white = false;   ///< von Neumann ratio above its lower 99.9 % limit
  bool accel_white = false;  ///< likewise
  bool plausible = false;    ///< levels and means within their physical ranges
  double eta_gyro = 0, eta_accel = 0, eta_limit = 0;  ///< the ratios and their limit
  DifferenceSums gyro, accel;                         ///< the span's first differences
};

/// Settings of imuRestEvidence: the configured values only bound what is plausible.
struct RestEvidenceParams {
  double gyro_sigma = 0.002;            ///< [rad/s] configured noise per sample
  double accel_sigma = 0.02;            ///< [m/s^2] configured noise per sample
  Vec3 gyro_bias_prior = Vec3::Zero();  ///< [rad/s]
  double gyro_bias_sigma = 0.015;       ///< [rad/s] the gyro bias prior's std
  double accel_bias_bound = 0.5;        ///< [m/s^2] per axis
};

/// Whether imu[begin, end) shows rest, whatever the noise level: for each of the gyro and the
/// accelerometer, the von Neumann ratio (pooled over the axes) above 2 - 3.09 of its std under
/// white noise (a one-sided 0.1 % chance of calling white noise motion), the level from the
/// differences within the prior's range of the configured one, the mean rate within 5 gyro-bias
/// sigmas of the prior (a constant rotation is white too) and the mean specific force's norm
/// within sqrt(3) bias bounds of gravity. Fewer than 5 samples: not still.
/// `extra` (optional, per sample of `imu`, ImuScreen): a sensor's synthetic samples are left out,
/// and so is every difference touching one (an interpolated value differs from its neighbours
/// by less than noise would: it would lower the level and the ratio); the ratio is then taken
/// per difference and per deviation.
ImuRestEvidence imuRestEvidence(const std::vector<ImuSample>& imu, std::size_t begin,
                                std::size_t end, const RestEvidenceParams& params,
                                const std::vector<ImuExtraNoise>* extra = nullptr);

/// A moving IMU's white noise per sample from one of its signals (imuMotionNoise).
struct MotionNoise {
  double sigma = 0;  ///< the signal's unit per sample; 0: the data cannot tell it from motion
  double dof = 0;    ///< effective degrees of freedom of sigma^2
  int order = 0;     ///< the difference order the estimate is read from
};

/// The white noise of the gyro (`accel` false) or the accelerometer in imu[begin, end), moving
/// or not, from the ladder of scaled differences (see the file's comment) of orders 1 to 8 over
/// consecutive samples and over every other one. Each ladder's plateau is its first order k at
/// which orders k, k + 1 and k + 2 agree pairwise within the spread white noise gives their
/// ratio (99.9 %, two-sided); the two plateaus must agree likewise. The estimate is the stride-1
/// plateau's level. Differences spanning a gap (an interval beyond 1.5 `interval`) or a synthetic
/// sample (`extra`, ImuScreen) are left out; each order needs at least 20 differences.
MotionNoise imuMotionNoise(const std::vector<ImuSample>& imu, std::size_t begin, std::size_t end,
                           bool accel, double interval,
                           const std::vector<ImuExtraNoise>* extra = nullptr);

/// imuMotionNoise's sums kept between calls over a span that grows at its end, so that every
/// sample's differences are taken once: extend() to `end` gives what imuMotionNoise over
/// [begin, end) would (it is imuMotionNoise's implementation: the same differences, summed in
/// the same sample order, whatever the calls' split of the span). A call with another begin, an
/// earlier end, or a nominal interval that would join or part two samples already summed
/// otherwise, starts again from `begin`.
///
/// Each sample's differences come from the orders below (the k-th difference over stride s is
/// the (k-1)-th at the sample less the (k-1)-th s samples earlier), so a sample costs O(orders)
/// per stride; the last s differences of each order are kept for the next samples.
class MotionNoiseLadder {
 public:
  explicit MotionNoiseLadder(bool accel);
  /// imuMotionNoise(imu, begin, end, accel, interval, extra), from the sums so far.
  MotionNoise extend(const std::vector<ImuSample>& imu, std::size_t begin, std::size_t end,
                     double interval, const std::vector<ImuExtraNoise>* extra);

  static constexpr int kOrders = 8;   ///< difference orders 1..8
  static constexpr int kStrides = 2;  ///< over consecutive samples and every other one

  /// The mean square per axis of the scaled differences of `order` (1..kOrders) over samples
  /// `stride` (1..kStrides) apart summed so far (the signal's unit squared; 0 before any).
  double meanSquare(int stride, int order) const;
  /// How many differences of `order` over `stride` are summed so far.
  std::size_t differences(int stride, int order) const;

 private:
  void reset(std::size_t begin);
  bool accel_;
  std::size_t begin_ = 0, next_ = 0;  ///< the span summed: [begin_, next_)
  int run_ = 0;                       ///< consecutive measured samples ending at next_ - 1
  /// [s] the largest interval joined and the smallest parted so far (the interval's test).
  double joined_ = 0, parted_ = std::numeric_limits<double>::infinity();
  /// Sums of the squared norms of the unscaled differences (binomial taps) per stride, order.
  std::array<std::array<double, kOrders>, kStrides> squares_{};
  std::array<std::array<std::size_t, kOrders>, kStrides> count_{};
  /// The unscaled differences of orders 0 (the samples) to kOrders - 1 at the last s samples
  /// of stride s, the one at sample j in slot j % s; valid where the run covers them.
  std::array<std::array<std::array<Vec3, kStrides>, kOrders>, kStrides> last_;
};

}  // namespace freeinit::detail
