// Analytic scene primitives with exact ray intersection. A primitive may translate with a constant
// velocity (cars, pedestrians): its pose at relative time tau [s] is center_w + v_w * tau.
#pragma once

#include <freeinit/types.h>

namespace freeinit::sim {

/// Shape of a primitive.
enum class PrimitiveType : std::uint8_t {
  Rectangle = 0,  ///< bounded plane: normal = z axis of R_wo, half extents (hx, hy)
  Box = 1,        ///< oriented box, half extents (hx, hy, hz) along the axes of R_wo
  Cylinder = 2,   ///< vertical (world z) cylinder with caps: half_size = (radius, -, half height)
};

/// One analytic primitive.
struct Primitive {
  PrimitiveType type = PrimitiveType::Box;
  Vec3 center_w = Vec3::Zero();   ///< [m] center at tau = 0 (time of the recording start)
  Mat3 R_wo = Mat3::Identity();   ///< orientation (ignored by Cylinder)
  Vec3 half_size = Vec3::Ones();  ///< [m] see PrimitiveType
  Vec3 v_w = Vec3::Zero();        ///< [m/s] constant velocity; nonzero means a dynamic object
  float reflectivity = 0.5f;      ///< [-] in [0, 1]

  bool isDynamic() const { return !v_w.isZero(0.0); }
  /// [m] radius of a sphere around the center that encloses the primitive.
  double boundingRadius() const;
  /// [m] center at relative time tau [s].
  Vec3 centerAt(double tau) const { return center_w + v_w * tau; }

  /// Nearest intersection of the ray o_w + s d_w, 0 < s < s_max (d_w unit), with the primitive
  /// posed at relative time tau [s]. On a hit, sets s [m] and the unit surface normal n_w.
  bool intersect(const Vec3& o_w, const Vec3& d_w, double tau, double s_max, double& s,
                 Vec3& n_w) const;
};

/// Convenience constructors.
Primitive makeBox(const Vec3& center_w, const Vec3& half_size, double yaw = 0.0,
                  float reflectivity = 0.5f, const Vec3& v_w = Vec3::Zero());
Primitive makeRectangle(const Vec3& center_w, const Mat3& R_wo, double half_x, double half_y,
                        float reflectivity = 0.5f);
Primitive makeCylinder(const Vec3& center_w, double radius, double half_height,
                       float reflectivity = 0.5f, const Vec3& v_w = Vec3::Zero());

}  // namespace freeinit::sim
