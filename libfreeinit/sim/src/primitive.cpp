#include <freeinit/sim/primitive.h>

#include <cmath>
#include <limits>

namespace freeinit::sim {

double Primitive::boundingRadius() const {
  switch (type) {
    case PrimitiveType::Rectangle:
      return std::hypot(half_size.x(), half_size.y());
    case PrimitiveType::Box:
      return half_size.norm();
    case PrimitiveType::Cylinder:
      return std::hypot(half_size.x(), half_size.z());
  }
  return half_size.norm();
}

bool Primitive::intersect(const Vec3& o_w, const Vec3& d_w, double tau, double s_max, double& s,
                          Vec3& n_w) const {
  const Vec3 c_w = centerAt(tau);
  switch (type) {
    case PrimitiveType::Rectangle: {
      const Vec3 n = R_wo.col(2);
      const double den = n.dot(d_w);
      if (std::abs(den) < 1e-12) return false;
      const double si = n.dot(c_w - o_w) / den;
      if (si <= 0 || si >= s_max) return false;
      const Vec3 q = o_w + si * d_w - c_w;
      if (std::abs(q.dot(R_wo.col(0))) > half_size.x() ||
          std::abs(q.dot(R_wo.col(1))) > half_size.y())
        return false;
      s = si;
      n_w = den < 0 ? n : Vec3(-n);
      return true;
    }
    case PrimitiveType::Box: {
      // Slab test in the box frame.
      const Vec3 o = R_wo.transpose() * (o_w - c_w);
      const Vec3 d = R_wo.transpose() * d_w;
      double t_near = -std::numeric_limits<double>::infinity();
      double t_far = std::numeric_limits<double>::infinity();
      int axis_near = -1, axis_far = -1;
      for (int k = 0; k < 3; ++k) {
        if (std::abs(d[k]) < 1e-15) {
          if (std::abs(o[k]) > half_size[k]) return false;
          continue;
        }
        const double inv = 1.0 / d[k];
        double t1 = (-half_size[k] - o[k]) * inv;
        double t2 = (half_size[k] - o[k]) * inv;
        if (t1 > t2) std::swap(t1, t2);
        if (t1 > t_near) {
          t_near = t1;
          axis_near = k;
        }
        if (t2 < t_far) {
          t_far = t2;
          axis_far = k;
        }
        if (t_near > t_far) return false;
      }
      // From outside the nearest face is the entry; from inside it is the exit (rooms as boxes).
      double si = t_near;
      int axis = axis_near;
      if (si <= 0) {
        si = t_far;
        axis = axis_far;
      }
      if (si <= 0 || si >= s_max || axis < 0) return false;
      Vec3 n = Vec3::Zero();
      n[axis] = d[axis] > 0 ? -1.0 : 1.0;
      s = si;
      n_w = R_wo * n;
      return true;
    }
    case PrimitiveType::Cylinder: {
      const double r = half_size.x();
      const double hh = half_size.z();
      double best = s_max;
      Vec3 n_best = Vec3::Zero();
      const double ox = o_w.x() - c_w.x(), oy = o_w.y() - c_w.y();
      const double a = d_w.x() * d_w.x() + d_w.y() * d_w.y();
      if (a > 1e-15) {
        const double b = ox * d_w.x() + oy * d_w.y();
        const double c = ox * ox + oy * oy - r * r;
        const double disc = b * b - a * c;
        if (disc >= 0) {
          const double sq = std::sqrt(disc);
          for (double si : {(-b - sq) / a, (-b + sq) / a}) {
            if (si <= 0 || si >= best) continue;
            const double z = o_w.z() + si * d_w.z() - c_w.z();
            if (std::abs(z) > hh) continue;
            best = si;
            n_best = Vec3(ox + si * d_w.x(), oy + si * d_w.y(), 0) / r;
            if (n_best.dot(d_w) > 0) n_best = -n_best;
            break;
          }
        }
      }
      if (std::abs(d_w.z()) > 1e-15) {
        for (double zc : {c_w.z() + hh, c_w.z() - hh}) {
          const double si = (zc - o_w.z()) / d_w.z();
          if (si <= 0 || si >= best) continue;
          const double x = ox + si * d_w.x(), y = oy + si * d_w.y();
          if (x * x + y * y > r * r) continue;
          best = si;
          n_best = Vec3(0, 0, d_w.z() > 0 ? -1.0 : 1.0);
        }
      }
      if (best >= s_max) return false;
      s = best;
      n_w = n_best;
      return true;
    }
  }
  return false;
}

Primitive makeBox(const Vec3& center_w, const Vec3& half_size, double yaw, float reflectivity,
                  const Vec3& v_w) {
  Primitive p;
  p.type = PrimitiveType::Box;
  p.center_w = center_w;
  p.R_wo = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
  p.half_size = half_size;
  p.reflectivity = reflectivity;
  p.v_w = v_w;
  return p;
}

Primitive makeRectangle(const Vec3& center_w, const Mat3& R_wo, double half_x, double half_y,
                        float reflectivity) {
  Primitive p;
  p.type = PrimitiveType::Rectangle;
  p.center_w = center_w;
  p.R_wo = R_wo;
  p.half_size = Vec3(half_x, half_y, 0);
  p.reflectivity = reflectivity;
  return p;
}

Primitive makeCylinder(const Vec3& center_w, double radius, double half_height, float reflectivity,
                       const Vec3& v_w) {
  Primitive p;
  p.type = PrimitiveType::Cylinder;
  p.center_w = center_w;
  p.half_size = Vec3(radius, radius, half_height);
  p.reflectivity = reflectivity;
  p.v_w = v_w;
  return p;
}

}  // namespace freeinit::sim
