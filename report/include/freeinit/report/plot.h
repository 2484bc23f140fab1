// A small line plot rendered with OpenCV: what to draw and where comes from the core's
// plot layout (plot_layout.h: nice ticks, linear or log y, legend, margins), shared with
// the MRPT app's snapshot; this file holds the OpenCV drawing only. For the evaluation figures;
// not a general plotting library.
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

/// Draws the panel `spec` laid out with the evaluation figures' style over all of `img` (BGR).
void drawPanel(cv::Mat& img, const plot::PanelSpec& spec);

/// Panels laid out in a grid of `columns`, row by row (all panels the same size).
cv::Mat tile(const std::vector<cv::Mat>& panels, int columns);

/// Writes `image` as PNG atomically (temporary file + rename). Throws std::runtime_error.
void savePng(const std::string& path, const cv::Mat& image);

}  // namespace freeinit::report
