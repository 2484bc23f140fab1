// The layout of a 2-D plot over time, drawn by the one panel renderer (plot.h's drawPanel) for the
// MRPT app's velocity snapshot and for the evaluation figures. What is drawn and where is decided
// here, free of any drawing library: the axis limits and their "nice" ticks, the series (their
// colours, labels and the legend) and the placement of the plot area, title, legend and tick
// labels in normalized figure coordinates (x right, y down, both 0..1 across the figure). The
// renderer scales these by its image size.
#pragma once

#include <freeinit/types.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::plot {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb& a, const Rgb& c) {
    return a.r == c.r && a.g == c.g && a.b == c.b;
  }
};

inline constexpr Rgb kBlack{0, 0, 0};
inline constexpr Rgb kWhite{255, 255, 255};
inline constexpr Rgb kGrid{225, 225, 225};   ///< grid lines
inline constexpr Rgb kShade{255, 246, 214};  ///< a shaded x span (the initialization window)
inline constexpr Rgb kTruth = kBlack;        ///< ground truth, in every figure

/// The Okabe-Ito colour-blind-friendly palette, cyclic: blue, vermillion, bluish green, reddish
/// purple, orange, sky blue.
Rgb palette(std::size_t i);

/// The colour of vector component k (0, 1, 2 = x, y, z) in every figure: vermillion, bluish
/// green, blue, i.e. red/green/blue as axes are drawn, in the palette's shades.
Rgb componentColor(int k);

/// `a` moved a fraction `f` (0..1) towards `b`.
Rgb mix(const Rgb& a, const Rgb& b, double f);

/// About `target` ticks (the count nearest it) at multiples of 1, 2 or 5 times a power of ten
/// inside [lo, hi] (ends included when they fall on a tick). Empty when the interval is not finite
/// or lo > hi; {lo} when lo == hi.
std::vector<double> niceTicks(double lo, double hi, int target);

/// The powers of ten inside [lo, hi], lo > 0 (a log axis).
std::vector<double> decadeTicks(double lo, double hi);

/// A linear axis tick: as many decimals as the tick spacing `step` needs ("0.5", "10", "-0.25"
/// for 0.05 steps), never "-0".
std::string tickLabel(double value, double step);

struct Range {
  double lo = 0, hi = 1;
  double span() const { return hi - lo; }
  bool contains(double v) const { return v >= lo && v <= hi; }
};

struct Series {
  enum class Style { Line, Dashed, Markers };
  std::string label;  ///< legend text; empty: not in the legend
  std::vector<double> x, y;
  std::vector<double> sigma;  ///< empty, or one per point: a light band y +- sigma behind the line
  Rgb color = kBlack;
  Style style = Style::Line;
  int thickness = 2;  ///< [px] line width, or marker radius minus 2
};

/// A value marked with a filled square (the state's own value at the state time).
struct Mark {
  double x = 0, y = 0;
  Rgb color = kBlack;
};

struct AxisSpec {
  std::string label;
  double min = 0, max = 0;  ///< fixed limits when min < max, else taken from the data
  bool log = false;         ///< logarithmic (values <= 0 are left out of the limits)
  double pad = 0.05;        ///< auto linear limits: this fraction of the data span on each side
  double min_pad = 0;       ///< auto linear limits: at least this much on each side [axis unit]
  int ticks = 5;            ///< about this many ticks (linear)
  std::string unit;         ///< appended to each tick label (" s")
  bool tick_labels = true;  ///< false: ticks and grid only (a stacked panel over a shared axis)
};

/// What a panel shows.
struct PanelSpec {
  std::string title;
  std::optional<Rgb> title_color;  ///< default black
  AxisSpec x, y;
  std::vector<Series> series;   ///< drawn in this order (later over earlier)
  std::vector<Mark> marks;      ///< drawn over the series
  std::optional<Range> shade;   ///< an x span shaded behind everything
  std::vector<double> x_lines;  ///< vertical black lines (the state time)
};

/// A rectangle in normalized figure coordinates (y down).
struct Box {
  double x0 = 0, y0 = 0, x1 = 1, y1 = 1;
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
};

/// Where the parts of a panel go, as fractions of its cell. `reference_*` are the cell size [px]
/// these fractions were chosen at: text keeps its pixel size, so the legend and the title band
/// are sized in pixels of that reference.
struct PanelStyle {
  double left = 70.0 / 640, right = 15.0 / 640, bottom = 48.0 / 400;  ///< around the plot area
  double top = 12.0 / 400;                      ///< above the area (under the title and legend)
  double title_band = 24.0 / 400;               ///< added above for a title drawn above the area
  bool title_inside = false;                    ///< the title in the area's top-left corner instead
  double title_inset_x = 0, title_inset_y = 0;  ///< inside: the title's offset from that corner
  bool legend = true;                 ///< legend rows above the area for the labelled series
  double legend_row = 18.0 / 400;     ///< height of a legend row
  double legend_sample = 30.0 / 640;  ///< width of a legend entry's line sample
  double legend_text_gap = 6.0 / 640, legend_gap = 18.0 / 640;
};

/// The evaluation figures' panel (one plot per image, title and legend above the area).
PanelStyle figurePanelStyle();
/// The app snapshot's stacked panels: a thin frame, the title inside the area, no legend rows.
PanelStyle stackedPanelStyle();

struct Axis {
  Range range;
  bool log = false;
  std::vector<double> ticks;
  std::vector<std::string> labels;  ///< one per tick, or none (AxisSpec::tick_labels false)
  std::vector<double> minor;        ///< log axis: 2..9 times each decade, inside the range
  std::string label;
  /// The value's position along the axis, 0 at range.lo, 1 at range.hi (not clamped).
  double fraction(double v) const;
};

struct LegendEntry {
  std::size_t series = 0;  ///< index into PanelSpec::series
  double x = 0, y = 0;     ///< left end of the sample, vertical centre of the row
};

/// A panel laid out in its cell: everything in normalized figure coordinates.
struct PanelLayout {
  Box cell, area;
  Axis x, y;
  std::vector<LegendEntry> legend;
  /// Above the area: the title's baseline centre; inside: its top-left corner.
  double title_x = 0, title_y = 0;
  bool title_inside = false;
  double toX(double v) const { return area.x0 + x.fraction(v) * area.width(); }
  double toY(double v) const { return area.y1 - y.fraction(v) * area.height(); }
};

/// Width of `text` in normalized figure x units, as the renderer will draw it (legend packing).
using TextWidth = std::function<double(const std::string&)>;

/// The limits of one axis over the finite points of `series` (y: with +- sigma where given, and
/// the marks): fixed limits as given; linear: padded by AxisSpec::pad and min_pad, [0, 1]
/// without data, around the value when constant; log: out to whole decades, [0.01, 1] without
/// positive data.
Range axisRange(const AxisSpec& spec, const std::vector<Series>& series,
                const std::vector<Mark>& marks, bool y_axis);

/// Lays out `spec` in `cell` with `style`; `width_of` measures the legend labels.
PanelLayout layoutPanel(const PanelSpec& spec, const Box& cell, const PanelStyle& style,
                        const TextWidth& width_of);

/// `n` cells stacked vertically in `box`, `gap` apart (normalized).
std::vector<Box> stackCells(const Box& box, int n, double gap);

// The velocity-over-time panels of the app's snapshot and the evaluation figures.

/// A vector quantity over time: components per instant, optionally their standard deviations.
struct VectorTrack {
  std::vector<double> t;    ///< [s] on the plot's time axis
  std::vector<Vec3> value;  ///< one per t
  std::vector<Vec3> sigma;  ///< empty, or one per t
};

/// One panel of vector components (`axes`, each in componentColor) over time: the estimate as
/// thick lines with a +-1 sigma band, the truth as thin black dashed lines over it, per-frame
/// fits as markers, the state's value as squares at `state_t` with a vertical line there, and
/// the `window` shaded. The y limits hold all of it with 10 % of its span (at least `min_pad`)
/// either side. With one axis the title takes that axis's colour.
struct ComponentPanelData {
  std::string title, x_label, y_label;
  std::vector<int> axes{0, 1, 2};
  std::string estimate_name;  ///< legend: "<name>_x" per axis; empty: no legend entries
  VectorTrack estimate, truth, fits;
  std::string truth_label = "truth", fits_label;
  std::optional<double> state_t;  ///< [s] on the time axis
  std::optional<Vec3> state_value;
  std::optional<Range> window, time_range;  ///< time_range: fixed x limits
  double min_pad = 0;                       ///< [value unit] of the y limits
  std::string time_unit;                    ///< appended to the time tick labels
};
PanelSpec componentPanel(const ComponentPanelData& data);

}  // namespace freeinit::plot
