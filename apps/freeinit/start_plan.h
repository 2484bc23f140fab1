// Where in a recording freeinit initializes (--start T, --every S, --starts FILE): start values
// as the user gives them, and the plan of starts a run walks through in increasing order.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace freeinit::apps {

/// Start values above this are UNIX stamps [s], others seconds after the first record (1e8 s is
/// in 1973: no recording is that long, no real stamp is that early).
inline constexpr double kUnixStampThreshold = 1e8;
/// [UNIX s] of a start value given `first` [UNIX s], the first record's stamp.
double startTime(double value, double first);
/// Start values from a file, one per line ('#' comments and blank lines ignored), in increasing
/// order. Throws InputError naming the file and line.
std::vector<double> readStartsFile(const std::string& path);

/// The starts of a run [UNIX s], in increasing order: one (possibly -inf: from the first
/// record), a list, or `first + k * every` without end.
class StartPlan {
 public:
  static StartPlan single(double t) { return StartPlan({t}, 0); }
  static StartPlan list(std::vector<double> t) { return StartPlan(std::move(t), 0); }
  static StartPlan every(double t0, double step) { return StartPlan({t0}, step); }

  /// The next start, none when the list is done.
  std::optional<double> peek() const {
    if (step_ > 0) return list_.front() + static_cast<double>(next_) * step_;
    if (next_ < list_.size()) return list_[next_];
    return std::nullopt;
  }
  /// The number of the next start, from 0.
  std::size_t index() const { return next_; }
  void pop() { ++next_; }
  /// The explicit starts not reached (none for `every`).
  std::vector<double> rest() const {
    if (step_ > 0) return {};
    return {list_.begin() + static_cast<std::ptrdiff_t>(next_), list_.end()};
  }

 private:
  StartPlan(std::vector<double> t, double step) : list_(std::move(t)), step_(step) {}
  std::vector<double> list_;
  double step_;
  std::size_t next_ = 0;
};

}  // namespace freeinit::apps
