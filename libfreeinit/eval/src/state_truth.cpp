#include <freeinit/eval/state_truth.h>

#include <algorithm>

namespace freeinit::eval {

std::optional<StateTruth> interpolateTruth(const std::vector<StateTruth>& samples, double t) {
  constexpr double kTolerance = 1e-6;  // [s]
  if (samples.empty() || t < samples.front().t - kTolerance || t > samples.back().t + kTolerance)
    return std::nullopt;
  const auto it = std::lower_bound(samples.begin(), samples.end(), t,
                                   [](const StateTruth& s, double x) { return s.t < x; });
  if (it == samples.begin()) return samples.front();
  if (it == samples.end()) return samples.back();
  const StateTruth& a = *(it - 1);
  const StateTruth& b = *it;
  const double u = (t - a.t) / (b.t - a.t);
  StateTruth s = a;
  s.t = t;
  s.q_wb = a.q_wb.slerp(u, b.q_wb);
  s.p_w = (1 - u) * a.p_w + u * b.p_w;
  s.v_w = (1 - u) * a.v_w + u * b.v_w;
  s.omega_b = (1 - u) * a.omega_b + u * b.omega_b;
  return s;
}

}  // namespace freeinit::eval
