#include <freeinit/report/figures.h>
#include <freeinit/report/plot.h>

#include <algorithm>

namespace freeinit::report {
namespace {

const VelocityTrack* find(const std::vector<VelocityTrack>& tracks, const std::string& method) {
  for (const auto& t : tracks)
    if (t.method == method && !t.t.empty()) return &t;
  return nullptr;
}

/// One colour per method in every figure.
plot::Rgb methodColor(const std::string& method) {
  const char* const kMethods[] = {"free-init", "fast-lio2", "dlio", "doppler-ls"};
  for (std::size_t i = 0; i < 4; ++i)
    if (method == kMethods[i]) return plot::palette(i);
  return plot::palette(4);
}

std::string displayName(const std::string& method) {
  if (method == "free-init") return "Free-Init";
  if (method == "fast-lio2") return "FAST-LIO2 static mean";
  if (method == "dlio") return "DLIO static mean";
  if (method == "doppler-ls") return "per-frame Doppler LS";
  return method;
}

/// A plot over time spanning Free-Init's track (the window), or all tracks without it.
Plot timePlot(const std::string& title, const std::string& y_label,
              const std::vector<VelocityTrack>& tracks) {
  Plot p;
  p.title = title;
  p.x_label = "time since the recording start [s]";
  p.y_label = y_label;
  if (const VelocityTrack* fi = find(tracks, "free-init")) {
    p.x_min = fi->t.front();
    p.x_max = fi->t.back();
  }
  return p;
}

}  // namespace

cv::Mat velocityErrorPanel(const std::string& title, const std::vector<VelocityTrack>& tracks,
                           int width, int height) {
  Plot p = timePlot(title, "velocity error [m/s]", tracks);
  p.log_y = true;
  const bool both_static = find(tracks, "fast-lio2") && find(tracks, "dlio");
  for (const auto& tr : tracks) {
    const std::string& m = tr.method;
    if (tr.t.empty() || (both_static && m == "dlio")) continue;  // the same v = 0 line as FAST-LIO2
    Series s;
    s.label =
        (both_static && m == "fast-lio2") ? "FAST-LIO2 / DLIO static mean (v = 0)" : displayName(m);
    s.color = methodColor(m);
    s.style = tr.per_frame ? Series::Style::Markers : Series::Style::Line;
    s.thickness = tr.per_frame ? 3 : 2;
    for (std::size_t i = 0; i < tr.t.size(); ++i) {
      s.x.push_back(tr.t[i]);
      s.y.push_back((tr.v_est[i] - tr.v_true[i]).norm());
    }
    p.add(std::move(s));
  }
  // Errors span 0.1 mm/s (Free-Init with every point) .. tens of m/s (the static means): fixed
  // decades keep panels comparable.
  p.y_min = 1e-4;
  p.y_max = 100;
  return p.render(width, height);
}

cv::Mat velocityComponentsPanel(const std::string& title, const std::vector<VelocityTrack>& tracks,
                                int width, int height) {
  plot::ComponentPanelData d;
  d.title = title;
  d.x_label = "time since the recording start [s]";
  d.y_label = "body velocity [m/s]";
  d.estimate_name = "Free-Init v";
  if (const VelocityTrack* fi = find(tracks, "free-init")) {
    d.estimate = {fi->t, fi->v_est, {}};
    d.truth = {fi->t, fi->v_true, {}};
    d.time_range = plot::Range{fi->t.front(), fi->t.back()};
  }
  if (const VelocityTrack* ls = find(tracks, "doppler-ls")) d.fits = {ls->t, ls->v_est, {}};
  d.fits_label = "per-frame Doppler LS";
  cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  drawPanel(img, plot::componentPanel(d));
  return img;
}

}  // namespace freeinit::report
