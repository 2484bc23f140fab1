#include <freeinit/mrpt/snapshots.h>
#include <mrpt/img/CImage.h>
#include <mrpt/opengl/CArrow.h>
#include <mrpt/opengl/CFBORender.h>
#include <mrpt/opengl/CGridPlaneXY.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloud.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/stock_objects.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace freeinit::mrpt_glue {
namespace {

using mrpt::img::TColor;

void saveAtomically(const mrpt::img::CImage& img, const std::string& png) {
  const std::string tmp = png + ".tmp.png";  // the extension selects the format
  if (!img.saveToFile(tmp)) throw std::runtime_error(png + ": cannot write the image");
  std::error_code ec;
  std::filesystem::rename(tmp, png, ec);
  if (ec) throw std::runtime_error(png + ": " + ec.message());
}

std::string num(double x, int prec = 3) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(prec) << x;
  return os.str();
}

// Height colormap: blue (low) -> cyan -> yellow (high).
void heightColor(float u, float& r, float& g, float& b) {
  u = std::clamp(u, 0.0f, 1.0f);
  r = u;
  g = 0.4f + 0.6f * u;
  b = 1.0f - 0.8f * u;
}

}  // namespace

void renderMapSnapshot(const std::string& png, const InitResult& result, int width, int height) {
  mrpt::opengl::COpenGLScene scene;

  // Extent of what is shown, robust to far outliers (5-95 % quantiles per axis).
  std::vector<float> xs, ys, zs;
  for (const auto& p : result.static_map) {
    xs.push_back(p.p_w.x());
    ys.push_back(p.p_w.y());
    zs.push_back(p.p_w.z());
  }
  auto quantile = [](std::vector<float> v, double q) {
    if (v.empty()) return 0.0f;
    const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  };
  const float x0 = quantile(xs, 0.05), x1 = quantile(xs, 0.95);
  const float y0 = quantile(ys, 0.05), y1 = quantile(ys, 0.95);
  const float z0 = quantile(zs, 0.02), z1 = quantile(zs, 0.98);
  const float extent = std::max({x1 - x0, y1 - y0, 4.0f});

  auto grid = mrpt::opengl::CGridPlaneXY::Create(x0 - 5, x1 + 5, y0 - 5, y1 + 5, z0, 5);
  grid->setColor(0.35f, 0.35f, 0.35f, 0.6f);
  scene.insert(grid);

  auto cloud = mrpt::opengl::CPointCloudColoured::Create();
  cloud->setPointSize(2.0f);
  for (const auto& p : result.static_map) {
    float r, g, b;
    heightColor((p.p_w.z() - z0) / std::max(z1 - z0, 0.1f), r, g, b);
    cloud->push_back(p.p_w.x(), p.p_w.y(), p.p_w.z(), r, g, b);
  }
  scene.insert(cloud);

  auto rejected = mrpt::opengl::CPointCloud::Create();
  rejected->setPointSize(3.0f);
  rejected->setColor(1.0f, 0.1f, 0.1f);
  for (const auto& p : result.rejected) rejected->insertPoint(p.p_w.x(), p.p_w.y(), p.p_w.z());
  scene.insert(rejected);

  auto traj = mrpt::opengl::CSetOfLines::Create();
  traj->setLineWidth(6.0f);
  traj->setColor(0.1f, 1.0f, 0.2f);
  for (std::size_t i = 1; i < result.trajectory.size(); ++i) {
    const auto& a = result.trajectory[i - 1].p_w;
    const auto& b = result.trajectory[i].p_w;
    traj->appendLine(a.x(), a.y(), a.z(), b.x(), b.y(), b.z());
  }
  scene.insert(traj);

  // Body axes at the start and at the state, gravity arrow (2 m along g) at the state.
  const Vec3 p_end = result.state.p_w;
  auto axes0 = mrpt::opengl::stock_objects::CornerXYZ(1.0f);
  scene.insert(axes0);
  auto axes1 = mrpt::opengl::stock_objects::CornerXYZ(1.0f);
  const Mat3 R = result.state.q_wb.toRotationMatrix();
  mrpt::math::CMatrixDouble33 Rm;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) Rm(i, j) = R(i, j);
  axes1->setPose(mrpt::poses::CPose3D::FromRotationAndTranslation(
      Rm, mrpt::math::TVector3D(p_end.x(), p_end.y(), p_end.z())));
  scene.insert(axes1);
  const Vec3 tip = p_end + 3.0 * result.state.g_w.normalized();
  auto arrow = mrpt::opengl::CArrow::Create(
      static_cast<float>(p_end.x()), static_cast<float>(p_end.y()), static_cast<float>(p_end.z()),
      static_cast<float>(tip.x()), static_cast<float>(tip.y()), static_cast<float>(tip.z()), 0.25f,
      0.08f, 0.25f);
  arrow->setColor(0.3f, 0.6f, 1.0f);
  scene.insert(arrow);

  mrpt::opengl::CFBORender render(static_cast<unsigned>(width), static_cast<unsigned>(height));
  // Look from behind and above the start pose, at a point between it and the map's center, so
  // that the trajectory, the axes and the gravity arrow stay in view.
  auto& cam = render.getCamera(scene);
  const float cx = 0.5f * (x0 + x1), cy = 0.5f * (y0 + y1);
  const float px = static_cast<float>(p_end.x()), py = static_cast<float>(p_end.y());
  cam.setPointingAt(px + 0.35f * (cx - px), py + 0.35f * (cy - py),
                    static_cast<float>(p_end.z()));
  cam.setZoomDistance(std::clamp(0.7f * extent, 8.0f, 60.0f));
  cam.setAzimuthDegrees(
      static_cast<float>(std::atan2(py - cy, px - cx) * 180.0 / M_PI) + 25.0f);
  cam.setElevationDegrees(30.0f);
  scene.getViewport()->setCustomBackgroundColor(mrpt::img::TColorf(0.08f, 0.08f, 0.12f));

  mrpt::img::CImage img;
  render.render_RGB(scene, img);

  const auto& s = result.state;
  const TColor white(255, 255, 255);
  img.filledRectangle(0, 0, width - 1, 60, TColor(20, 20, 30));
  img.selectTextFont("10x20");
  img.textOut(12, 10, "Free-Init static map: " + std::to_string(result.static_map.size()) +
                          " static points, " + std::to_string(result.rejected.size()) +
                          " rejected (red)", white);
  img.textOut(12, 34, "status " + std::string(toString(s.status)) + "   |v| " +
                          num(s.v_w.norm()) + " m/s   trajectory (green), gravity (blue, 3 m)",
              white);
  saveAtomically(img, png);
}

void renderVelocityPlot(const std::string& png, const InitResult& result,
                        const std::vector<TruthSample>& truth, int width, int height) {
  const auto& v = result.velocities;
  if (v.empty()) throw std::runtime_error(png + ": no velocity samples to plot");
  const double t0 = v.front().t, t1 = std::max(v.back().t, t0 + 1e-3);

  // Ground truth body velocity over the same span.
  std::vector<std::pair<double, Vec3>> gt;
  for (const auto& g : truth) {
    if (g.t < t0 || g.t > t1) continue;
    gt.emplace_back(g.t, g.q_wb.conjugate() * g.v_w);
  }

  mrpt::img::CImage img(width, height, mrpt::img::CH_RGB);
  img.filledRectangle(0, 0, width - 1, height - 1, TColor(255, 255, 255));
  img.selectTextFont("9x15");
  const TColor black(0, 0, 0), grey(200, 200, 200);
  const TColor est_col[3] = {TColor(220, 40, 40), TColor(30, 150, 30), TColor(40, 60, 220)};
  const char* axis_name[3] = {"v_b.x", "v_b.y", "v_b.z"};
  const int left = 90, right = width - 20, top = 40;
  const int panel_h = (height - top - 50) / 3;

  img.textOut(left, 10,
              "Free-Init velocimeter: body velocity [m/s] (solid: estimate +/- 1 sigma band, "
              "black dashed: ground truth)",
              black);
  for (int a = 0; a < 3; ++a) {
    double lo = 1e9, hi = -1e9;
    for (const auto& s : v) {
      lo = std::min(lo, s.v_b[a] - s.sigma_v_b[a]);
      hi = std::max(hi, s.v_b[a] + s.sigma_v_b[a]);
    }
    for (const auto& g : gt) {
      lo = std::min(lo, g.second[a]);
      hi = std::max(hi, g.second[a]);
    }
    const double pad = std::max(0.05, 0.1 * (hi - lo));
    lo -= pad;
    hi += pad;
    const int y_top = top + a * panel_h + 10, y_bot = top + (a + 1) * panel_h - 10;
    auto X = [&](double t) {
      return left + static_cast<int>((t - t0) / (t1 - t0) * (right - left));
    };
    auto Y = [&](double val) {
      return y_bot - static_cast<int>((val - lo) / (hi - lo) * (y_bot - y_top));
    };
    img.rectangle(left, y_top, right, y_bot, black);
    for (int k = 0; k <= 4; ++k) {
      const double val = lo + (hi - lo) * k / 4.0;
      img.line(left, Y(val), right, Y(val), grey);
      img.textOut(4, Y(val) - 7, num(val, 2), black);
    }
    img.textOut(left + 8, y_top + 4, axis_name[a], est_col[a]);
    for (std::size_t i = 1; i < v.size(); ++i) {
      const TColor band(230, 230, 240);
      img.line(X(v[i].t), Y(v[i].v_b[a] - v[i].sigma_v_b[a]), X(v[i].t),
               Y(v[i].v_b[a] + v[i].sigma_v_b[a]), band);
    }
    for (std::size_t i = 1; i < v.size(); ++i)
      img.line(X(v[i - 1].t), Y(v[i - 1].v_b[a]), X(v[i].t), Y(v[i].v_b[a]), est_col[a], 2);
    for (std::size_t i = 1; i < gt.size(); ++i) {
      if ((i / 3) % 2 == 0)  // dashed
        img.line(X(gt[i - 1].first), Y(gt[i - 1].second[a]), X(gt[i].first), Y(gt[i].second[a]),
                 black, 1);
    }
  }
  const int y_axis = top + 3 * panel_h;
  for (int k = 0; k <= 5; ++k) {
    const double t = t0 + (t1 - t0) * k / 5.0;
    const int x = left + static_cast<int>((t - t0) / (t1 - t0) * (right - left));
    img.textOut(x - 20, y_axis, num(t - t0, 2) + " s", black);
  }
  saveAtomically(img, png);
}

}  // namespace freeinit::mrpt_glue
