#include "joint/noise_estimate.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace freeinit::detail {
namespace {

/// Whether sample i's accelerometer (`accel`) or gyro reading is a measurement, not a value
/// ImuScreen made (`extra`: ImuScreen's per sample, or none).
bool measuredReading(const std::vector<ImuExtraNoise>* extra, std::size_t i, bool accel) {
  if (extra == nullptr || i >= extra->size()) return true;
  return !(accel ? (*extra)[i].accel_synthetic : (*extra)[i].gyro_synthetic);
}

}  // namespace

NoisePosterior combineNoise(double declared, double estimate, double dof) {
  // Prior on log sigma^2: the declared value, kNoisePriorSpread either way at 95 %.
  const double s0 = 2.0 * std::log(kNoisePriorSpread) / 1.96;
  const double prior_precision = 1.0 / (s0 * s0);
  const double m0 = std::log(declared * declared);
  double w = prior_precision, m = m0;
  if (estimate > 0 && dof > 0) {
    const double data_precision = 0.5 * dof;
    w = prior_precision + data_precision;
    m = (m0 * prior_precision + std::log(estimate * estimate) * data_precision) / w;
  }
  NoisePosterior out;
  out.sigma = std::exp(0.5 * (m + 0.5 / w));
  out.rel_sigma = 0.5 / std::sqrt(w);
  constexpr double kZ99 = 2.326;
  out.upper99 = std::exp(0.5 * (m + kZ99 / std::sqrt(w)));
  return out;
}

double untruncatedSigma(double mean_square, double cut) {
  if (!(mean_square > 0)) return 0.0;
  if (!(cut > 0)) return std::sqrt(mean_square);
  constexpr double kInvSqrt2Pi = 0.3989422804014327;
  double sigma = std::sqrt(mean_square);
  for (int i = 0; i < 30; ++i) {
    const double a = cut / sigma;
    const double phi = kInvSqrt2Pi * std::exp(-0.5 * a * a);
    const double inside = std::erf(a / std::sqrt(2.0));  // 2 Phi(a) - 1
    const double t = std::max(0.3, 1.0 - 2.0 * a * phi / inside);
    const double next = std::sqrt(mean_square / t);
    if (std::abs(next - sigma) < 1e-9 * sigma) return next;
    sigma = next;
  }
  return sigma;
}

double DifferenceSums::sigma() const {
  return count > 0 ? std::sqrt(squares / (6.0 * static_cast<double>(count))) : 0.0;
}

ImuRestEvidence imuRestEvidence(const std::vector<ImuSample>& imu, std::size_t begin,
                                std::size_t end, const RestEvidenceParams& p,
                                const std::vector<ImuExtraNoise>* extra) {
  ImuRestEvidence out;
  if (end > imu.size() || end < begin + 5) return out;
  auto measured = [extra](std::size_t i, bool accel) { return measuredReading(extra, i, accel); };
  std::size_t count_g = 0, count_a = 0;
  Vec3 mg = Vec3::Zero(), ma = Vec3::Zero();
  for (std::size_t i = begin; i < end; ++i) {
    if (measured(i, false)) {
      mg += imu[i].gyro;
      ++count_g;
    }
    if (measured(i, true)) {
      ma += imu[i].accel;
      ++count_a;
    }
  }
  if (count_g < 5 || count_a < 5) return out;
  const double n_g = static_cast<double>(count_g), n_a = static_cast<double>(count_a);
  mg /= n_g;
  ma /= n_a;
  double sg = 0, sa = 0;
  for (std::size_t i = begin; i < end; ++i) {
    const bool g = measured(i, false), a = measured(i, true);
    if (g) sg += (imu[i].gyro - mg).squaredNorm();
    if (a) sa += (imu[i].accel - ma).squaredNorm();
    if (i > begin) {
      if (g && measured(i - 1, false)) out.gyro.add(imu[i].gyro - imu[i - 1].gyro);
      if (a && measured(i - 1, true)) out.accel.add(imu[i].accel - imu[i - 1].accel);
    }
  }
  // Von Neumann's ratio of white noise: mean 2n/(n-1), variance 4(n-2)/((n+1)(n-1)) per axis,
  // a third of it pooled over three. A motion slower than the sample rate adds to the spread,
  // hardly to the differences. Exact zeros (a quantized, still signal): white as well. With
  // samples left out, the squares per difference over those per deviation (n - 1 of them); the
  // limit for the sensor with fewer samples.
  const double n = std::min(n_g, n_a);
  const double sd = std::sqrt(4.0 * (n - 2.0) / ((n + 1.0) * (n - 1.0)) / 3.0);
  constexpr double kZ999 = 3.09;
  out.eta_limit = 2.0 - kZ999 * sd;
  const double per_g = out.gyro.count > 0 ? (n_g - 1.0) / static_cast<double>(out.gyro.count) : 0;
  const double per_a = out.accel.count > 0 ? (n_a - 1.0) / static_cast<double>(out.accel.count) : 0;
  out.eta_gyro = sg > 0 ? out.gyro.squares * per_g / sg : 2.0;
  out.eta_accel = sa > 0 ? out.accel.squares * per_a / sa : 2.0;
  out.gyro_white = out.eta_gyro >= out.eta_limit;
  out.accel_white = out.eta_accel >= out.eta_limit;
  // Levels: within the prior's range of the configured ones (a vibrating vehicle can look white
  // at a level no standing IMU has); a gyro reading far from its bias prior turns (steadily).
  const double sig_g = out.gyro.sigma(), sig_a = out.accel.sigma();
  const bool levels =
      sig_g <= kNoisePriorSpread * p.gyro_sigma && sig_a <= kNoisePriorSpread * p.accel_sigma;
  const bool rate = (mg - p.gyro_bias_prior).cwiseAbs().maxCoeff() <= 5.0 * p.gyro_bias_sigma;
  const bool gravity = std::abs(ma.norm() - kGravity) <= std::sqrt(3.0) * p.accel_bias_bound;
  out.plausible = levels && rate && gravity;
  out.still = out.gyro_white && out.accel_white && out.plausible;
  return out;
}

namespace {

constexpr int kLadderOrders = 8;
constexpr int kLadderStrides = 2;
constexpr int kMostTaps = kLadderOrders * kLadderStrides + 1;

/// The k-th difference over samples `stride` apart as taps on consecutive samples: the signed
/// binomials C(order, i) (zero between its samples), unscaled, exact in doubles; `norm`, the
/// sum of their squares C(2 order, order), is the squared gain on white noise the ladder scales
/// away.
struct DifferenceTaps {
  std::array<double, kMostTaps> tap{};
  int length = 0;
  double norm = 0;
};

constexpr DifferenceTaps differenceTaps(int order, int stride) {
  DifferenceTaps d;
  d.length = order * stride + 1;
  double binomial = 1;  // C(order, i)
  for (int i = 0; i <= order; ++i) {
    d.tap[static_cast<std::size_t>(i * stride)] = ((order - i) % 2 == 0 ? 1.0 : -1.0) * binomial;
    d.norm += binomial * binomial;
    binomial = binomial * (order - i) / (i + 1);
  }
  return d;
}

/// Sum over lags of the squared cross-correlation of two tap sets scaled to unit gain on white
/// noise: n / that is the effective number of samples behind the mean square of a (a = b), and
/// the covariance of two mean squares over n outputs of white noise is
/// 2 sigma^4 crossSquares(a, b) / n.
constexpr double crossSquares(const DifferenceTaps& a, const DifferenceTaps& b) {
  double sum = 0;  // of the unscaled taps: integers, exact
  for (int lag = -(a.length - 1); lag < b.length; ++lag) {
    double c = 0;
    for (int i = lag < 0 ? -lag : 0; i < a.length && i + lag < b.length; ++i)
      c += a.tap[static_cast<std::size_t>(i)] * b.tap[static_cast<std::size_t>(i + lag)];
    sum += c * c;
  }
  return sum / (a.norm * b.norm);
}

/// The ladder's constants: its tap sets and their crossSquares, per stride index s (stride
/// s + 1) and order index k (order k + 1).
struct LadderTable {
  std::array<std::array<DifferenceTaps, kLadderOrders>, kLadderStrides> taps{};
  /// crossSquares(taps[s][k], taps[t][l]) at cross[s][k][t][l].
  std::array<
      std::array<std::array<std::array<double, kLadderOrders>, kLadderStrides>, kLadderOrders>,
      kLadderStrides>
      cross{};
};

constexpr LadderTable ladderTable() {
  LadderTable t;
  for (int s = 0; s < kLadderStrides; ++s)
    for (int k = 0; k < kLadderOrders; ++k) t.taps[s][k] = differenceTaps(k + 1, s + 1);
  for (int s = 0; s < kLadderStrides; ++s)
    for (int k = 0; k < kLadderOrders; ++k)
      for (int u = 0; u < kLadderStrides; ++u)
        for (int l = 0; l < kLadderOrders; ++l)
          t.cross[s][k][u][l] = crossSquares(t.taps[s][k], t.taps[u][l]);
  return t;
}

constexpr LadderTable kLadder = ladderTable();
static_assert(kLadder.taps[1][7].norm == 12870 && kLadder.taps[1][7].length == 17,
              "C(16, 8) over 17 samples");
static_assert(kLadder.cross[0][0][0][0] == 1.5, "first differences: 1 + 2 (1/2)^2");

/// One of the ladder's differences: stride index s, order index k (kLadder).
struct Rung {
  int s = 0, k = 0;
};

/// Whether the mean squares ea and eb of rungs a and b, each over `outputs` differences per
/// axis of three, agree as white noise's would: |log(ea / eb)| within 3.29 of its std (99.9 %,
/// two-sided). The std is the asymptotic one, 2 / (3 outputs) (X(a, a) + X(b, b) - 2 X(a, b))
/// with X = crossSquares, times 1 + 3 L / outputs (L the longer tap set): over short windows the
/// ratio of two highly correlated mean squares spreads wider (measured on 400 windows of white
/// noise each: 1.05-1.5 at 100 samples for orders 1-8 and strides 1-2, 1.04-1.14 at 400).
bool sameWhiteLevel(double ea, double eb, const LadderTable& t, Rung a, Rung b, double outputs) {
  if (!(ea > 0) || !(eb > 0) || !(outputs > 0)) return ea == eb;
  const double var = 2.0 / (3.0 * outputs) *
                     (t.cross[a.s][a.k][a.s][a.k] + t.cross[b.s][b.k][b.s][b.k] -
                      2.0 * t.cross[a.s][a.k][b.s][b.k]);
  const int longer = std::max(t.taps[a.s][a.k].length, t.taps[b.s][b.k].length);
  const double finite_window = 1.0 + 3.0 * longer / outputs;
  constexpr double kZ999TwoSided = 3.29;
  return std::abs(std::log(ea / eb)) <=
         kZ999TwoSided * finite_window * std::sqrt(std::max(var, 0.0));
}

}  // namespace

MotionNoise imuMotionNoise(const std::vector<ImuSample>& imu, std::size_t begin, std::size_t end,
                           bool accel, double interval, const std::vector<ImuExtraNoise>* extra) {
  return MotionNoiseLadder(accel).extend(imu, begin, end, interval, extra);
}

MotionNoiseLadder::MotionNoiseLadder(bool accel) : accel_(accel) { reset(0); }

void MotionNoiseLadder::reset(std::size_t begin) {
  begin_ = next_ = begin;
  run_ = 0;
  joined_ = 0;
  parted_ = std::numeric_limits<double>::infinity();
  squares_ = {};
  count_ = {};
  for (auto& stride : last_)
    for (auto& order : stride)
      for (Vec3& d : order) d.setZero();
}

double MotionNoiseLadder::meanSquare(int stride, int order) const {
  if (stride < 1 || stride > kStrides || order < 1 || order > kOrders) return 0.0;
  const auto s = static_cast<std::size_t>(stride - 1), k = static_cast<std::size_t>(order - 1);
  if (count_[s][k] == 0) return 0.0;
  return squares_[s][k] / (kLadder.taps[s][k].norm * 3.0 * static_cast<double>(count_[s][k]));
}

std::size_t MotionNoiseLadder::differences(int stride, int order) const {
  if (stride < 1 || stride > kStrides || order < 1 || order > kOrders) return 0;
  return count_[static_cast<std::size_t>(stride - 1)][static_cast<std::size_t>(order - 1)];
}

MotionNoise MotionNoiseLadder::extend(const std::vector<ImuSample>& imu, std::size_t begin,
                                      std::size_t end, double interval,
                                      const std::vector<ImuExtraNoise>* extra) {
  static_assert(kOrders == kLadderOrders && kStrides == kLadderStrides, "one ladder");
  end = std::min(end, imu.size());
  const double cut = 1.5 * interval;
  const bool same_joins = interval > 0 ? joined_ <= cut && parted_ > cut : joined_ == 0;
  if (begin != begin_ || end < next_ || !same_joins) reset(begin);
  const bool accel = accel_;
  const LadderTable& table = kLadder;
  std::array<std::array<double, kLadderOrders>, kLadderStrides>& squares = squares_;
  std::array<std::array<std::size_t, kLadderOrders>, kLadderStrides>& count = count_;
  // run: consecutive measured samples ending at j without a gap between them. The order-k
  // difference over stride s at j exists where run >= k s + 1; it is the order k - 1 one at j
  // less that at j - s, which then exists as well (and was kept in last_ then).
  int run = run_;
  for (std::size_t j = next_; j < end; ++j) {
    bool joined = false;
    if (j > begin) {
      const double dt = imu[j].t - imu[j - 1].t;
      joined = interval > 0 && dt <= cut;
      if (joined)
        joined_ = std::max(joined_, dt);
      else
        parted_ = std::min(parted_, dt);
    }
    run = !measuredReading(extra, j, accel) ? 0 : (joined ? std::min(run + 1, kMostTaps) : 1);
    const Vec3& x = accel ? imu[j].accel : imu[j].gyro;
    for (int s = 0; s < kLadderStrides; ++s) {
      const int stride = s + 1;
      const std::size_t slot = j % static_cast<std::size_t>(stride);
      Vec3 d = x;  // the order-k difference at j (unscaled)
      for (int k = 0; k < kLadderOrders; ++k) {
        Vec3& kept = last_[s][k][slot];
        const Vec3 earlier = kept;  // the order-k difference at j - stride
        kept = d;
        if (run < (k + 1) * stride + 1) break;  // the higher orders are longer still
        d -= earlier;
        squares[s][k] += d.squaredNorm();
        ++count[s][k];
      }
    }
  }
  run_ = run;
  next_ = std::max(next_, end);
  // Each ladder's plateau: its first order whose next two agree with it.
  constexpr std::size_t kMinDifferences = 20;
  std::array<int, kLadderStrides> plateau{};
  std::array<double, kLadderStrides> level{};
  for (int s = 0; s < kLadderStrides; ++s) {
    plateau[s] = -1;
    if (count[s][kLadderOrders - 1] < kMinDifferences) return {};
    std::array<double, kLadderOrders> e{};
    for (int k = 0; k < kLadderOrders; ++k) e[k] = meanSquare(s + 1, k + 1);
    const double n = static_cast<double>(count[s][kLadderOrders - 1]);
    auto agree = [&](int k) {
      return sameWhiteLevel(e[k], e[k + 1], table, Rung{s, k}, Rung{s, k + 1}, n);
    };
    for (int k = 0; k + 2 < kLadderOrders && plateau[s] < 0; ++k)
      if (agree(k) && agree(k + 1)) plateau[s] = k;
    if (plateau[s] < 0) return {};
    level[s] = e[plateau[s]];
  }
  const Rung a{0, plateau[0]}, b{1, plateau[1]};
  const double n_b = static_cast<double>(count[1][plateau[1]]);
  if (!sameWhiteLevel(level[0], level[1], table, a, b, n_b)) return {};
  MotionNoise out;
  out.sigma = std::sqrt(level[0]);
  out.dof = 3.0 * static_cast<double>(count[0][plateau[0]]) / table.cross[0][a.k][0][a.k];
  out.order = plateau[0] + 1;
  return out;
}

}  // namespace freeinit::detail

namespace freeinit {

const char* toString(NoiseUsed::Source s) {
  switch (s) {
    case NoiseUsed::Source::Declared:
      return "declared";
    case NoiseUsed::Source::DataRest:
      return "data_rest";
    case NoiseUsed::Source::DataMoving:
      return "data_moving";
    case NoiseUsed::Source::UpperBound:
      return "upper_bound";
    case NoiseUsed::Source::Data:
      return "data";
  }
  return "unknown";
}

}  // namespace freeinit
