// A text progress bar for the apps. On a terminal it redraws one line in place (carriage return)
// whenever the shown percentage changes; on a pipe or a log file it prints one line per quarter,
// so that logs stay readable.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <string>

namespace freeinit::app_support {

class ProgressBar {
 public:
  /// `label` prefixes the bar ("reading", "estimating"); `unit` names what is counted; counts are
  /// shown divided by `scale` (e.g. bytes as "MB" with scale 1e6, one decimal).
  ProgressBar(std::ostream& out, std::string label, std::string unit, bool terminal,
              double scale = 1.0);

  /// Shows `done` of `total` (total 0 counts as complete). Cheap when nothing visible changes.
  void update(std::size_t done, std::size_t total);

  /// Shows the last state with an optional note and ends the line. Idempotent.
  void finish(const std::string& note = "");

 private:
  void draw(std::size_t done, std::size_t total, const std::string& note);

  std::ostream& out_;
  std::string label_, unit_;
  bool terminal_;
  double scale_;
  int shown_percent_ = -1;
  std::size_t done_ = 0, total_ = 0;
  bool finished_ = false;
};

}  // namespace freeinit::app_support
