// The LiDAR-IMU extrinsics a ROS recording carries on /tf_static (tf2_msgs/TFMessage, ROS 1 or 2):
// each TransformStamped is the pose of child_frame_id in header.frame_id (p_parent = R p_child +
// t); the LiDAR pose in the IMU (body) frame is the chain from the IMU header's frame_id to the
// cloud header's, through any common ancestor (base_link -> imu_link, base_link -> aeva_link).
#pragma once

#include <freeinit/ros2/messages.h>
#include <freeinit/types.h>

#include <optional>
#include <string>
#include <vector>

namespace freeinit::bags {

/// Extrinsics found in a recording, and where.
struct RecordedExtrinsics {
  Extrinsics extrinsics;    ///< the LiDAR pose in the IMU frame
  std::string imu_frame;    ///< the IMU messages' frame_id
  std::string lidar_frame;  ///< the clouds' frame_id
  std::string chain;        ///< e.g. "imu_link <- base_link -> aeva_link"
};

/// R_bl, p_bl of `lidar_frame` in `imu_frame` from `transforms` (later ones replace earlier ones of
/// the same child), or nullopt when they do not link the two frames. Frame names are compared
/// without a leading '/' (ROS 1 tf allowed one). The same frame for both gives the identity.
/// Transforms with a non-finite value or a zero quaternion are ignored.
std::optional<RecordedExtrinsics> extrinsicsFromTransforms(
    const std::vector<ros2::TransformStamped>& transforms, const std::string& imu_frame,
    const std::string& lidar_frame);

/// "" when `given` and `recorded` agree within 0.1 deg and 1 mm; else one line with both
/// differences, e.g. "differ by 90.000 deg and 0.0 mm".
std::string extrinsicsDifference(const Extrinsics& given, const Extrinsics& recorded);

/// The extrinsics an importer uses, where they come from, and a disagreement.
struct ChosenExtrinsics {
  Extrinsics extrinsics;
  /// `ini_name`, or "<tf_static_topic> of <recording> (<chain>)".
  std::string source;
  /// "" or "<ini_name> and <tf_static_topic> of <recording> (<chain>) <difference>: the INI's are
  /// used" where both give extrinsics and they differ (extrinsicsDifference).
  std::string warning;
};

/// The INI's extrinsics (`given`) when it gives them, else the recording's (`recorded`, read from
/// `tf_static_topic` of `recording`); nullopt when neither does. `ini_name` names where the INI
/// gives them ("[extrinsics]", "import.ini [extrinsics]") in `source` and `warning`.
std::optional<ChosenExtrinsics> chooseExtrinsics(const std::optional<Extrinsics>& given,
                                                 const std::optional<RecordedExtrinsics>& recorded,
                                                 const std::string& ini_name,
                                                 const std::string& tf_static_topic,
                                                 const std::string& recording);

/// [deg] and [m]: the tolerances of extrinsicsDifference.
inline constexpr double kExtrinsicsAngleTolerance = 0.1;
inline constexpr double kExtrinsicsOffsetTolerance = 1e-3;

}  // namespace freeinit::bags
