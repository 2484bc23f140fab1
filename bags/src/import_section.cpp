#include <freeinit/bags/import_section.h>

#include <functional>
#include <string>
#include <string_view>

namespace freeinit::bags {
namespace {

constexpr const char* kSection = "bag_import";
/// [s] the largest clock offset: ROS1 times are uint32 seconds, so two of them differ by less
/// than 2^32 s (a scan stamp from a clock since boot against bag times since 1970 is ~1.7e9 s).
constexpr double kMaxClockOffset = 4294967296.0;

std::string parseFieldType(std::string_view text, FieldType& t) {
  try {
    t = fieldTypeFromName(std::string(text));
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// "<key>" names a PointCloud2 field ("" = not read, optional fields only), "<key>_type" its
// datatype.
template <class Field>
void addField(config::Section<ImportSettings>& s, const std::string& key, Field field,
              const std::string& doc) {
  s.text(
       key, [field](auto& x) -> auto& { return field(x).name; }, doc)
      .custom(
          key + "_type", [field](auto& x) -> auto& { return field(x).type; }, "-",
          "int8 | uint8 | int16 | uint16 | int32 | uint32 | float32 | float64",
          std::function<std::string(std::string_view, FieldType&)>(parseFieldType),
          std::function<std::string(const FieldType&)>(
              [](const FieldType& t) { return fieldTypeName(t); }),
          "datatype of " + key + " in the bag (another type is an error, not a conversion)");
}

}  // namespace

const config::Section<ImportSettings>& importSection() {
  using config::between;
  using S = ImportSettings;
  static const auto s = [] {
    config::Section<S> sec(
        kSection,
        "how to read a ROS 1 bag or ROS 2 recording (defaults: the Free-Init / FMCW-LIO release)");
    sec.text(
           "imu_topic", [](auto& x) -> auto& { return x.bag.imu_topic; }, "sensor_msgs/Imu topic",
           true)
        .text(
            "lidar_topic", [](auto& x) -> auto& { return x.bag.lidar_topic; },
            "sensor_msgs/PointCloud2 topic", true);
    addField(
        sec, "x_field", [](auto& x) -> auto& { return x.bag.cloud.x; }, "[m] LiDAR frame x");
    addField(
        sec, "y_field", [](auto& x) -> auto& { return x.bag.cloud.y; }, "[m] LiDAR frame y");
    addField(
        sec, "z_field", [](auto& x) -> auto& { return x.bag.cloud.z; }, "[m] LiDAR frame z");
    addField(
        sec, "doppler_field", [](auto& x) -> auto& { return x.bag.cloud.doppler; },
        "[m/s] per-point Doppler velocity");
    sec.choice(
           "doppler_sign", [](auto& x) -> auto& { return x.bag.cloud.doppler_sign; },
           {{"1", 1.0}, {"-1", -1.0}},
           "1: the field is the range rate (negative approaching); -1: approach is positive")
        .choice(
            "doppler_mode", [](auto& x) -> auto& { return x.bag.doppler_mode; },
            {{"relative", DopplerMode::kRelative},
             {"ego_compensated", DopplerMode::kEgoCompensated}},
            "relative (raw range rate) or ego_compensated (refused: Free-Init needs raw "
            "Doppler)");
    addField(
        sec, "time_field", [](auto& x) -> auto& { return x.bag.cloud.time.field; },
        "per-point time (empty: none, see frame_duration)");
    sec.number(
           "time_scale", [](auto& x) -> auto& { return x.bag.cloud.time.scale; }, "s per unit",
           config::aboveUpTo(0, 1e3), "1e-9: ns, 1e-6: us, 1: s")
        .flag(
            "time_relative", [](auto& x) -> auto& { return x.bag.cloud.time.relative; },
            "true: offset after the scan stamp; false: absolute UNIX time (float64)")
        .number(
            "frame_duration", [](auto& x) -> auto& { return x.bag.cloud.time.frame_duration; }, "s",
            between(0, 10),
            "without a time field: the span after the scan stamp the points are spread over, in "
            "point order (0: all at the scan stamp)")
        .choice(
            "stamp_source", [](auto& x) -> auto& { return x.bag.stamp_source; },
            {{"header", StampSource::kHeader},
             {"trigger", StampSource::kTrigger},
             {"bag_time", StampSource::kBagTime}},
            "scan stamp: the cloud's header stamp, the stamp of the trigger_topic message with "
            "the cloud's seq, or the time the bag recorded the cloud")
        .text(
            "trigger_topic", [](auto& x) -> auto& { return x.bag.trigger_topic; },
            "std_msgs/Header topic of the scan starts (only with stamp_source = trigger)");
    addField(
        sec, "intensity_field", [](auto& x) -> auto& { return x.bag.cloud.intensity; },
        "optional intensity");
    addField(
        sec, "line_field", [](auto& x) -> auto& { return x.bag.cloud.line; },
        "optional scan line index");
    sec.choice(
           "imu_accel_unit", [](auto& x) -> auto& { return x.bag.imu_accel_in_g; },
           {{"m/s^2", false}, {"g", true}},
           "unit of linear_acceleration (checked against the data: mean |a| ~ 9.81 or ~ 1)")
        .number(
            "lidar_time_offset", [](auto& x) -> auto& { return x.bag.lidar_time_offset; }, "s",
            between(-kMaxClockOffset, kMaxClockOffset),
            "added to every scan stamp to put it on the IMU clock (bag times are often days "
            "off)")
        .number(
            "reorder_window", [](auto& x) -> auto& { return x.bag.reorder_window; }, "s",
            between(0, 3600),
            "how late (in stamp time) a message may be recorded and still be put in order")
        .flag(
            "drop_invalid_points", [](auto& x) -> auto& { return x.bag.drop_invalid_points; },
            "drop NaN/inf points (counted); false: error")
        .number(
            "gap_factor", [](auto& x) -> auto& { return x.bag.gap_factor; }, "-",
            config::aboveUpTo(1, 1e6), "report intervals > gap_factor x the median as gaps")
        .number(
            "unit_check_samples", [](auto& x) -> auto& { return x.bag.unit_check_samples; }, "-",
            between(1, 1e6), "first IMU samples whose mean specific force checks imu_accel_unit")
        .text(
            "tf_static_topic", [](auto& x) -> auto& { return x.bag.tf_static_topic; },
            "tf2_msgs/TFMessage topic giving the LiDAR pose in the IMU frame when [extrinsics] "
            "does not (empty: not read)")
        .text("imu_label", &S::imu_label, "sensorLabel written on the IMU observations", true)
        .text("lidar_label", &S::lidar_label, "sensorLabel written on the point clouds", true)
        .text("freeinit_config", &S::freeinit_config,
              "the freeinit configuration made for this sensor, relative to this INI's folder, "
              "suggested after the import (empty: the defaults suit it)",
              false)
        .check([](const S& x, const config::Checker& c) {
          if (x.imu_label == x.lidar_label) c.fail("lidar_label", "must differ from imu_label");
          try {
            validate(x.bag);
          } catch (const std::invalid_argument& e) {  // "key: why"
            const std::string what = e.what();
            const auto colon = what.find(": ");
            c.fail(what.substr(0, colon),
                   colon == std::string::npos ? what : what.substr(colon + 2));
          }
        });
    return sec;
  }();
  return s;
}

}  // namespace freeinit::bags
