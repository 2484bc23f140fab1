// A scene: a list of analytic primitives, ray cast exactly (nearest hit over all candidates).
#pragma once

#include <freeinit/sim/primitive.h>

#include <string>
#include <vector>

namespace freeinit::sim {

/// Result of a ray cast.
struct RayHit {
  double range = 0;         ///< [m] distance along the unit ray
  Vec3 n_w = Vec3::Zero();  ///< unit surface normal facing the ray origin
  int primitive = -1;       ///< index into Scene::primitives()
};

/// A set of analytic primitives (static or moving with constant velocity).
class Scene {
 public:
  Scene() = default;
  explicit Scene(std::string kind) : kind_(std::move(kind)) {}

  /// Adds a primitive; returns its index.
  int add(const Primitive& p);
  const std::vector<Primitive>& primitives() const { return primitives_; }
  /// "street", "corridor", "tunnel", "open" or "parking".
  const std::string& kind() const { return kind_; }

  /// Nearest hit of o_w + s d_w (d_w unit), 0 < s < max_range, at relative time tau [s]
  /// (seconds since the recording start). Tests all primitives.
  bool castRay(const Vec3& o_w, const Vec3& d_w, double tau, double max_range, RayHit& hit) const;
  /// Same, testing only the primitives whose indices are listed in candidates.
  bool castRay(const Vec3& o_w, const Vec3& d_w, double tau, double max_range,
               const std::vector<int>& candidates, RayHit& hit) const;

 private:
  std::string kind_;
  std::vector<Primitive> primitives_;
};

}  // namespace freeinit::sim
