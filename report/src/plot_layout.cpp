#include <freeinit/report/plot_layout.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace freeinit::plot {

Rgb palette(std::size_t i) {
  static const Rgb kColors[] = {{0, 114, 178},   {213, 94, 0},  {0, 158, 115},
                                {204, 121, 167}, {230, 159, 0}, {86, 180, 233}};
  return kColors[i % (sizeof(kColors) / sizeof(kColors[0]))];
}

Rgb componentColor(int k) {
  static const std::size_t kIndex[3] = {1, 2, 0};  // vermillion, bluish green, blue
  return palette(kIndex[((k % 3) + 3) % 3]);
}

Rgb mix(const Rgb& a, const Rgb& b, double f) {
  f = std::clamp(f, 0.0, 1.0);
  auto ch = [f](std::uint8_t u, std::uint8_t v) {
    return static_cast<std::uint8_t>(std::lround((1 - f) * u + f * v));
  };
  return {ch(a.r, b.r), ch(a.g, b.g), ch(a.b, b.b)};
}

std::vector<double> niceTicks(double lo, double hi, int target) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) return {};
  if (lo == hi) return {lo};
  target = std::max(1, target);
  // Of the spacings 1, 2, 5, 10 times the power of ten below (hi - lo) / target, the one whose
  // count of ticks is nearest the target (the smaller spacing on a tie), two ticks at least.
  const double mag = std::pow(10.0, std::floor(std::log10((hi - lo) / target)));
  auto first = [&](double step) { return std::ceil(lo / step - 1e-9); };
  auto miss = [&](double step) {
    const double n = std::floor(hi / step + 1e-9) - first(step) + 1;
    return n < 2 ? 1e9 : std::abs(n - target);
  };
  double step = mag;
  for (double m : {2.0, 5.0, 10.0})
    if (miss(m * mag) < miss(step)) step = m * mag;
  std::vector<double> t;
  for (double k = first(step);; k += 1) {
    const double v = k * step;
    if (v > hi + step * 1e-9) break;
    t.push_back(std::abs(v) < step * 1e-9 ? 0.0 : v);
  }
  return t;
}

std::vector<double> decadeTicks(double lo, double hi) {
  std::vector<double> t;
  if (!(lo > 0) || !(hi >= lo) || !std::isfinite(hi)) return t;
  for (double e = std::ceil(std::log10(lo) - 1e-9); std::pow(10.0, e) <= hi * (1 + 1e-9); e += 1)
    t.push_back(std::pow(10.0, e));
  return t;
}

std::string tickLabel(double value, double step) {
  int decimals = 0;
  if (step > 0 && std::isfinite(step))
    decimals = std::clamp(static_cast<int>(std::ceil(-std::log10(step) - 1e-9)), 0, 12);
  if (std::abs(value) < 0.5 * std::pow(10.0, -decimals)) value = 0.0;  // never "-0"
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, value);
  return buf;
}

double Axis::fraction(double v) const {
  if (log) {
    const double l0 = std::log10(range.lo), l1 = std::log10(range.hi);
    return (std::log10(std::max(v, range.lo)) - l0) / (l1 - l0);
  }
  return (v - range.lo) / range.span();
}

Range axisRange(const AxisSpec& spec, const std::vector<Series>& series,
                const std::vector<Mark>& marks, bool y_axis) {
  if (spec.min < spec.max) return {spec.min, spec.max};
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  auto take = [&](double v) {
    if (!std::isfinite(v) || (spec.log && !(v > 0))) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  };
  for (const Series& s : series)
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      if (!y_axis) {
        take(s.x[i]);
        continue;
      }
      take(s.y[i]);
      if (i < s.sigma.size() && std::isfinite(s.sigma[i])) {
        take(s.y[i] - s.sigma[i]);
        take(s.y[i] + s.sigma[i]);
      }
    }
  for (const Mark& m : marks)
    if (std::isfinite(m.x) && std::isfinite(m.y)) take(y_axis ? m.y : m.x);

  if (spec.log) {
    if (!(lo <= hi)) return {0.01, 1};
    Range r{std::pow(10.0, std::floor(std::log10(lo))), std::pow(10.0, std::ceil(std::log10(hi)))};
    if (!(r.hi > r.lo)) r.hi = r.lo * 10;
    return r;
  }
  if (!(lo <= hi)) return {0, 1};
  double pad = std::max(spec.pad * (hi - lo), spec.min_pad);
  if (hi == lo && !(pad > 0)) pad = lo != 0 ? 0.05 * std::abs(lo) : 0.5;  // a constant: around it
  return {lo - pad, hi + pad};
}

PanelStyle figurePanelStyle() { return {}; }

PanelStyle stackedPanelStyle() {
  // Chosen at a cell of 1180 x 175 px (the snapshot's four panels in 1280 x 800).
  PanelStyle s;
  s.left = s.right = 0;
  s.top = s.bottom = 6.0 / 175;
  s.title_band = 0;
  s.title_inside = true;
  s.title_inset_x = 8.0 / 1180;
  s.title_inset_y = 4.0 / 175;
  s.legend = false;
  return s;
}

namespace {

Axis makeAxis(const AxisSpec& spec, const Range& range, int target) {
  Axis a;
  a.range = range;
  a.log = spec.log;
  a.label = spec.label;
  if (spec.log) {
    a.ticks = decadeTicks(range.lo, range.hi);
    for (double d : a.ticks) {
      char buf[32];
      std::snprintf(buf, sizeof(buf), "%g", d);
      a.labels.push_back(std::string(buf) + spec.unit);
    }
    for (double d = std::pow(10.0, std::floor(std::log10(range.lo))); d < range.hi; d *= 10)
      for (int k = 2; k <= 9; ++k)
        if (range.contains(d * k)) a.minor.push_back(d * k);
  } else {
    a.ticks = niceTicks(range.lo, range.hi, target);
    const double step = a.ticks.size() >= 2 ? a.ticks[1] - a.ticks[0] : range.span();
    for (double t : a.ticks) a.labels.push_back(tickLabel(t, step) + spec.unit);
  }
  if (!spec.tick_labels) a.labels.clear();
  return a;
}

}  // namespace

PanelLayout layoutPanel(const PanelSpec& spec, const Box& cell, const PanelStyle& style,
                        const TextWidth& width_of) {
  PanelLayout l;
  l.cell = cell;
  const double W = cell.width(), H = cell.height();
  const double left = cell.x0 + style.left * W, right = cell.x1 - style.right * W;
  double top = cell.y0 + style.top * H;
  if (!spec.title.empty() && !style.title_inside) top += style.title_band * H;

  // Legend: rows of entries between the title and the plot area, so it never hides data.
  if (style.legend) {
    const double row_h = style.legend_row * H;
    double x = left;
    int rows = 0;
    for (std::size_t i = 0; i < spec.series.size(); ++i) {
      const std::string& label = spec.series[i].label;
      if (label.empty()) continue;
      const double w =
          (style.legend_sample + style.legend_text_gap) * W + (width_of ? width_of(label) : 0.0);
      if (rows == 0 || (x + w > right && x > left)) {
        ++rows;
        x = left;
      }
      l.legend.push_back({i, x, top + row_h * (rows - 1) + row_h / 3});
      x += w + style.legend_gap * W;
    }
    if (rows > 0) top += row_h * rows + row_h / 3;
  }
  const double bottom = std::max(top + 1e-6, cell.y1 - style.bottom * H);
  l.area = {left, top, std::max(left + 1e-6, right), bottom};

  l.title_inside = style.title_inside;
  if (style.title_inside) {
    l.title_x = l.area.x0 + style.title_inset_x * W;
    l.title_y = l.area.y0 + style.title_inset_y * H;
  } else {
    l.title_x = cell.x0 + 0.5 * W;
    l.title_y = cell.y0 + style.title_band * H;
  }

  l.x = makeAxis(spec.x, axisRange(spec.x, spec.series, spec.marks, false), spec.x.ticks);
  l.y = makeAxis(spec.y, axisRange(spec.y, spec.series, spec.marks, true), spec.y.ticks);
  return l;
}

std::vector<Box> stackCells(const Box& box, int n, double gap) {
  std::vector<Box> cells;
  if (n < 1) return cells;
  const double h = (box.height() - gap * (n - 1)) / n;
  for (int k = 0; k < n; ++k) {
    const double y0 = box.y0 + k * (h + gap);
    cells.push_back({box.x0, y0, box.x1, y0 + h});
  }
  return cells;
}

PanelSpec componentPanel(const ComponentPanelData& d) {
  static const char* const kAxis[3] = {"x", "y", "z"};
  PanelSpec p;
  p.title = d.title;
  if (d.axes.size() == 1) p.title_color = componentColor(d.axes.front());
  p.x.label = d.x_label;
  p.x.pad = 0;
  p.x.ticks = 6;
  p.x.unit = d.time_unit;
  if (d.time_range) p.x.min = d.time_range->lo, p.x.max = d.time_range->hi;
  p.y.label = d.y_label;
  p.y.pad = 0.1;  // room for a title inside the area
  p.y.min_pad = d.min_pad;
  p.shade = d.window;
  if (d.state_t) p.x_lines.push_back(*d.state_t);

  auto series = [&](const VectorTrack& tr, int k, bool band) {
    Series s;
    for (std::size_t i = 0; i < tr.t.size() && i < tr.value.size(); ++i) {
      s.x.push_back(tr.t[i]);
      s.y.push_back(tr.value[i](k));
      if (band && i < tr.sigma.size()) s.sigma.push_back(tr.sigma[i](k));
    }
    return s;
  };
  // The estimates first, the truth drawn over them, the per-frame fits on top.
  for (int k : d.axes) {
    if (d.estimate.t.empty()) break;
    Series s = series(d.estimate, k, true);
    if (!d.estimate_name.empty()) s.label = d.estimate_name + "_" + kAxis[k];
    s.color = componentColor(k);
    s.thickness = 3;
    p.series.push_back(std::move(s));
  }
  bool first = true;
  for (int k : d.axes) {
    if (d.truth.t.empty()) break;
    Series s = series(d.truth, k, false);
    if (first) s.label = d.truth_label;
    s.color = kTruth;
    s.style = Series::Style::Dashed;
    s.thickness = 1;
    p.series.push_back(std::move(s));
    first = false;
  }
  first = true;
  for (int k : d.axes) {
    if (d.fits.t.empty()) break;
    Series s = series(d.fits, k, false);
    if (first) s.label = d.fits_label;
    s.color = componentColor(k);
    s.style = Series::Style::Markers;
    s.thickness = 3;
    p.series.push_back(std::move(s));
    first = false;
  }
  if (d.state_t && d.state_value)
    for (int k : d.axes) p.marks.push_back({*d.state_t, (*d.state_value)(k), componentColor(k)});
  return p;
}

}  // namespace freeinit::plot
