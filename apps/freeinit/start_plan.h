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

/// The most starts one run makes (--every, --starts): each writes a folder of outputs (about
/// 1.5 MB with the default [output]), staged until the run ends.
inline constexpr std::size_t kMaxStarts = 10000;
/// The most initializations open at once (--every, --starts): each holds its window's data
/// until its state is ready (a few MB at 60,000 points per cloud), so that starts closer than a
/// window keep several open. --every must be at least [window] duration / kMaxOpenStarts.
inline constexpr std::size_t kMaxOpenStarts = 32;

/// Why `every` [s] is refused with a window of `window` [s] (starts so close that more than
/// kMaxOpenStarts windows overlap), "" if it is not.
std::string everyProblem(double every, double window);
/// Why the starts `t` [s, increasing] are refused with a window of `window` [s] (more than
/// kMaxStarts, or more than kMaxOpenStarts within one window), "" if they are not. `source`
/// names them in the message (the starts file).
std::string startsProblem(const std::vector<double>& t, double window, const std::string& source);
/// The decimals of the start folders' names (startFolderName) for starts at these offsets [s]
/// (increasing): 3 (milliseconds) unless two of them would share a name, then as many as they
/// need, up to 9.
int folderDecimals(const std::vector<double>& offsets);

/// The starts of a run [UNIX s], in increasing order: one (possibly -inf: from the first
/// record), a list, or `first + k * every` for k < `limit`.
class StartPlan {
 public:
  static StartPlan single(double t) { return StartPlan({t}, 0); }
  static StartPlan list(std::vector<double> t) { return StartPlan(std::move(t), 0); }
  static StartPlan every(double t0, double step, std::size_t limit = kMaxStarts) {
    StartPlan p({t0}, step);
    p.limit_ = limit;
    return p;
  }

  /// The next start, none when the list is done (or `every` reached its limit).
  std::optional<double> peek() const {
    if (step_ > 0) {
      if (next_ >= limit_) return std::nullopt;
      return list_.front() + static_cast<double>(next_) * step_;
    }
    if (next_ < list_.size()) return list_[next_];
    return std::nullopt;
  }
  /// `every` stopped at its limit: the start it would make next [UNIX s].
  std::optional<double> beyondLimit() const {
    if (step_ > 0 && next_ >= limit_) return list_.front() + static_cast<double>(next_) * step_;
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
  std::size_t limit_ = 0;  ///< `every`: the number of starts
};

}  // namespace freeinit::apps
