#include <freeinit/io/atomic_file.h>
#include <freeinit/report/plot.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <ostream>
#include <stdexcept>
#include <utility>

namespace freeinit::report {
namespace {

constexpr int kHershey = cv::FONT_HERSHEY_SIMPLEX;
const cv::Scalar kBlack(0, 0, 0), kWhite(255, 255, 255);

cv::Scalar bgr(const plot::Rgb& c) { return cv::Scalar(c.b, c.g, c.r); }

/// The Hershey font's scale and stroke thickness per role.
std::pair<double, int> hersheyScale(PanelFont::Role role) {
  switch (role) {
    case PanelFont::Role::Label:
      return {0.5, 1};
    case PanelFont::Role::Title:
      return {0.6, 2};
    case PanelFont::Role::Tick:
      break;
  }
  return {0.45, 1};
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

cv::Size HersheyFont::size(const std::string& text, Role role) const {
  const auto [scale, thickness] = hersheyScale(role);
  int baseline = 0;
  return cv::getTextSize(text, kHershey, scale, thickness, &baseline);
}

void HersheyFont::draw(cv::Mat& img, const std::string& text, cv::Point top_left, Role role,
                       const plot::Rgb& color) const {
  const auto [scale, thickness] = hersheyScale(role);
  const cv::Point baseline_left(top_left.x, top_left.y + size(text, role).height);
  cv::putText(img, text, baseline_left, kHershey, scale, bgr(color), thickness, cv::LINE_AA);
}

void drawPanel(cv::Mat& img, const plot::PanelSpec& spec, const plot::Box& cell,
               const plot::PanelStyle& style, const PanelFont& font) {
  using Style = plot::Series::Style;
  using Role = PanelFont::Role;
  const double W = img.cols, H = img.rows;
  const plot::PanelLayout l = plot::layoutPanel(
      spec, cell, style, [&](const std::string& s) { return font.size(s, Role::Tick).width / W; });
  auto at = [&](double nx, double ny) {
    return cv::Point(static_cast<int>(std::lround(nx * W)), static_cast<int>(std::lround(ny * H)));
  };
  const cv::Rect box(at(cell.x0, cell.y0), at(cell.x1, cell.y1));
  const cv::Rect area(at(l.area.x0, l.area.y0), at(l.area.x1, l.area.y1));
  auto X = [&](double v) { return static_cast<int>(std::lround(l.toX(v) * W)); };
  auto Y = [&](double v) { return static_cast<int>(std::lround(l.toY(v) * H)); };
  const plot::Rgb black = plot::kBlack;

  if (spec.shade) {
    const int x0 = std::max(area.x, X(spec.shade->lo));
    const int x1 = std::min(area.x + area.width, X(spec.shade->hi));
    if (x1 > x0)
      cv::rectangle(img, cv::Rect(x0, area.y, x1 - x0, area.height), bgr(plot::kShade), cv::FILLED);
  }

  // Grid and ticks; a tick label 8 px under the area, or 6 px left of it, centred on its tick.
  for (std::size_t i = 0; i < l.x.ticks.size(); ++i) {
    const int x = X(l.x.ticks[i]);
    cv::line(img, {x, area.y}, {x, area.y + area.height}, bgr(plot::kGrid), 1);
    if (i >= l.x.labels.size()) continue;
    const std::string& s = l.x.labels[i];
    font.draw(img, s, {x - font.size(s, Role::Tick).width / 2, area.y + area.height + 8},
              Role::Tick, black);
  }
  for (std::size_t i = 0; i < l.y.ticks.size(); ++i) {
    const int y = Y(l.y.ticks[i]);
    cv::line(img, {area.x, y}, {area.x + area.width, y}, bgr(plot::kGrid), 1);
    if (i >= l.y.labels.size()) continue;
    const std::string& s = l.y.labels[i];
    const cv::Size sz = font.size(s, Role::Tick);
    font.draw(img, s, {area.x - sz.width - 6, y - sz.height / 2}, Role::Tick, black);
  }
  for (double m : l.y.minor) {  // log axis: short ticks at 2..9 times each decade
    const int y = Y(m);
    cv::line(img, {area.x, y}, {area.x + 5, y}, kBlack, 1);
  }
  cv::rectangle(img, area, kBlack, 1);

  // Axis labels: x centred under the area, 8 px above the cell's bottom; y turned a quarter to
  // the left, 4 px right of the cell's left edge.
  if (!l.x.label.empty()) {
    const cv::Size sz = font.size(l.x.label, Role::Label);
    font.draw(img, l.x.label,
              {area.x + (area.width - sz.width) / 2, box.y + box.height - 8 - sz.height},
              Role::Label, black);
  }
  if (!l.y.label.empty()) {
    const cv::Size sz = font.size(l.y.label, Role::Label);
    cv::Mat label(sz.height + 8, sz.width + 4, CV_8UC3, kWhite);
    font.draw(label, l.y.label, {2, 2}, Role::Label, black);
    cv::rotate(label, label, cv::ROTATE_90_COUNTERCLOCKWISE);
    const cv::Rect to(box.x + 4, std::max(box.y, area.y + (area.height - label.rows) / 2),
                      label.cols, label.rows);
    if ((to & box) == to) label.copyTo(img(to));
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
    font.draw(img, s.label, {p.x + 36, p.y - font.size(s.label, Role::Tick).height / 2}, Role::Tick,
              black);
  }

  // The title last: centred on its baseline above the area, or inside it at its top-left corner
  // on a white box over the data.
  if (!spec.title.empty()) {
    const cv::Size sz = font.size(spec.title, Role::Title);
    const cv::Point c = at(l.title_x, l.title_y);
    cv::Point top_left(c.x - sz.width / 2, c.y - sz.height);
    if (l.title_inside) {
      top_left = c;
      cv::rectangle(img, c - cv::Point(6, 2), c + cv::Point(sz.width + 4, sz.height + 1), kWhite,
                    cv::FILLED);
    }
    font.draw(img, spec.title, top_left, Role::Title, spec.title_color.value_or(plot::kBlack));
  }
}

void drawPanel(cv::Mat& img, const plot::PanelSpec& spec) {
  drawPanel(img, spec, {0, 0, 1, 1}, plot::figurePanelStyle(), HersheyFont());
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
