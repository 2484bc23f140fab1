// The plot layout shared by the snapshot and the evaluation figures: ticks, axis limits over the
// data (truth and bands included), degenerate data, the legend and the velocity panels.
#include <freeinit/report/plot_layout.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace freeinit::plot {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// The spacing is 1, 2 or 5 times a power of ten and every tick a whole multiple of it.
void expectNice(const std::vector<double>& t) {
  ASSERT_GE(t.size(), 2u);
  const double step = t[1] - t[0];
  const double mant = step / std::pow(10.0, std::floor(std::log10(step) + 1e-12));
  EXPECT_TRUE(std::abs(mant - 1) < 1e-9 || std::abs(mant - 2) < 1e-9 || std::abs(mant - 5) < 1e-9)
      << "step " << step;
  for (std::size_t i = 1; i < t.size(); ++i) EXPECT_NEAR(t[i] - t[i - 1], step, 1e-12 * step);
  for (double v : t) EXPECT_NEAR(v / step, std::round(v / step), 1e-9);
}

TEST(PlotLayout, NiceTicksAtOneTwoFiveInsideTheRange) {
  const std::vector<double> unit = niceTicks(0, 1, 5);
  ASSERT_EQ(unit.size(), 6u);
  for (std::size_t i = 0; i < unit.size(); ++i) EXPECT_NEAR(unit[i], 0.2 * i, 1e-15);

  // The snapshot's time axis (0.49 s window, 10 % either side) and a v_b.z panel.
  const std::vector<double> t = niceTicks(-0.049, 0.539, 6);
  ASSERT_EQ(t.size(), 6u);
  EXPECT_EQ(t.front(), 0.0);
  EXPECT_NEAR(t.back(), 0.5, 1e-12);
  expectNice(t);
  const std::vector<double> v = niceTicks(-0.44, 0.56, 5);
  expectNice(v);
  EXPECT_GE(v.front(), -0.44);
  EXPECT_LE(v.back(), 0.56);
  EXPECT_EQ(std::count(v.begin(), v.end(), 0.0), 1);  // zero exactly, not 1e-17

  const std::pair<double, double> ranges[] = {{-3.7, 1234}, {1e-5, 3e-5}, {16.8, 17.2}, {-1e6, -2}};
  for (const auto& [lo, hi] : ranges) {
    const std::vector<double> ts = niceTicks(lo, hi, 5);
    expectNice(ts);
    EXPECT_GE(ts.size(), 3u) << lo << " " << hi;
    EXPECT_LE(ts.size(), 11u) << lo << " " << hi;
    EXPECT_GE(ts.front(), lo - 1e-12 * (hi - lo));
    EXPECT_LE(ts.back(), hi + 1e-12 * (hi - lo));
  }
}

TEST(PlotLayout, NiceTicksOfDegenerateIntervals) {
  EXPECT_EQ(niceTicks(2.5, 2.5, 5), std::vector<double>{2.5});
  EXPECT_TRUE(niceTicks(1, 0, 5).empty());
  EXPECT_TRUE(niceTicks(kNaN, 1, 5).empty());
  EXPECT_TRUE(niceTicks(0, kInf, 5).empty());
  EXPECT_EQ(niceTicks(0, 1, 0).size(), 2u);  // target < 1 taken as 1
}

TEST(PlotLayout, DecadeTicksAndLabels) {
  const std::vector<double> d = decadeTicks(1e-4, 100);
  ASSERT_EQ(d.size(), 7u);
  EXPECT_NEAR(d.front(), 1e-4, 1e-18);
  EXPECT_NEAR(d.back(), 100, 1e-12);
  EXPECT_TRUE(decadeTicks(0, 10).empty());
  EXPECT_EQ(tickLabel(0.1, 0.1), "0.1");
  EXPECT_EQ(tickLabel(-1e-17, 0.1), "0.0");
  EXPECT_EQ(tickLabel(10, 5), "10");
  EXPECT_EQ(tickLabel(-0.25, 0.05), "-0.25");
  EXPECT_EQ(tickLabel(0.004, 0.002), "0.004");
}

Series line(std::vector<double> x, std::vector<double> y) {
  Series s;
  s.x = std::move(x);
  s.y = std::move(y);
  return s;
}

TEST(PlotLayout, LimitsCoverTheDataTheBandsAndTheMarks) {
  Series s = line({0, 1, 2}, {1, 3, 2});
  s.sigma = {0.5, 0.5, 2};  // 2 +- 2 reaches 0 and 4
  AxisSpec y;
  const Range r = axisRange(y, {s}, {{1.0, 5.0, kBlack}}, true);
  EXPECT_NEAR(r.lo, 0 - 0.05 * 5, 1e-12);
  EXPECT_NEAR(r.hi, 5 + 0.05 * 5, 1e-12);
  AxisSpec x;
  x.pad = 0;
  const Range rx = axisRange(x, {s}, {}, false);
  EXPECT_EQ(rx.lo, 0);
  EXPECT_EQ(rx.hi, 2);
  y.min = -1, y.max = 1;  // fixed limits win
  const Range fixed = axisRange(y, {s}, {}, true);
  EXPECT_EQ(fixed.lo, -1);
  EXPECT_EQ(fixed.hi, 1);
}

TEST(PlotLayout, DegenerateData) {
  AxisSpec lin, log;
  log.log = true;
  // No series, or series without points: the unit range, still with ticks.
  for (const std::vector<Series>& none : {std::vector<Series>{}, std::vector<Series>{Series{}}}) {
    const Range r = axisRange(lin, none, {}, true);
    EXPECT_EQ(r.lo, 0);
    EXPECT_EQ(r.hi, 1);
    const Range l = axisRange(log, none, {}, true);
    EXPECT_EQ(l.lo, 0.01);
    EXPECT_EQ(l.hi, 1);
  }
  // A constant: a range around it (relative, absolute at zero, or the given min_pad).
  const Range c = axisRange(lin, {line({0, 1}, {17, 17})}, {}, true);
  EXPECT_LT(c.lo, 17);
  EXPECT_GT(c.hi, 17);
  EXPECT_GE(niceTicks(c.lo, c.hi, 5).size(), 3u);
  const Range z = axisRange(lin, {line({0, 1}, {0, 0})}, {}, true);
  EXPECT_EQ(z.lo, -0.5);
  EXPECT_EQ(z.hi, 0.5);
  AxisSpec padded;
  padded.min_pad = 0.02;
  const Range p = axisRange(padded, {line({0, 1}, {0.003, 0.003})}, {}, true);
  EXPECT_NEAR(p.lo, -0.017, 1e-12);
  EXPECT_NEAR(p.hi, 0.023, 1e-12);
  const Range lc = axisRange(log, {line({0, 1}, {0.3, 0.3})}, {}, true);
  EXPECT_NEAR(lc.lo, 0.1, 1e-15);
  EXPECT_NEAR(lc.hi, 1, 1e-15);
  // NaN and infinities are left out, and so are values <= 0 on a log axis.
  const Series bad = line({0, 1, kNaN, 3, kInf}, {kNaN, 2, 100, 4, 100});
  const Range n = axisRange(lin, {bad}, {{kNaN, 50, kBlack}}, true);
  EXPECT_NEAR(n.lo, 2 - 0.1, 1e-12);
  EXPECT_NEAR(n.hi, 4 + 0.1, 1e-12);
  AxisSpec x;
  x.pad = 0;
  const Range nx = axisRange(x, {bad}, {}, false);
  EXPECT_EQ(nx.lo, 1);
  EXPECT_EQ(nx.hi, 3);
  const Range ln = axisRange(log, {line({0, 1, 2, 3}, {-1, 0, 3e-3, 40})}, {}, true);
  EXPECT_NEAR(ln.lo, 1e-3, 1e-18);
  EXPECT_NEAR(ln.hi, 100, 1e-12);
}

TEST(PlotLayout, FigurePanelAtItsReferenceSize) {
  // At 640 x 400 px the evaluation panel's margins are 70 / 15 px, the title band 24 px over a
  // 12 px top and 48 px under the area; one legend row of 18 px with 6 px under it.
  PanelSpec spec;
  spec.title = "t";
  spec.series = {line({0, 1}, {0, 1})};
  spec.series[0].label = "a";
  const PanelLayout l =
      layoutPanel(spec, {0, 0, 1, 1}, figurePanelStyle(), [](const std::string&) { return 0.1; });
  EXPECT_NEAR(l.area.x0 * 640, 70, 1e-9);
  EXPECT_NEAR(l.area.x1 * 640, 625, 1e-9);
  EXPECT_NEAR(l.area.y0 * 400, 36 + 18 + 6, 1e-9);
  EXPECT_NEAR(l.area.y1 * 400, 352, 1e-9);
  ASSERT_EQ(l.legend.size(), 1u);
  EXPECT_NEAR(l.legend[0].x * 640, 70, 1e-9);
  EXPECT_NEAR(l.legend[0].y * 400, 42, 1e-9);
  EXPECT_NEAR(l.title_x, 0.5, 1e-12);
  EXPECT_NEAR(l.title_y * 400, 24, 1e-9);
  EXPECT_NEAR(l.toX(l.x.range.lo), l.area.x0, 1e-12);
  EXPECT_NEAR(l.toY(l.y.range.hi), l.area.y0, 1e-12);  // y down
  ASSERT_EQ(l.x.ticks.size(), l.x.labels.size());
  ASSERT_EQ(l.y.ticks.size(), l.y.labels.size());
}

TEST(PlotLayout, AnAxisWithoutTickLabelsKeepsItsTicks) {
  // A stacked panel over a shared time axis: the grid at the same ticks, the labels only once.
  PanelSpec spec;
  spec.series = {line({0, 0.5}, {1, 2})};
  spec.x.unit = " s";
  const auto width = [](const std::string&) { return 0.0; };
  const PanelLayout labelled = layoutPanel(spec, {0, 0, 1, 1}, stackedPanelStyle(), width);
  spec.x.tick_labels = false;
  const PanelLayout bare = layoutPanel(spec, {0, 0, 1, 1}, stackedPanelStyle(), width);
  ASSERT_GE(labelled.x.ticks.size(), 2u);
  EXPECT_EQ(bare.x.ticks, labelled.x.ticks);
  EXPECT_EQ(labelled.x.labels.size(), labelled.x.ticks.size());
  EXPECT_EQ(labelled.x.labels.front(), "0.0 s");
  EXPECT_TRUE(bare.x.labels.empty());
  EXPECT_EQ(bare.y.labels.size(), bare.y.ticks.size());
}

TEST(PlotLayout, LegendWrapsIntoRowsInsideTheCell) {
  PanelSpec spec;
  for (int i = 0; i < 5; ++i) {
    spec.series.push_back(line({0, 1}, {0, 1}));
    spec.series.back().label = "entry";
  }
  spec.series.push_back(line({0, 1}, {0, 1}));  // unlabelled: not in the legend
  const Box cell{0.5, 0.5, 1.0, 1.0};
  const PanelLayout l =
      layoutPanel(spec, cell, figurePanelStyle(), [](const std::string&) { return 0.1; });
  ASSERT_EQ(l.legend.size(), 5u);
  double rows = 1;
  for (std::size_t i = 1; i < l.legend.size(); ++i)
    if (l.legend[i].y > l.legend[i - 1].y) ++rows;
  EXPECT_GE(rows, 2);
  for (const auto& e : l.legend) {
    EXPECT_GE(e.x, l.area.x0);
    EXPECT_LT(e.x, cell.x1);
    EXPECT_GT(e.y, cell.y0);
    EXPECT_LT(e.y, l.area.y0);  // above the data
  }
  const PanelLayout none = layoutPanel(spec, cell, stackedPanelStyle(), nullptr);
  EXPECT_TRUE(none.legend.empty());
  EXPECT_TRUE(none.title_inside);
}

TEST(PlotLayout, StackedCellsTileTheBox) {
  const Box box{0.1, 0.2, 0.9, 0.8};
  const std::vector<Box> c = stackCells(box, 4, 0.01);
  ASSERT_EQ(c.size(), 4u);
  EXPECT_DOUBLE_EQ(c.front().y0, box.y0);
  EXPECT_NEAR(c.back().y1, box.y1, 1e-12);
  for (std::size_t i = 1; i < c.size(); ++i) {
    EXPECT_NEAR(c[i].y0 - c[i - 1].y1, 0.01, 1e-12);
    EXPECT_NEAR(c[i].height(), c[0].height(), 1e-12);
  }
  EXPECT_TRUE(stackCells(box, 0, 0).empty());
}

TEST(PlotLayout, ComponentPanelShowsEstimateTruthFitsAndState) {
  ComponentPanelData d;
  d.estimate_name = "Free-Init v";
  d.fits_label = "per-frame Doppler LS";
  d.estimate.t = {0, 0.1, 0.2};
  d.estimate.value = {Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3)};
  d.estimate.sigma = {Vec3::Constant(0.1), Vec3::Constant(0.1), Vec3::Constant(0.1)};
  d.truth.t = {-0.05, 0.1, 0.25};  // beyond the estimate on both sides
  d.truth.value = {Vec3(0, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 5)};
  d.fits.t = {0.05, 0.15};
  d.fits.value = {Vec3(1, 2, 3), Vec3(1, 2, 3)};
  d.state_t = 0.2;
  d.state_value = Vec3(1, 2, 6);
  const PanelSpec p = componentPanel(d);
  ASSERT_EQ(p.series.size(), 9u);
  for (int k = 0; k < 3; ++k) {
    const Series& est = p.series[static_cast<std::size_t>(k)];
    EXPECT_EQ(est.label, std::string("Free-Init v_") + "xyz"[k]);
    EXPECT_TRUE(est.color == componentColor(k));
    EXPECT_EQ(est.sigma.size(), 3u);
    const Series& tr = p.series[static_cast<std::size_t>(3 + k)];
    EXPECT_EQ(tr.label, k == 0 ? "truth" : "");
    EXPECT_TRUE(tr.color == kTruth);
    EXPECT_EQ(tr.style, Series::Style::Dashed);
    const Series& fit = p.series[static_cast<std::size_t>(6 + k)];
    EXPECT_EQ(fit.style, Series::Style::Markers);
    EXPECT_TRUE(fit.color == componentColor(k));
  }
  ASSERT_EQ(p.marks.size(), 3u);
  EXPECT_FALSE(p.title_color.has_value());  // three axes: a black title
  ASSERT_EQ(p.x_lines.size(), 1u);

  // The limits hold the truth (0 .. 5, and -0.05 .. 0.25 s), the bands and the state (6).
  const PanelLayout l = layoutPanel(p, {0, 0, 1, 1}, figurePanelStyle(),
                                    [](const std::string& s) { return 0.01 * s.size(); });
  EXPECT_LE(l.y.range.lo, 0.0);
  EXPECT_GE(l.y.range.hi, 6.0);
  EXPECT_DOUBLE_EQ(l.x.range.lo, -0.05);
  EXPECT_DOUBLE_EQ(l.x.range.hi, 0.25);
  EXPECT_EQ(l.legend.size(), 5u);  // three estimates, the truth, the fits

  // One axis: its colour on the title; a fixed time range; no fits, no state: neither drawn.
  ComponentPanelData one = d;
  one.axes = {2};
  one.fits = {};
  one.state_value.reset();
  one.time_range = Range{0, 0.2};
  const PanelSpec q = componentPanel(one);
  ASSERT_TRUE(q.title_color.has_value());
  EXPECT_TRUE(*q.title_color == componentColor(2));
  EXPECT_EQ(q.series.size(), 2u);
  EXPECT_TRUE(q.marks.empty());
  const PanelLayout lq = layoutPanel(q, {0, 0, 1, 1}, stackedPanelStyle(), nullptr);
  EXPECT_EQ(lq.x.range.lo, 0);
  EXPECT_EQ(lq.x.range.hi, 0.2);
  EXPECT_LE(lq.y.range.lo, 3 - 0.1);
  EXPECT_GE(lq.y.range.hi, 5);

  // Nothing at all: an empty panel that still lays out.
  const PanelSpec e = componentPanel(ComponentPanelData{});
  EXPECT_TRUE(e.series.empty());
  const PanelLayout le = layoutPanel(e, {0, 0, 1, 1}, figurePanelStyle(), nullptr);
  EXPECT_FALSE(le.x.ticks.empty());
  EXPECT_FALSE(le.y.ticks.empty());
}

TEST(PlotLayout, ColoursAreDistinctAndXyzIsRedGreenBlue) {
  for (std::size_t i = 0; i < 6; ++i)
    for (std::size_t j = i + 1; j < 6; ++j) EXPECT_FALSE(palette(i) == palette(j));
  EXPECT_TRUE(palette(6) == palette(0));
  const Rgb x = componentColor(0), y = componentColor(1), z = componentColor(2);
  EXPECT_GT(x.r, std::max(x.g, x.b));
  EXPECT_GT(y.g, std::max(y.r, y.b));
  EXPECT_GT(z.b, std::max(z.r, z.g));
  EXPECT_TRUE(mix(kBlack, kWhite, 0.5) == (Rgb{128, 128, 128}));
  EXPECT_TRUE(mix(x, kWhite, 0) == x);
}

}  // namespace
}  // namespace freeinit::plot
