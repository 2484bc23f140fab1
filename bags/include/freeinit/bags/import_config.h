// What to read from a ROS recording (a ROS 1 bag, an MCAP file, a rosbag2 folder) and how to
// interpret it: the same settings for both ROS generations. The defaults are the layout of the
// Free-Init / FMCW-LIO dataset release (Aeva Aeries II + Xsens IMU):
//   sensor_msgs/Imu on /imu/data (rad/s, m/s^2);
//   sensor_msgs/PointCloud2 on /aeva/AeriesII/point_cloud_frame with float32 x y z intensity
//   reflectivity velocity, int32 time_offset_ns (point time minus the header stamp, ns) and uint8
//   line_index; header stamp = frame start; raw (relative, not ego-compensated) Doppler with the
//   range-rate sign of freeinit/types.h. Everything is configurable; nothing is guessed from data.
// Other sensors: clouds without a per-point time (all points at the scan stamp, or spread evenly
// over a declared frame duration), scan stamps from a trigger topic matched by sequence number or
// from the bag's receive time, and a declared offset between the clocks
// (ini/import_bag_ti_mmwave.ini is a 4D radar with all three). Trigger stamps are ROS 1 only:
// ROS 2 headers have no sequence number to match by.
//
// No ROS and no MRPT type appears here.
#pragma once

#include <freeinit/types.h>

#include <cstdint>
#include <string>

namespace freeinit::bags {

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
/// Without a time field (field.name empty) the offsets come from the point order: point i of the
/// n points of a cloud (row-major, dropped invalid points included) is at
///   offset = frame_duration * (i + 0.5) / n,
/// the middle of its share of the frame, so that the points' mean time is the middle of the
/// frame; frame_duration = 0 puts every point at the scan stamp.
struct TimeFieldSpec {
  FieldSpec field{"time_offset_ns", FieldType::kInt32};
  double scale = 1e-9;        ///< [s per unit] 1e-9 for ns, 1e-6 for us, 1 for s
  bool relative = true;       ///< value is relative to the header stamp (else absolute UNIX time)
  double frame_duration = 0;  ///< [s] without a time field: the span the points are spread over
};

/// The PointCloud2 layout. x, y, z and the Doppler are required; the time field is optional.
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

/// Where a scan's stamp (the time its point offsets are relative to) comes from.
enum class StampSource {
  kHeader,   ///< the cloud's header stamp
  kTrigger,  ///< the stamp of the std_msgs/Header on trigger_topic whose seq is the cloud's seq
  kBagTime,  ///< the time the bag recorded the cloud (the recorder's clock, usually not the IMU's)
};

struct BagImportConfig {
  std::string imu_topic = "/imu/data";
  std::string lidar_topic = "/aeva/AeriesII/point_cloud_frame";
  CloudLayout cloud;
  StampSource stamp_source = StampSource::kHeader;
  /// std_msgs/Header messages marking each scan's start (stamp_source = trigger): a cloud takes the
  /// stamp of the trigger whose seq equals its header.seq (the nearest in bag time if a seq is
  /// repeated). Clouds without a trigger are skipped and counted.
  std::string trigger_topic;
  bool imu_accel_in_g = false;  ///< linear_acceleration is in g (converted with kGravity)
  /// [s] added to every scan stamp (whatever its source) to put it on the IMU clock:
  /// t_imu = t_scan + offset.
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
  /// tf2_msgs/TFMessage topic whose transforms give the LiDAR pose in the IMU frame (from the IMU
  /// header's frame_id to the cloud header's) when the configuration gives none ("" = not read).
  std::string tf_static_topic = "/tf_static";
};

/// "header", "trigger", "bag_time" (the INI values); throws std::invalid_argument otherwise.
StampSource stampSourceFromName(const std::string& name);
std::string stampSourceName(StampSource s);

/// Throws std::invalid_argument naming the key for inconsistent settings (empty required field
/// names, scale <= 0, doppler_sign not +-1, non-finite offsets, a trigger source without a
/// trigger topic, ...): what reading needs. The INI keys' accepted ranges are declared by the
/// importer's [bag_import] section.
void validate(const BagImportConfig& c);

}  // namespace freeinit::bags
