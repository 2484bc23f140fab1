#include <freeinit/atomic_file.h>
#include <freeinit/report/plot.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <ostream>
#include <stdexcept>

namespace freeinit::report {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
const cv::Scalar kBlack(0, 0, 0), kGrid(225, 225, 225), kWhite(255, 255, 255);

/// Ticks at 1, 2 or 5 times a power of ten, about `target` of them over [lo, hi].
std::vector<double> niceTicks(double lo, double hi, int target) {
  const double raw = (hi - lo) / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  std::vector<double> t;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step)
    t.push_back(std::abs(v) < step * 1e-9 ? 0.0 : v);
  return t;
}

std::string tickLabel(double v, bool log) {
  char buf[32];
  if (log) {
    std::snprintf(buf, sizeof(buf), "%g", v);
  } else {
    std::snprintf(buf, sizeof(buf), "%.4g", v);
  }
  return buf;
}

void text(cv::Mat& img, const std::string& s, cv::Point org, double scale, int thickness = 1,
          const cv::Scalar& color = kBlack) {
  cv::putText(img, s, org, kFont, scale, color, thickness, cv::LINE_AA);
}

cv::Size textSize(const std::string& s, double scale, int thickness = 1) {
  int baseline = 0;
  return cv::getTextSize(s, kFont, scale, thickness, &baseline);
}

}  // namespace

cv::Scalar paletteColor(std::size_t i) {
  // Okabe-Ito palette (BGR): blue, vermillion, bluish green, reddish purple, orange, sky blue.
  static const cv::Scalar kColors[] = {{178, 114, 0},   {0, 94, 213},  {115, 158, 0},
                                       {167, 121, 204}, {0, 159, 230}, {233, 180, 86}};
  return kColors[i % (sizeof(kColors) / sizeof(kColors[0]))];
}

cv::Mat Plot::render(int width, int height) const {
  cv::Mat img(height, width, CV_8UC3, kWhite);
  const double fs = 0.45;  // font scale of ticks and legend
  const int left = 70, right = 15, bottom = 48;
  int top = title.empty() ? 12 : 36;

  // Legend: rows of entries between the title and the plot area, so it never hides data.
  struct Entry {
    const Series* series;
    cv::Point at;  // left end of the sample
  };
  std::vector<Entry> legend;
  {
    const int sample = 30, gap = 18, row_h = 18;
    int x = left, rows = 0;
    for (const auto& s : series_) {
      if (s.label.empty()) continue;
      const int w = sample + 6 + textSize(s.label, fs).width;
      if (rows == 0 || (x + w > width - right && x > left)) {
        ++rows;
        x = left;
      }
      legend.push_back({&s, cv::Point(x, top + row_h * (rows - 1) + 6)});
      x += w + gap;
    }
    top += row_h * rows + (rows > 0 ? 6 : 0);
  }
  const cv::Rect area(left, top, width - left - right, height - top - bottom);

  // Limits from the data where not given.
  double x0 = x_min, x1 = x_max, y0 = y_min, y1 = y_max;
  const bool auto_x = !(x0 < x1), auto_y = !(y0 < y1);
  if (auto_x) x0 = std::numeric_limits<double>::infinity(), x1 = -x0;
  if (auto_y) y0 = std::numeric_limits<double>::infinity(), y1 = -y0;
  for (const auto& s : series_) {
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      if (auto_x) x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]);
      if (auto_y && (!log_y || s.y[i] > 0)) y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
    }
  }
  if (!(x0 < x1)) x0 = 0, x1 = 1;
  if (!(y0 <= y1)) y0 = log_y ? 0.01 : 0, y1 = 1;
  if (log_y) {
    if (auto_y)
      y0 = std::pow(10.0, std::floor(std::log10(y0))),
      y1 = std::pow(10.0, std::ceil(std::log10(y1)));
    if (!(y1 > y0)) y1 = y0 * 10;
  } else if (auto_y) {
    const double pad = 0.05 * std::max(y1 - y0, 1e-9);
    y0 -= pad, y1 += pad;
  }
  auto fy = [&](double y) {
    return log_y
               ? (std::log10(std::max(y, y0)) - std::log10(y0)) / (std::log10(y1) - std::log10(y0))
               : (y - y0) / (y1 - y0);
  };
  auto px = [&](double x, double y) {
    return cv::Point2d(area.x + (x - x0) / (x1 - x0) * area.width,
                       area.y + (1.0 - fy(y)) * area.height);
  };

  // Grid and ticks.
  for (double t : niceTicks(x0, x1, 6)) {
    const int x = static_cast<int>(std::lround(px(t, y0).x));
    cv::line(img, {x, area.y}, {x, area.y + area.height}, kGrid, 1);
    const std::string s = tickLabel(t, false);
    text(img, s, {x - textSize(s, fs).width / 2, area.y + area.height + 18}, fs);
  }
  std::vector<double> yt;
  if (log_y) {
    for (double d = y0; d <= y1 * (1 + 1e-9); d *= 10) yt.push_back(d);
  } else {
    yt = niceTicks(y0, y1, 5);
  }
  for (double t : yt) {
    const int y = static_cast<int>(std::lround(px(x0, t).y));
    cv::line(img, {area.x, y}, {area.x + area.width, y}, kGrid, 1);
    const std::string s = tickLabel(t, log_y);
    const auto sz = textSize(s, fs);
    text(img, s, {area.x - sz.width - 6, y + sz.height / 2}, fs);
  }
  if (log_y) {  // minor grid lines at 2..9 times each decade
    for (double d = y0; d < y1; d *= 10)
      for (int k = 2; k <= 9; ++k) {
        const int y = static_cast<int>(std::lround(px(x0, d * k).y));
        cv::line(img, {area.x, y}, {area.x + 5, y}, kBlack, 1);
      }
  }
  cv::rectangle(img, area, kBlack, 1);

  // Labels and title.
  if (!x_label.empty()) {
    const auto sz = textSize(x_label, 0.5);
    text(img, x_label, {area.x + (area.width - sz.width) / 2, height - 8}, 0.5);
  }
  if (!y_label.empty()) {
    const auto sz = textSize(y_label, 0.5);
    cv::Mat label(sz.height + 8, sz.width + 4, CV_8UC3, kWhite);
    text(label, y_label, {2, sz.height + 2}, 0.5);
    cv::rotate(label, label, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int y = std::max(0, area.y + (area.height - label.rows) / 2);
    if (y + label.rows <= img.rows) label.copyTo(img(cv::Rect(4, y, label.cols, label.rows)));
  }
  if (!title.empty()) {
    const auto sz = textSize(title, 0.6, 2);
    text(img, title, {(width - sz.width) / 2, 24}, 0.6, 2);
  }

  // Data, clipped to the plot area.
  cv::Mat canvas = img(area);
  const cv::Point2d offset(area.x, area.y);
  for (const auto& s : series_) {
    std::vector<cv::Point> pts;
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      const cv::Point2d p = px(s.x[i], s.y[i]) - offset;
      pts.emplace_back(static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y)));
    }
    if (s.style == Series::Style::Line) {
      if (pts.size() >= 2) cv::polylines(canvas, pts, false, s.color, s.thickness, cv::LINE_AA);
    } else {
      for (const auto& p : pts) cv::circle(canvas, p, s.thickness + 2, s.color, -1, cv::LINE_AA);
    }
  }

  for (const Entry& e : legend) {
    const Series& s = *e.series;
    if (s.style == Series::Style::Line)
      cv::line(img, e.at, e.at + cv::Point(30, 0), s.color, s.thickness, cv::LINE_AA);
    else
      cv::circle(img, e.at + cv::Point(15, 0), s.thickness + 2, s.color, -1, cv::LINE_AA);
    text(img, s.label, e.at + cv::Point(36, 5), fs);
  }
  return img;
}

cv::Mat tile(const std::vector<cv::Mat>& panels, int columns) {
  if (panels.empty() || columns < 1) throw std::invalid_argument("tile: no panels");
  const int rows = (static_cast<int>(panels.size()) + columns - 1) / columns;
  const cv::Size size = panels.front().size();
  cv::Mat out(rows * size.height, columns * size.width, CV_8UC3, kWhite);
  for (std::size_t i = 0; i < panels.size(); ++i) {
    if (panels[i].size() != size) throw std::invalid_argument("tile: panels differ in size");
    const int r = static_cast<int>(i) / columns, c = static_cast<int>(i) % columns;
    panels[i].copyTo(out(cv::Rect(c * size.width, r * size.height, size.width, size.height)));
  }
  return out;
}

void savePng(const std::string& path, const cv::Mat& image) {
  std::vector<uchar> png;
  if (!cv::imencode(".png", image, png)) throw std::runtime_error(path + ": PNG encoding failed");
  writeFileAtomically(
      path,
      [&](std::ostream& o) {
        o.write(reinterpret_cast<const char*>(png.data()),
                static_cast<std::streamsize>(png.size()));
      },
      true);
}

}  // namespace freeinit::report
