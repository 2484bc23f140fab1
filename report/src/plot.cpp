#include <freeinit/io/atomic_file.h>
#include <freeinit/report/plot.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <ostream>
#include <stdexcept>

namespace freeinit::report {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kFontScale = 0.45;  // ticks and legend
const cv::Scalar kBlack(0, 0, 0), kWhite(255, 255, 255);

cv::Scalar bgr(const plot::Rgb& c) { return cv::Scalar(c.b, c.g, c.r); }

void text(cv::Mat& img, const std::string& s, cv::Point org, double scale, int thickness = 1,
          const cv::Scalar& color = kBlack) {
  cv::putText(img, s, org, kFont, scale, color, thickness, cv::LINE_AA);
}

cv::Size textSize(const std::string& s, double scale, int thickness = 1) {
  int baseline = 0;
  return cv::getTextSize(s, kFont, scale, thickness, &baseline);
}

/// A series' line through `pts`; dashed: every other run of four segments.
void drawLine(cv::Mat& img, const std::vector<cv::Point>& pts, const plot::Series& s) {
  if (pts.size() < 2) return;
  if (s.style == plot::Series::Style::Line) {
    cv::polylines(img, pts, false, bgr(s.color), s.thickness, cv::LINE_AA);
    return;
  }
  for (std::size_t i = 1; i < pts.size(); ++i)
    if ((i / 4) % 2 == 0) cv::line(img, pts[i - 1], pts[i], bgr(s.color), s.thickness, cv::LINE_AA);
}

}  // namespace

void drawPanel(cv::Mat& img, const plot::PanelSpec& spec) {
  using Style = plot::Series::Style;
  const double W = img.cols, H = img.rows;
  const plot::PanelLayout l =
      plot::layoutPanel(spec, {0, 0, 1, 1}, plot::figurePanelStyle(),
                        [&](const std::string& s) { return textSize(s, kFontScale).width / W; });
  auto at = [&](double nx, double ny) {
    return cv::Point(static_cast<int>(std::lround(nx * W)), static_cast<int>(std::lround(ny * H)));
  };
  const cv::Rect area(at(l.area.x0, l.area.y0), at(l.area.x1, l.area.y1));
  auto X = [&](double v) { return static_cast<int>(std::lround(l.toX(v) * W)); };
  auto Y = [&](double v) { return static_cast<int>(std::lround(l.toY(v) * H)); };

  if (spec.shade) {
    const int x0 = std::max(area.x, X(spec.shade->lo));
    const int x1 = std::min(area.x + area.width, X(spec.shade->hi));
    if (x1 > x0)
      cv::rectangle(img, cv::Rect(x0, area.y, x1 - x0, area.height), bgr(plot::kShade), cv::FILLED);
  }

  // Grid and ticks.
  for (std::size_t i = 0; i < l.x.ticks.size(); ++i) {
    const int x = X(l.x.ticks[i]);
    cv::line(img, {x, area.y}, {x, area.y + area.height}, bgr(plot::kGrid), 1);
    const std::string& s = l.x.labels[i];
    text(img, s, {x - textSize(s, kFontScale).width / 2, area.y + area.height + 18}, kFontScale);
  }
  for (std::size_t i = 0; i < l.y.ticks.size(); ++i) {
    const int y = Y(l.y.ticks[i]);
    cv::line(img, {area.x, y}, {area.x + area.width, y}, bgr(plot::kGrid), 1);
    const std::string& s = l.y.labels[i];
    const auto sz = textSize(s, kFontScale);
    text(img, s, {area.x - sz.width - 6, y + sz.height / 2}, kFontScale);
  }
  for (double m : l.y.minor) {  // log axis: short ticks at 2..9 times each decade
    const int y = Y(m);
    cv::line(img, {area.x, y}, {area.x + 5, y}, kBlack, 1);
  }
  cv::rectangle(img, area, kBlack, 1);

  // Labels and title.
  if (!l.x.label.empty()) {
    const auto sz = textSize(l.x.label, 0.5);
    text(img, l.x.label, {area.x + (area.width - sz.width) / 2, img.rows - 8}, 0.5);
  }
  if (!l.y.label.empty()) {
    const auto sz = textSize(l.y.label, 0.5);
    cv::Mat label(sz.height + 8, sz.width + 4, CV_8UC3, kWhite);
    text(label, l.y.label, {2, sz.height + 2}, 0.5);
    cv::rotate(label, label, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int y = std::max(0, area.y + (area.height - label.rows) / 2);
    if (y + label.rows <= img.rows) label.copyTo(img(cv::Rect(4, y, label.cols, label.rows)));
  }
  if (!spec.title.empty()) {
    const auto sz = textSize(spec.title, 0.6, 2);
    const cv::Point c = at(l.title_x, l.title_y);
    text(img, spec.title, {c.x - sz.width / 2, c.y}, 0.6, 2,
         bgr(spec.title_color.value_or(plot::kBlack)));
  }

  // Data, clipped to the plot area: the bands first, then the series in order, then the marks.
  cv::Mat canvas = img(area);
  auto point = [&](double x, double y) { return cv::Point(X(x) - area.x, Y(y) - area.y); };
  auto finite = [](double x, double y) { return std::isfinite(x) && std::isfinite(y); };
  for (const auto& s : spec.series) {
    std::vector<cv::Point> upper, lower;
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size() && i < s.sigma.size(); ++i) {
      if (!finite(s.x[i], s.y[i]) || !std::isfinite(s.sigma[i])) continue;
      upper.push_back(point(s.x[i], s.y[i] + s.sigma[i]));
      lower.push_back(point(s.x[i], s.y[i] - s.sigma[i]));
    }
    if (upper.size() < 2) continue;
    upper.insert(upper.end(), lower.rbegin(), lower.rend());
    cv::fillPoly(canvas, std::vector<std::vector<cv::Point>>{upper},
                 bgr(plot::mix(s.color, plot::kWhite, 0.9)), cv::LINE_AA);
  }
  for (const auto& s : spec.series) {
    std::vector<cv::Point> pts;
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i)
      if (finite(s.x[i], s.y[i])) pts.push_back(point(s.x[i], s.y[i]));
    if (s.style == Style::Markers) {
      for (const auto& p : pts)
        cv::circle(canvas, p, s.thickness + 2, bgr(s.color), -1, cv::LINE_AA);
    } else {
      drawLine(canvas, pts, s);
    }
  }
  for (double t : spec.x_lines)
    cv::line(canvas, point(t, l.y.range.lo), point(t, l.y.range.hi), kBlack, 1);
  for (const auto& m : spec.marks) {
    if (!finite(m.x, m.y)) continue;
    const cv::Point p = point(m.x, m.y);
    cv::rectangle(canvas, p - cv::Point(5, 5), p + cv::Point(5, 5), bgr(m.color), cv::FILLED);
    cv::rectangle(canvas, p - cv::Point(5, 5), p + cv::Point(5, 5), kBlack, 1);
  }

  for (const auto& e : l.legend) {
    const plot::Series& s = spec.series[e.series];
    const cv::Point p = at(e.x, e.y);
    if (s.style == Style::Markers) {
      cv::circle(img, p + cv::Point(15, 0), s.thickness + 2, bgr(s.color), -1, cv::LINE_AA);
    } else if (s.style == Style::Dashed) {
      for (int k = 0; k < 3; ++k)
        cv::line(img, p + cv::Point(12 * k, 0), p + cv::Point(12 * k + 6, 0), bgr(s.color),
                 s.thickness, cv::LINE_AA);
    } else {
      cv::line(img, p, p + cv::Point(30, 0), bgr(s.color), s.thickness, cv::LINE_AA);
    }
    text(img, s.label, p + cv::Point(36, 5), kFontScale);
  }
}

cv::Mat Plot::render(int width, int height) const {
  plot::PanelSpec spec;
  spec.title = title;
  spec.x.label = x_label;
  spec.x.min = x_min;
  spec.x.max = x_max;
  spec.x.pad = 0;  // the data's own time span
  spec.x.ticks = 6;
  spec.y.label = y_label;
  spec.y.min = y_min;
  spec.y.max = y_max;
  spec.y.log = log_y;
  spec.series = series_;
  cv::Mat img(height, width, CV_8UC3, kWhite);
  drawPanel(img, spec);
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
