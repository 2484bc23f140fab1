// The one panel renderer: draws a plot layout (plot_layout.h: what is drawn and where) on an
// OpenCV image, for the evaluation figures and the MRPT app's velocity snapshot alike.
//
// One shared drawing rather than one renderer per output kind, because the kinds differ in two
// things only and both are parameters: the layout's style (the figures' single panel, title and
// legend above; the snapshot's stacked panels, title inside) and the font (OpenCV's Hershey font
// in the figures; in the snapshot MRPT's bitmap font of the rest of the app's PNGs, through
// PanelFont). An mrpt::img::CImage keeps its pixels in a cv::Mat (BGR, asCvMatRef()), so MRPT
// holds the snapshot's image and draws its text, and OpenCV draws the rest of both kinds: lines
// anti-aliased, 1 px frames, sigma bands as filled polygons, data clipped to the plot area, none
// of which CImage's own drawing calls offer.
//
// For the evaluation figures and the app's snapshot; not a general plotting library.
#pragma once

#include <freeinit/report/plot_layout.h>

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace freeinit::report {

using Series = plot::Series;

class Plot {
 public:
  std::string title, x_label, y_label;
  bool log_y = false;  ///< logarithmic y axis (values <= 0 are clipped to the lower limit)
  /// Axis limits; when min >= max they are taken from the data.
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;

  void add(Series s) { series_.push_back(std::move(s)); }
  /// The plot as a BGR image of width x height pixels.
  cv::Mat render(int width, int height) const;

 private:
  std::vector<Series> series_;
};

/// How a panel's text is measured and drawn: the one thing in which the renderer's outputs differ
/// besides the layout's style. Text is placed by its box: `size()`'s height is the one the panel
/// centres on a tick and keeps clear of the axes.
class PanelFont {
 public:
  enum class Role {
    Tick,   ///< tick labels and legend entries
    Label,  ///< axis labels
    Title
  };
  virtual ~PanelFont() = default;
  /// [px] width and height of `text`'s box.
  virtual cv::Size size(const std::string& text, Role role) const = 0;
  /// Draws `text` into `img` (BGR) with the top-left corner of its box at `top_left` [px].
  virtual void draw(cv::Mat& img, const std::string& text, cv::Point top_left, Role role,
                    const plot::Rgb& color) const = 0;
};

/// OpenCV's anti-aliased Hershey simplex font, the evaluation figures' (scale 0.45 for ticks and
/// legend, 0.5 for axis labels, 0.6 bold for the title). Its box is the height above the baseline.
class HersheyFont : public PanelFont {
 public:
  cv::Size size(const std::string& text, Role role) const override;
  void draw(cv::Mat& img, const std::string& text, cv::Point top_left, Role role,
            const plot::Rgb& color) const override;
};

/// Draws the panel `spec` laid out in `cell` (normalized coordinates of `img`, BGR) with `style`
/// and `font`: the shaded span, grid and ticks with their labels, the frame, the axis labels,
/// then the data clipped to the plot area (the sigma bands, the series in order, the vertical
/// lines, the marks), the legend and the title (inside the area: on a white box, over the data).
void drawPanel(cv::Mat& img, const plot::PanelSpec& spec, const plot::Box& cell,
               const plot::PanelStyle& style, const PanelFont& font);

/// The evaluation figures' panel: `spec` in the figure style over all of `img` (BGR), in the
/// Hershey font.
void drawPanel(cv::Mat& img, const plot::PanelSpec& spec);

/// Panels laid out in a grid of `columns`, row by row (all panels the same size).
cv::Mat tile(const std::vector<cv::Mat>& panels, int columns);

/// Writes `image` as PNG atomically (temporary file + rename). Throws std::runtime_error.
void savePng(const std::string& path, const cv::Mat& image);

}  // namespace freeinit::report
