#include <freeinit/app_support/snapshots.h>
#include <freeinit/io/number_format.h>
#include <freeinit/report/plot.h>
#include <freeinit/report/plot_layout.h>
#include <mrpt/img/CImage.h>
#include <mrpt/opengl/CArrow.h>
#include <mrpt/opengl/CFBORender.h>
#include <mrpt/opengl/CGridPlaneXY.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloud.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CSphere.h>
#include <mrpt/opengl/stock_objects.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <stdexcept>

namespace freeinit::app_support {
namespace {

using mrpt::img::TColor;

// Encoded in memory and written by the atomic writer: its errors name the file and the system's
// reason (a full disk), which CImage::saveToFile's boolean does not.
void saveAtomically(const mrpt::img::CImage& img, const std::string& png) {
  report::savePng(png, img.asCvMatRef());
}

// Height colormap (viridis-like, our own control points): dark purple (low) -> teal -> yellow
// (high). It holds no red, so the rejected points (red) stay apart from the map.
TColor heightColor(float u) {
  static const float kStops[5][3] = {{0.27f, 0.00f, 0.33f},
                                     {0.23f, 0.32f, 0.55f},
                                     {0.13f, 0.57f, 0.55f},
                                     {0.37f, 0.79f, 0.38f},
                                     {0.99f, 0.91f, 0.15f}};
  u = std::clamp(u, 0.0f, 1.0f) * 4.0f;
  const int i = std::min(static_cast<int>(u), 3);
  const float f = u - static_cast<float>(i);
  auto ch = [&](int c) {
    return static_cast<std::uint8_t>(255.0f * ((1 - f) * kStops[i][c] + f * kStops[i + 1][c]));
  };
  return TColor(ch(0), ch(1), ch(2));
}

// Doppler colormap, u in [-1, 1]: blue (approaching) -> grey (0) -> magenta (receding); apart
// from the rejected points' red.
TColor dopplerColor(float u) {
  u = std::clamp(u, -1.0f, 1.0f);
  const float neg[3] = {40, 100, 255}, zero[3] = {150, 150, 160}, pos[3] = {235, 70, 215};
  const float* end = u < 0 ? neg : pos;
  const float f = std::abs(u);
  auto ch = [&](int c) { return static_cast<std::uint8_t>((1 - f) * zero[c] + f * end[c]); };
  return TColor(ch(0), ch(1), ch(2));
}

mrpt::poses::CPose3D toPose(const Quat& q, const Vec3& p) {
  const Mat3 R = q.toRotationMatrix();
  mrpt::math::CMatrixDouble33 Rm;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) Rm(i, j) = R(i, j);
  return mrpt::poses::CPose3D::FromRotationAndTranslation(
      Rm, mrpt::math::TVector3D(p.x(), p.y(), p.z()));
}

struct Range {
  float lo = 0, hi = 1;
};

// Robust range of the values (quantiles q and 1 - q).
Range quantileRange(std::vector<float> v, double q) {
  if (v.empty()) return {};
  auto at = [&](double f) {
    const auto k = static_cast<std::size_t>(f * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  };
  return {at(q), at(1 - q)};
}

const TColor kRejected(235, 40, 40);
const TColor kTrajectory(255, 150, 20);
const TColor kStart(255, 255, 255);
const TColor kGravityColour(120, 235, 255);

mrpt::img::TColorf colorf(const TColor& c) {
  return mrpt::img::TColorf(static_cast<float>(c.R) / 255.f, static_cast<float>(c.G) / 255.f,
                            static_cast<float>(c.B) / 255.f);
}

// What differs between the views.
struct ViewStyle {
  Range x, y;            ///< [m] grid extent
  float grid_z = 0;      ///< [m] grid height
  float grid_step = 1;   ///< [m] grid spacing
  float marker = 1;      ///< [m] sizes the start sphere, the axes and the gravity arrow
  float point_size = 2;  ///< [px] map points
  /// [m/s] > 0: the map colored by Doppler over +-doppler_scale instead of by height
  float doppler_scale = 0;
};

// A path as a dense chain of large points, one every `step` metres (GL line widths above 1 px are
// not portable to core profiles).
mrpt::opengl::CPointCloud::Ptr pathCloud(const std::vector<Vec3>& path, const TColor& color,
                                         float step, float size) {
  auto cloud = mrpt::opengl::CPointCloud::Create();
  cloud->setPointSize(size);
  cloud->setColor(colorf(color));
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Vec3 a = path[i - 1], b = path[i];
    const int n = std::max(1, static_cast<int>((b - a).norm() / step));
    for (int k = 0; k < n; ++k) {
      const Vec3 p = a + (b - a) * (static_cast<double>(k) / n);
      cloud->insertPoint(static_cast<float>(p.x()), static_cast<float>(p.y()),
                         static_cast<float>(p.z()));
    }
  }
  return cloud;
}

// One scene per view: the map colored by height over the range `z` (or by Doppler), the rejected
// points, the
// trajectory with body axes, the start, and the state's axes with gravity.
void buildScene(mrpt::opengl::COpenGLScene& scene, const InitResult& result, const Range& z,
                const ViewStyle& v) {
  using namespace mrpt::opengl;
  const float marker = v.marker, point_size = v.point_size;
  auto grid = CGridPlaneXY::Create(v.x.lo, v.x.hi, v.y.lo, v.y.hi, v.grid_z, v.grid_step);
  grid->setColor(0.45f, 0.45f, 0.5f, 0.5f);
  scene.insert(grid);

  auto cloud = CPointCloudColoured::Create();
  cloud->setPointSize(point_size);
  for (const auto& p : result.static_map) {
    const TColor c = v.doppler_scale > 0
                         ? dopplerColor(p.doppler / v.doppler_scale)
                         : heightColor((p.p_w.z() - z.lo) / std::max(z.hi - z.lo, 0.1f));
    cloud->push_back(p.p_w.x(), p.p_w.y(), p.p_w.z(), c.R / 255.f, c.G / 255.f, c.B / 255.f);
  }
  scene.insert(cloud);

  auto rejected = CPointCloud::Create();
  rejected->setPointSize(point_size + 1.0f);
  rejected->setColor(colorf(kRejected));
  for (const auto& p : result.rejected) rejected->insertPoint(p.p_w.x(), p.p_w.y(), p.p_w.z());
  scene.insert(rejected);

  // The trajectory, body axes every few poses, a sphere at the start.
  const auto& traj = result.trajectory;
  std::vector<Vec3> positions;
  for (const auto& p : traj) positions.push_back(p.p_w);
  scene.insert(pathCloud(positions, kTrajectory, 0.05f * marker, 7.0f));
  const std::size_t every = std::max<std::size_t>(1, traj.size() / 10);
  for (std::size_t i = 0; i < traj.size(); i += every) {
    auto axes = stock_objects::CornerXYZSimple(0.6f * marker, 2.0f);
    axes->setPose(toPose(traj[i].q_wb, traj[i].p_w));
    scene.insert(axes);
  }
  if (!traj.empty()) {
    auto start = CSphere::Create(0.15f * marker, 16);
    start->setColor(colorf(kStart));
    start->setLocation(traj.front().p_w.x(), traj.front().p_w.y(), traj.front().p_w.z());
    scene.insert(start);
  }

  // At the state: the body axes (arrows) and gravity.
  const auto& s = result.state;
  // MRPT 2.5.8's CornerXYZ(scale) makes the arrow head ratio 0.25 * scale, asserted <= 1: above
  // a scale of 4 (a window longer than ~27 m) the axes are drawn at 4 and scaled up.
  auto axes = stock_objects::CornerXYZ(std::min(marker, 4.0f));
  if (marker > 4.0f) axes->setScale(marker / 4.0f);
  axes->setPose(toPose(s.q_wb, s.p_w));
  scene.insert(axes);
  const Vec3 tip = s.p_w + 3.0 * marker * s.g_w.normalized();
  auto arrow = CArrow::Create(static_cast<float>(s.p_w.x()), static_cast<float>(s.p_w.y()),
                              static_cast<float>(s.p_w.z()), static_cast<float>(tip.x()),
                              static_cast<float>(tip.y()), static_cast<float>(tip.z()), 0.25f,
                              0.06f * marker, 0.18f * marker);
  arrow->setColor(colorf(kGravityColour));
  scene.insert(arrow);
  auto vp = scene.getViewport();
  vp->setCustomBackgroundColor(mrpt::img::TColorf(0.08f, 0.08f, 0.12f));
  vp->lightParameters().ambient = mrpt::img::TColorf(0.6f, 0.6f, 0.6f, 1.0f);  // vertical arrows
}

mrpt::img::CImage renderView(mrpt::opengl::COpenGLScene& scene, int w, int h, const Vec3& target,
                             float distance, float azimuth_deg, float elevation_deg) {
  mrpt::opengl::CFBORender render(static_cast<unsigned>(w), static_cast<unsigned>(h));
  auto& cam = render.getCamera(scene);
  cam.setPointingAt(static_cast<float>(target.x()), static_cast<float>(target.y()),
                    static_cast<float>(target.z()));
  cam.setZoomDistance(distance);
  cam.setAzimuthDegrees(azimuth_deg);
  cam.setElevationDegrees(elevation_deg);
  mrpt::img::CImage img;
  render.render_RGB(scene, img);
  return img;
}

void swatch(mrpt::img::CImage& img, int x, int y, const TColor& c, const std::string& text) {
  img.filledRectangle(x, y + 3, x + 14, y + 15, c);
  img.textOut(x + 20, y, text, TColor(230, 230, 230));
}

// The velocity plot's panels, in normalized coordinates of the image (at 1280 x 800: 80 px left
// for the tick labels, 70 px of header, 30 px under the panels for the time labels).
const plot::Box kVelocityPlotBox{80.0 / 1280, 70.0 / 800, 1260.0 / 1280, 770.0 / 800};

// The panels' text in MRPT's 9x15 bitmap font, the font of the header above them and of the
// app's other PNGs, drawn by a CImage over the panel image's pixels. Its box is the font's cell.
class BitmapFont : public report::PanelFont {
 public:
  cv::Size size(const std::string& text, Role) const override {
    // One cell per character: UTF-8 continuation bytes take none.
    const auto chars = std::count_if(text.begin(), text.end(), [](char c) {
      return (static_cast<unsigned char>(c) & 0xC0) != 0x80;
    });
    return {kCellWidth * static_cast<int>(chars), kCellHeight};
  }
  void draw(cv::Mat& img, const std::string& text, cv::Point top_left, Role,
            const plot::Rgb& color) const override {
    mrpt::img::CImage pixels(img, mrpt::img::SHALLOW_COPY);
    pixels.selectTextFont("9x15");
    pixels.textOut(top_left.x, top_left.y, text, TColor(color.r, color.g, color.b));
  }

 private:
  static constexpr int kCellWidth = 9, kCellHeight = 15;  // [px]
};

}  // namespace

void renderMapSnapshot(const std::string& png, const InitResult& result, int width, int height) {
  const auto& s = result.state;
  std::vector<float> xs, ys, zs, dopplers;
  for (const auto& p : result.static_map) {
    xs.push_back(p.p_w.x());
    ys.push_back(p.p_w.y());
    zs.push_back(p.p_w.z());
    dopplers.push_back(std::abs(p.doppler));
  }
  // The Doppler view's scale: 98 % of the returns within it, at least 0.1 m/s.
  const float doppler_scale = std::max(quantileRange(dopplers, 0.02).hi, 0.1f);
  const Range zr = quantileRange(zs, 0.02);
  Range xr = quantileRange(xs, 0.05), yr = quantileRange(ys, 0.05);
  const float extent = std::max({xr.hi - xr.lo, yr.hi - yr.lo, 4.0f});

  // The trajectory's box, for the close-up.
  Vec3 lo = s.p_w, hi = s.p_w;
  for (const auto& p : result.trajectory) {
    lo = lo.cwiseMin(p.p_w);
    hi = hi.cwiseMax(p.p_w);
  }
  const Vec3 traj_center = 0.5 * (lo + hi);
  const auto path_across = static_cast<float>((hi - lo).norm());
  const float traj_extent = std::max(path_across, 0.2f);  // [m] the close-up's scale

  const int header = 96;
  const int view_h = std::max(32, height - header);
  const int left_w = width * 3 / 5, right_w = width - left_w;
  const float cx = 0.5f * (xr.lo + xr.hi), cy = 0.5f * (yr.lo + yr.hi);
  const float px = static_cast<float>(s.p_w.x()), py = static_cast<float>(s.p_w.y());
  // Look from behind and above the state pose, towards the map's center.
  const float azimuth = static_cast<float>(std::atan2(py - cy, px - cx) * 180.0 / M_PI) + 25.0f;

  // Left the overview by height; right, above, the close-up of the trajectory, and below the
  // overview again by Doppler (what only these data have).
  const int closeup_h = view_h / 2, doppler_h = view_h - closeup_h;
  mrpt::img::CImage overview, closeup, by_doppler;
  for (const bool doppler : {false, true}) {
    mrpt::opengl::COpenGLScene scene;
    const float pad = 5.0f;
    ViewStyle v;
    v.x = {xr.lo - pad, xr.hi + pad};
    v.y = {yr.lo - pad, yr.hi + pad};
    v.grid_z = zr.lo;
    v.grid_step = 5.0f;
    v.marker = std::clamp(0.04f * extent, 0.3f, 2.0f);
    if (doppler) v.doppler_scale = doppler_scale;
    buildScene(scene, result, zr, v);
    const Vec3 target(px + 0.35 * (cx - px), py + 0.35 * (cy - py), s.p_w.z());
    (doppler ? by_doppler : overview) =
        renderView(scene, doppler ? right_w : left_w, doppler ? doppler_h : view_h, target,
                   std::clamp(0.7f * extent, 8.0f, 60.0f), azimuth, 30.0f);
  }
  {
    mrpt::opengl::COpenGLScene scene;
    // A 0.1 m grid just under the trajectory.
    const float r = 1.2f * traj_extent;
    const auto tcx = static_cast<float>(traj_center.x()), tcy = static_cast<float>(traj_center.y());
    ViewStyle v;
    v.x = {std::floor(10 * (tcx - r)) / 10, std::ceil(10 * (tcx + r)) / 10};
    v.y = {std::floor(10 * (tcy - r)) / 10, std::ceil(10 * (tcy + r)) / 10};
    v.grid_z = static_cast<float>(lo.z()) - 0.3f * traj_extent;
    v.grid_step = 0.1f;
    v.marker = 0.15f * traj_extent;
    buildScene(scene, result, zr, v);
    closeup =
        renderView(scene, right_w, closeup_h, traj_center, 3.0f * traj_extent, azimuth, 40.0f);
  }

  mrpt::img::CImage img(width, height, mrpt::img::CH_RGB);
  img.filledRectangle(0, 0, width - 1, height - 1, TColor(20, 20, 30));
  img.drawImage(0, header, overview);
  img.drawImage(left_w, header, closeup);
  img.drawImage(left_w, header + closeup_h, by_doppler);
  img.line(left_w, header, left_w, height - 1, TColor(120, 120, 140), 2);
  img.line(left_w, header + closeup_h, width - 1, header + closeup_h, TColor(120, 120, 140), 2);

  const Vec3 g_b = s.g_b();
  const double tilt_deg =
      std::acos(std::clamp(-g_b.z() / std::max(g_b.norm(), 1e-9), -1.0, 1.0)) * 180.0 / M_PI;
  const TColor white(255, 255, 255), grey(190, 190, 200);
  img.selectTextFont("10x20");
  img.textOut(12, 8,
              "Free-Init static map   status: " + std::string(toString(s.status)) +
                  "   speed at state " + formatFixed(s.v_w.norm(), 3) + " m/s   gravity tilt " +
                  formatFixed(tilt_deg, 2) + " deg",
              white);
  img.selectTextFont("9x15");
  double window = 0;
  if (!result.trajectory.empty()) window = s.timestamp - result.trajectory.front().t;
  img.textOut(12, 32,
              std::to_string(result.static_map.size()) + " static points, " +
                  std::to_string(result.rejected.size()) + " rejected; window " +
                  formatFixed(window, 2) + " s; path " + formatFixed(path_across, 2) +
                  " m across; |b_g| " + formatFixed(s.b_g.norm(), 4) + " rad/s, |b_a| " +
                  formatFixed(s.b_a.norm(), 3) + " m/s^2",
              grey);
  int x = 12;
  const int y = 58;
  for (int k = 0; k < 6; ++k)
    img.filledRectangle(x + 4 * k, y + 3, x + 4 * k + 3, y + 15, heightColor(k / 5.0f));
  img.textOut(x + 30, y,
              "map by height " + formatFixed(zr.lo, 1) + ".." + formatFixed(zr.hi, 1) + " m",
              TColor(230, 230, 230));
  x += 270;
  swatch(img, x, y, kRejected, "rejected (dynamic/outlier)");
  x += 260;
  swatch(img, x, y, kTrajectory, "trajectory, axes");
  x += 175;
  swatch(img, x, y, kStart, "start");
  x += 70;
  swatch(img, x, y, kGravityColour, "gravity");
  img.textOut(12, header + 6, "overview (grid 5 m)", white);
  img.textOut(left_w + 10, header + 6, "close-up of the trajectory (grid 0.1 m)", white);
  const int dy = header + closeup_h + 6;
  img.textOut(left_w + 10, dy, "the overview by Doppler", white);
  for (int k = 0; k <= 10; ++k)
    img.filledRectangle(left_w + 10 + 4 * k, dy + 23, left_w + 13 + 4 * k, dy + 35,
                        dopplerColor(static_cast<float>(k - 5) / 5.0f));
  img.textOut(left_w + 66, dy + 20,
              "-" + formatFixed(doppler_scale, 2) + ".." + formatFixed(doppler_scale, 2) +
                  " m/s, approaching..receding",
              TColor(230, 230, 230));
  saveAtomically(img, png);
}

void renderVelocityPlot(const std::string& png, const InitResult& result,
                        const std::vector<TruthSample>& truth, int width, int height) {
  const auto& v = result.velocities;
  if (v.empty()) throw std::runtime_error(png + ": no velocity samples to plot");
  const auto& s = result.state;
  // The window runs from the first velocimeter sample to the state; the plot adds 10 % on each
  // side where the ground truth is known, so that the window stands out.
  const double w0 = v.front().t, w1 = std::max({v.back().t, s.timestamp, w0 + 1e-3});
  const double pad = truth.empty() ? 0.0 : 0.1 * (w1 - w0);
  const double t0 = w0 - pad, t1 = w1 + pad;

  // On the plot's time axis, seconds since the window start: the velocimeter's estimates and the
  // ground truth (body velocity and gyro bias) over the plotted span.
  plot::VectorTrack est_v, est_bg, true_v, true_bg;
  for (const auto& x : v) {
    est_v.t.push_back(x.t - w0);
    est_v.value.push_back(x.v_b);
    est_v.sigma.push_back(x.sigma_v_b);
    est_bg.t.push_back(x.t - w0);
    est_bg.value.push_back(x.b_g);
  }
  for (const auto& g : truth) {
    if (g.t < t0 || g.t > t1) continue;
    true_v.t.push_back(g.t - w0);
    true_v.value.push_back(g.q_wb.conjugate() * g.v_w);
    true_bg.t.push_back(g.t - w0);
    true_bg.value.push_back(g.b_g);
  }
  std::optional<TruthErrors> err;
  if (!truth.empty() && s.ok()) {
    try {
      err = compareWithTruth(s, truth);
    } catch (const std::exception&) {
      err.reset();  // the state time is outside the truth: no error line
    }
  }

  mrpt::img::CImage img(width, height, mrpt::img::CH_RGB);
  img.filledRectangle(0, 0, width - 1, height - 1, TColor(255, 255, 255));
  const TColor black(0, 0, 0);
  const int left = static_cast<int>(std::lround(kVelocityPlotBox.x0 * width));
  img.selectTextFont("10x20");
  img.textOut(left, 6, "Free-Init velocimeter over the initialization window", black);
  img.selectTextFont("9x15");
  std::string sub = "solid: estimate (light band: +/- 1 sigma)";
  if (!truth.empty()) sub += "   black dashed: ground truth";
  sub += "   shaded: window   |: state time, squares: state";
  img.textOut(left, 30, sub, black);
  if (err)
    img.textOut(left, 48,
                "at the state: |v_b error| " + formatFixed(err->velocity, 3) +
                    " m/s, gravity error " + formatFixed(err->gravity_deg, 2) +
                    " deg, |b_g error| " + formatFixed(err->gyro_bias, 4) + " rad/s",
                black);

  // Four panels stacked under the header: v_b per axis with its band, then the gyro bias.
  auto data = [&](const std::string& title, std::vector<int> axes) {
    plot::ComponentPanelData d;
    d.title = title;
    d.axes = std::move(axes);
    d.state_t = s.timestamp - w0;
    d.window = plot::Range{0.0, s.timestamp - w0};
    d.time_range = plot::Range{t0 - w0, t1 - w0};
    d.min_pad = 0.02;
    d.time_unit = " s";
    return d;
  };
  const char* names[3] = {"v_b.x [m/s]", "v_b.y [m/s]", "v_b.z [m/s]"};
  std::vector<plot::PanelSpec> panels;
  for (int a = 0; a < 3; ++a) {
    plot::ComponentPanelData d = data(names[a], {a});
    d.estimate = est_v;
    d.truth = true_v;
    if (s.ok()) d.state_value = s.v_b();
    panels.push_back(plot::componentPanel(d));
  }
  {
    plot::ComponentPanelData d =
        data("gyro bias x y z [rad/s]: velocimeter (lines), state (squares)", {0, 1, 2});
    d.estimate = est_bg;
    d.truth = true_bg;
    if (s.ok()) d.state_value = s.b_g;
    panels.push_back(plot::componentPanel(d));
  }
  // One time axis, labelled under the bottom panel.
  for (std::size_t k = 0; k + 1 < panels.size(); ++k) panels[k].x.tick_labels = false;
  const auto cells = plot::stackCells(kVelocityPlotBox, static_cast<int>(panels.size()), 0.0);
  for (std::size_t k = 0; k < panels.size(); ++k)
    report::drawPanel(img.asCvMatRef(), panels[k], cells[k], plot::stackedPanelStyle(),
                      BitmapFont());
  saveAtomically(img, png);
}

}  // namespace freeinit::app_support

namespace freeinit::app_support {

void renderTopViewPanels(const std::string& png, const std::string& title,
                         const std::vector<TopViewPanel>& panels, int width, int height) {
  using namespace mrpt::opengl;
  const int header = 40;
  const int n = std::max<int>(1, static_cast<int>(panels.size()));
  const int panel_h = std::max(32, (height - header) / n);
  mrpt::img::CImage img(width, height, mrpt::img::CH_RGB);
  img.filledRectangle(0, 0, width - 1, height - 1, TColor(20, 20, 30));
  const TColor white(255, 255, 255), map_grey(150, 150, 160);
  for (int i = 0; i < static_cast<int>(panels.size()); ++i) {
    const TopViewPanel& p = panels[static_cast<std::size_t>(i)];
    // Fit the view to the true path (and the estimate), with a margin.
    Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
    for (const auto* path : {&p.truth, &p.path})
      for (const Vec3& q : *path) {
        lo = lo.cwiseMin(q.head<2>());
        hi = hi.cwiseMax(q.head<2>());
      }
    if (!(hi.x() >= lo.x())) lo = hi = Eigen::Vector2d::Zero();
    const Eigen::Vector2d c = 0.5 * (lo + hi);
    const double aspect = static_cast<double>(width) / panel_h;
    // Orthographic: MRPT 2.5.8 shows a height of half the zoom distance.
    const double visible_h =
        std::max({(hi.y() - lo.y()) + 16.0, (hi.x() - lo.x() + 16.0) / aspect});
    COpenGLScene scene;
    auto vp = scene.getViewport();
    vp->setCustomBackgroundColor(mrpt::img::TColorf(0.08f, 0.08f, 0.12f));
    auto grid = CGridPlaneXY::Create(static_cast<float>(c.x() - visible_h * aspect),
                                     static_cast<float>(c.x() + visible_h * aspect),
                                     static_cast<float>(c.y() - visible_h),
                                     static_cast<float>(c.y() + visible_h), -0.1f, 10.0f);
    grid->setColor(0.35f, 0.35f, 0.4f, 0.5f);
    scene.insert(grid);
    auto map = CPointCloud::Create();
    map->setPointSize(2.0f);
    map->setColor(colorf(map_grey));
    for (std::size_t k = 0; k < p.map_x.size() && k < p.map_y.size(); ++k)
      map->insertPoint(p.map_x[k], p.map_y[k], 0.0f);
    scene.insert(map);
    const float step = static_cast<float>(visible_h / panel_h);  // about one point per pixel
    // The truth wide, the estimate narrow over it (inserted first and at a lower z: that is the
    // order MRPT 2.5.8's orthographic top view draws over the truth).
    std::vector<Vec3> path = p.path;
    for (auto& q : path) q.z() = 0.0;
    std::vector<Vec3> truth = p.truth;
    for (auto& q : truth) q.z() = -0.5;
    scene.insert(pathCloud(path, kTrajectory, step, 4.0f));
    scene.insert(pathCloud(truth, white, step, 9.0f));
    CFBORender render(static_cast<unsigned>(width), static_cast<unsigned>(panel_h));
    auto& cam = render.getCamera(scene);
    cam.setOrthogonal(true);
    cam.setPointingAt(static_cast<float>(c.x()), static_cast<float>(c.y()), 0.0f);
    cam.setZoomDistance(static_cast<float>(2.0 * visible_h));
    cam.setAzimuthDegrees(-90.0f);
    cam.setElevationDegrees(90.0f);
    mrpt::img::CImage view;
    render.render_RGB(scene, view);
    const int y0 = header + i * panel_h;
    img.drawImage(0, y0, view);
    img.line(0, y0, width - 1, y0, TColor(120, 120, 140), 2);
    img.selectTextFont("9x15");
    img.textOut(10, y0 + 6, p.title + "   (grid 10 m)", white);
  }
  img.selectTextFont("10x20");
  img.textOut(12, 10, title, white);
  img.selectTextFont("9x15");
  const int x = width - 420;
  if (std::any_of(panels.begin(), panels.end(), [](const auto& p) { return !p.truth.empty(); }))
    swatch(img, x, 12, white, "ground truth");
  swatch(img, x + 140, 12, kTrajectory, "icp-slam path");
  swatch(img, x + 290, 12, map_grey, "icp-slam map");
  saveAtomically(img, png);
}

}  // namespace freeinit::app_support
