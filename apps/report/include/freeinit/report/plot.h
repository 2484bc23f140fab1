// A small line plot rendered with OpenCV: axes with "nice" ticks (linear or log y), labels, a
// title, a legend, lines and markers. For the evaluation figures; not a general plotting library.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace freeinit::report {

struct Series {
  enum class Style { Line, Markers };
  std::string label;  ///< legend text; empty: not in the legend
  std::vector<double> x, y;
  cv::Scalar color{0, 0, 0};  ///< BGR
  Style style = Style::Line;
  int thickness = 2;  ///< [px] line width or marker radius
};

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

/// Distinct, colour-blind-friendly colours (BGR), indexed cyclically.
cv::Scalar paletteColor(std::size_t i);

/// Panels laid out in a grid of `columns`, row by row (all panels the same size).
cv::Mat tile(const std::vector<cv::Mat>& panels, int columns);

/// Writes `image` as PNG atomically (temporary file + rename). Throws std::runtime_error.
void savePng(const std::string& path, const cv::Mat& image);

}  // namespace freeinit::report
