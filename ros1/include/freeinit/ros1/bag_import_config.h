// What to read from a ROS1 bag and how to interpret it. The defaults are the layout of the
// Free-Init / FMCW-LIO dataset release (Aeva Aeries II + Xsens IMU):
//   sensor_msgs/Imu on /imu/data (rad/s, m/s^2);
//   sensor_msgs/PointCloud2 on /aeva/AeriesII/point_cloud_frame with float32 x y z intensity
//   reflectivity velocity, int32 time_offset_ns (point time minus the header stamp, ns) and uint8
//   line_index; header stamp = frame start; raw (relative, not ego-compensated) Doppler with the
//   range-rate sign of freeinit/types.h. Everything is configurable; nothing is guessed from data.
// No ROS and no MRPT type appears here.
#pragma once

#include <freeinit/types.h>

#include <cstdint>
#include <string>

namespace freeinit::ros1 {

/// PointField datatypes (sensor_msgs/PointField constants).
enum class FieldType : std::uint8_t {
  kInt8 = 1,
  kUint8 = 2,
  kInt16 = 3,
  kUint16 = 4,
  kInt32 = 5,
  kUint32 = 6,
  kFloat32 = 7,
  kFloat64 = 8
};

/// "int8" ... "float64" (as in PCL / ROS 2 names). Throws std::invalid_argument otherwise.
FieldType fieldTypeFromName(const std::string& name);
std::string fieldTypeName(FieldType t);
std::string fieldTypeName(std::uint8_t datatype);  ///< also names unknown codes
std::size_t fieldTypeSize(FieldType t);

/// One point field the importer reads: its name and the datatype the bag must have. A field
/// whose name is empty is not read (its value is 0). A field with a different datatype in the bag
/// is an error, not a conversion: a different type usually means a different unit.
struct FieldSpec {
  std::string name;
  FieldType type = FieldType::kFloat32;
};

/// Where a point's time comes from. point time = header stamp + offset, with
///   offset = value * scale                       (relative = true: value is an offset)
///   offset = value * scale - header stamp        (relative = false: value is absolute time)
struct TimeFieldSpec {
  FieldSpec field{"time_offset_ns", FieldType::kInt32};
  double scale = 1e-9;   ///< [s per unit] 1e-9 for ns, 1e-6 for us, 1 for s
  bool relative = true;  ///< value is relative to the header stamp (else absolute UNIX time)
};

/// The PointCloud2 layout. x, y, z, the Doppler and the time are required.
struct CloudLayout {
  FieldSpec x{"x", FieldType::kFloat32};
  FieldSpec y{"y", FieldType::kFloat32};
  FieldSpec z{"z", FieldType::kFloat32};
  FieldSpec doppler{"velocity", FieldType::kFloat32};  ///< [m/s]
  TimeFieldSpec time;
  FieldSpec intensity{"intensity", FieldType::kFloat32};  ///< optional ("" = not read)
  FieldSpec line{"line_index", FieldType::kUint8};        ///< optional ("" = not read)
  /// Multiplies the Doppler field: 1 when it is the range rate (negative approaching), -1 when
  /// the sensor reports positive for approaching points.
  double doppler_sign = 1.0;
};

/// How the Doppler values relate to the platform's motion. Declared, never guessed.
enum class DopplerMode {
  kRelative,        ///< raw range rate of the sensor (what Free-Init needs)
  kEgoCompensated,  ///< the sensor's ego velocity already removed ("absolute" Doppler)
};

struct BagImportConfig {
  std::string imu_topic = "/imu/data";
  std::string lidar_topic = "/aeva/AeriesII/point_cloud_frame";
  CloudLayout cloud;
  bool imu_accel_in_g = false;  ///< linear_acceleration is in g (converted with kGravity)
  /// [s] added to every LiDAR time to put it on the IMU clock: t_imu = t_lidar + offset.
  double lidar_time_offset = 0;
  DopplerMode doppler_mode = DopplerMode::kRelative;
  /// [s] how far (in header time) a message may arrive after later-stamped ones and still be
  /// put in order. Aeva frames are published after their 0.1 s sweep, so they trail the IMU.
  double reorder_window = 1.0;
  /// Drop NaN/inf points (counted in the summary) instead of failing. Organized, non-dense clouds
  /// mark missing returns this way.
  bool drop_invalid_points = true;
  /// [s] an interval between consecutive messages of a topic longer than this many times its
  /// median interval is reported as a gap.
  double gap_factor = 2.0;
  /// Number of first IMU samples whose mean specific force checks the declared unit (g or m/s^2).
  int unit_check_samples = 200;
};

/// Throws std::invalid_argument naming the key for inconsistent settings (empty required field
/// names, scale <= 0, doppler_sign not +-1, non-finite offsets, ...).
void validate(const BagImportConfig& c);

}  // namespace freeinit::ros1
