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

/// The k-th difference over samples `stride` apart as taps on consecutive samples, scaled to
/// unit gain on white noise (zero between its samples).
struct DifferenceTaps {
  std::array<double, kMostTaps> tap{};
  int length = 0;
};

DifferenceTaps differenceTaps(int order, int stride) {
  DifferenceTaps d;
  d.length = order * stride + 1;
  double binomial = 1, norm = 0;  // C(order, i), and the sum of its squares = C(2 order, order)
  for (int i = 0; i <= order; ++i) {
    d.tap[static_cast<std::size_t>(i * stride)] = ((order - i) % 2 == 0 ? 1.0 : -1.0) * binomial;
    norm += binomial * binomial;
    binomial = binomial * (order - i) / (i + 1);
  }
  for (double& t : d.tap) t /= std::sqrt(norm);
  return d;
}

/// Sum over lags of the squared cross-correlation of two tap sets: n / that is the effective
/// number of samples behind the mean square of a (a = b), and the covariance of two mean squares
/// over n outputs of white noise is 2 sigma^4 crossSquares(a, b) / n.
double crossSquares(const DifferenceTaps& a, const DifferenceTaps& b) {
  double sum = 0;
  for (int lag = -(a.length - 1); lag < b.length; ++lag) {
    double c = 0;
    for (int i = 0; i < a.length; ++i) {
      const int j = i + lag;
      if (j >= 0 && j < b.length)
        c += a.tap[static_cast<std::size_t>(i)] * b.tap[static_cast<std::size_t>(j)];
    }
    sum += c * c;
  }
  return sum;
}

/// Whether the mean squares ea and eb of tap sets a and b, each over `outputs` differences per
/// axis of three, agree as white noise's would: |log(ea / eb)| within 3.29 of its std (99.9 %,
/// two-sided). The std is the asymptotic one, 2 / (3 outputs) (X(a, a) + X(b, b) - 2 X(a, b))
/// with X = crossSquares, times 1 + 3 L / outputs (L the longer tap set): over short windows the
/// ratio of two highly correlated mean squares spreads wider (measured on 400 windows of white
/// noise each: 1.05-1.5 at 100 samples for orders 1-8 and strides 1-2, 1.04-1.14 at 400).
bool sameWhiteLevel(double ea, double eb, const DifferenceTaps& a, const DifferenceTaps& b,
                    double outputs) {
  if (!(ea > 0) || !(eb > 0) || !(outputs > 0)) return ea == eb;
  const double var =
      2.0 / (3.0 * outputs) * (crossSquares(a, a) + crossSquares(b, b) - 2.0 * crossSquares(a, b));
  const double finite_window = 1.0 + 3.0 * std::max(a.length, b.length) / outputs;
  constexpr double kZ999TwoSided = 3.29;
  return std::abs(std::log(ea / eb)) <=
         kZ999TwoSided * finite_window * std::sqrt(std::max(var, 0.0));
}

}  // namespace

MotionNoise imuMotionNoise(const std::vector<ImuSample>& imu, std::size_t begin, std::size_t end,
                           bool accel, double interval, const std::vector<ImuExtraNoise>* extra) {
  end = std::min(end, imu.size());
  std::array<std::array<DifferenceTaps, kLadderOrders>, kLadderStrides> taps;
  std::array<std::array<double, kLadderOrders>, kLadderStrides> squares{};
  std::array<std::array<std::size_t, kLadderOrders>, kLadderStrides> count{};
  for (int s = 0; s < kLadderStrides; ++s)
    for (int k = 0; k < kLadderOrders; ++k) taps[s][k] = differenceTaps(k + 1, s + 1);
  auto value = [&](std::size_t i) -> const Vec3& { return accel ? imu[i].accel : imu[i].gyro; };
  // run: consecutive measured samples ending at j without a gap between them.
  int run = 0;
  for (std::size_t j = begin; j < end; ++j) {
    const bool joined = j > begin && interval > 0 && imu[j].t - imu[j - 1].t <= 1.5 * interval;
    run = !measuredReading(extra, j, accel) ? 0 : (joined ? std::min(run + 1, kMostTaps) : 1);
    for (int s = 0; s < kLadderStrides; ++s)
      for (int k = 0; k < kLadderOrders; ++k) {
        const DifferenceTaps& d = taps[s][k];
        if (run < d.length) break;  // the higher orders are longer still
        Vec3 sum = Vec3::Zero();
        for (int t = 0; t < d.length; t += s + 1)
          sum += d.tap[static_cast<std::size_t>(t)] *
                 value(j + 1 - static_cast<std::size_t>(d.length - t));
        squares[s][k] += sum.squaredNorm();
        ++count[s][k];
      }
  }
  // Each ladder's plateau: its first order whose next two agree with it.
  constexpr std::size_t kMinDifferences = 20;
  std::array<int, kLadderStrides> plateau{};
  std::array<double, kLadderStrides> level{};
  for (int s = 0; s < kLadderStrides; ++s) {
    plateau[s] = -1;
    if (count[s][kLadderOrders - 1] < kMinDifferences) return {};
    std::array<double, kLadderOrders> e{};
    for (int k = 0; k < kLadderOrders; ++k)
      e[k] = squares[s][k] / (3.0 * static_cast<double>(count[s][k]));
    const double n = static_cast<double>(count[s][kLadderOrders - 1]);
    auto agree = [&](int k) {
      return sameWhiteLevel(e[k], e[k + 1], taps[s][k], taps[s][k + 1], n);
    };
    for (int k = 0; k + 2 < kLadderOrders && plateau[s] < 0; ++k)
      if (agree(k) && agree(k + 1)) plateau[s] = k;
    if (plateau[s] < 0) return {};
    level[s] = e[plateau[s]];
  }
  const DifferenceTaps& a = taps[0][plateau[0]];
  const DifferenceTaps& b = taps[1][plateau[1]];
  const double n_b = static_cast<double>(count[1][plateau[1]]);
  if (!sameWhiteLevel(level[0], level[1], a, b, n_b)) return {};
  MotionNoise out;
  out.sigma = std::sqrt(level[0]);
  out.dof = 3.0 * static_cast<double>(count[0][plateau[0]]) / crossSquares(a, a);
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
