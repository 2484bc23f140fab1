#include <freeinit/sim/scene.h>

namespace freeinit::sim {

int Scene::add(const Primitive& p) {
  primitives_.push_back(p);
  return static_cast<int>(primitives_.size()) - 1;
}

bool Scene::castRay(const Vec3& o_w, const Vec3& d_w, double tau, double max_range,
                    RayHit& hit) const {
  double best = max_range;
  bool found = false;
  for (std::size_t i = 0; i < primitives_.size(); ++i) {
    double s = 0;
    Vec3 n;
    if (primitives_[i].intersect(o_w, d_w, tau, best, s, n)) {
      best = s;
      hit.range = s;
      hit.n_w = n;
      hit.primitive = static_cast<int>(i);
      found = true;
    }
  }
  return found;
}

bool Scene::castRay(const Vec3& o_w, const Vec3& d_w, double tau, double max_range,
                    const std::vector<int>& candidates, RayHit& hit) const {
  double best = max_range;
  bool found = false;
  for (int i : candidates) {
    double s = 0;
    Vec3 n;
    if (primitives_[static_cast<std::size_t>(i)].intersect(o_w, d_w, tau, best, s, n)) {
      best = s;
      hit.range = s;
      hit.n_w = n;
      hit.primitive = i;
      found = true;
    }
  }
  return found;
}

}  // namespace freeinit::sim
