#include <freeinit/bags/static_transforms.h>

#include <Eigen/Geometry>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

namespace freeinit::bags {
namespace {

std::string bare(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

struct Link {
  std::string parent;
  Eigen::Isometry3d T_parent_child = Eigen::Isometry3d::Identity();
};

// The frames from `frame` up to the root of its tree (frame first; a cycle stops it).
std::vector<std::string> upwards(const std::map<std::string, Link>& links, std::string frame) {
  std::vector<std::string> path{frame};
  for (std::size_t steps = 0; steps < links.size(); ++steps) {
    const auto it = links.find(frame);
    if (it == links.end()) break;
    frame = it->second.parent;
    path.push_back(frame);
  }
  return path;
}

// The pose of path[0] in path[n]: the product of the first n links.
Eigen::Isometry3d poseIn(const std::map<std::string, Link>& links,
                         const std::vector<std::string>& path, std::size_t n) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (std::size_t k = 0; k < n; ++k) T = links.at(path[k]).T_parent_child * T;
  return T;
}

}  // namespace

std::optional<RecordedExtrinsics> extrinsicsFromTransforms(
    const std::vector<ros2::TransformStamped>& transforms, const std::string& imu_frame,
    const std::string& lidar_frame) {
  const std::string imu = bare(imu_frame), lidar = bare(lidar_frame);
  if (imu.empty() || lidar.empty()) return std::nullopt;
  RecordedExtrinsics r;
  r.imu_frame = imu;
  r.lidar_frame = lidar;
  if (imu == lidar) {
    r.chain = imu + " (the same frame)";
    return r;
  }
  std::map<std::string, Link> links;  // by child
  for (const ros2::TransformStamped& t : transforms) {
    const Eigen::Quaterniond q(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
    const Vec3 p(t.translation.x, t.translation.y, t.translation.z);
    if (!q.coeffs().allFinite() || !p.allFinite() || q.norm() < 1e-9) continue;
    const std::string child = bare(t.child_frame_id), parent = bare(t.header.frame_id);
    if (child.empty() || parent.empty() || child == parent) continue;
    Link l;
    l.parent = parent;
    l.T_parent_child.linear() = q.normalized().toRotationMatrix();
    l.T_parent_child.translation() = p;
    links[child] = l;
  }
  const std::vector<std::string> up_imu = upwards(links, imu), up_lidar = upwards(links, lidar);
  // The nearest common ancestor c: T_imu_lidar = T_c_imu^-1 T_c_lidar.
  for (std::size_t i = 0; i < up_imu.size(); ++i) {
    for (std::size_t j = 0; j < up_lidar.size(); ++j) {
      if (up_imu[i] != up_lidar[j]) continue;
      const Eigen::Isometry3d T = poseIn(links, up_imu, i).inverse() * poseIn(links, up_lidar, j);
      r.extrinsics.R_bl = T.linear();
      r.extrinsics.p_bl = T.translation();
      std::ostringstream chain;
      for (std::size_t k = 0; k <= i; ++k) chain << (k ? " <- " : "") << up_imu[k];
      for (std::size_t k = j; k-- > 0;) chain << " -> " << up_lidar[k];
      r.chain = chain.str();
      return r;
    }
  }
  return std::nullopt;
}

std::string extrinsicsDifference(const Extrinsics& given, const Extrinsics& recorded) {
  const Eigen::AngleAxisd d(given.R_bl.transpose() * recorded.R_bl);
  const double angle_deg = std::abs(d.angle()) * 180.0 / M_PI;
  const double offset = (given.p_bl - recorded.p_bl).norm();
  if (angle_deg <= kExtrinsicsAngleTolerance && offset <= kExtrinsicsOffsetTolerance) return "";
  std::ostringstream os;
  os << std::fixed << std::setprecision(3) << "differ by " << angle_deg << " deg and "
     << std::setprecision(1) << offset * 1e3 << " mm";
  return os.str();
}

std::optional<ChosenExtrinsics> chooseExtrinsics(const std::optional<Extrinsics>& given,
                                                 const std::optional<RecordedExtrinsics>& recorded,
                                                 const std::string& ini_name,
                                                 const std::string& tf_static_topic,
                                                 const std::string& recording) {
  if (!given && !recorded) return std::nullopt;
  ChosenExtrinsics c;
  if (!given) {
    c.extrinsics = recorded->extrinsics;
    c.source = tf_static_topic + " of " + recording + " (" + recorded->chain + ")";
    return c;
  }
  c.extrinsics = *given;
  c.source = ini_name;
  if (recorded) {
    const std::string diff = extrinsicsDifference(*given, recorded->extrinsics);
    if (!diff.empty())
      c.warning = ini_name + " and " + tf_static_topic + " of " + recording + " (" +
                  recorded->chain + ") " + diff + ": the INI's are used";
  }
  return c;
}

}  // namespace freeinit::bags
