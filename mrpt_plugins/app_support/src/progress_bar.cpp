#include <freeinit/app_support/progress_bar.h>

#include <algorithm>
#include <iomanip>
#include <ostream>
#include <utility>

namespace freeinit::app_support {
namespace {
constexpr int kWidth = 30;  // [characters] of the bar itself

int percentOf(std::size_t done, std::size_t total) {
  if (total == 0) return 100;
  return static_cast<int>(100.0 * static_cast<double>(std::min(done, total)) /
                          static_cast<double>(total));
}
}  // namespace

ProgressBar::ProgressBar(std::ostream& out, std::string label, std::string unit, bool terminal,
                         double scale)
    : out_(out),
      label_(std::move(label)),
      unit_(std::move(unit)),
      terminal_(terminal),
      scale_(scale) {}

void ProgressBar::update(std::size_t done, std::size_t total) {
  if (finished_) return;
  done_ = done;
  total_ = total;
  const int pct = percentOf(done, total);
  if (terminal_) {
    if (pct != shown_percent_) draw(done, total, "");
  } else if (pct / 25 > shown_percent_ / 25 && pct < 100) {
    draw(done, total, "");  // one line per started quarter; the last line comes from finish()
  }
}

void ProgressBar::finish(const std::string& note) {
  if (finished_) return;
  draw(done_, total_, note);
  if (terminal_) out_ << "\n";
  out_ << std::flush;
  finished_ = true;
}

void ProgressBar::draw(std::size_t done, std::size_t total, const std::string& note) {
  const int pct = percentOf(done, total);
  shown_percent_ = pct;
  const int n = pct * kWidth / 100;
  if (terminal_) out_ << "\r\033[K";  // back to the line start and clear it
  out_ << std::left << std::setw(12) << label_ << std::right << "["
       << std::string(static_cast<std::size_t>(n), '#')
       << std::string(static_cast<std::size_t>(kWidth - n), '.') << "] " << std::setw(3) << pct
       << "%  ";
  if (scale_ == 1.0) {
    out_ << done << "/" << total;
  } else {
    out_ << std::fixed << std::setprecision(1) << static_cast<double>(done) / scale_ << "/"
         << static_cast<double>(total) / scale_ << std::defaultfloat;
  }
  out_ << " " << unit_;
  if (!note.empty()) out_ << "  " << note;
  if (!terminal_) out_ << "\n";
  out_ << std::flush;
}

}  // namespace freeinit::app_support
