#include <freeinit/bags/import_config.h>

#include <cmath>
#include <stdexcept>

namespace freeinit::bags {
namespace {

struct TypeName {
  FieldType type;
  const char* name;
  std::size_t size;
};
constexpr TypeName kTypes[] = {
    {FieldType::kInt8, "int8", 1},       {FieldType::kUint8, "uint8", 1},
    {FieldType::kInt16, "int16", 2},     {FieldType::kUint16, "uint16", 2},
    {FieldType::kInt32, "int32", 4},     {FieldType::kUint32, "uint32", 4},
    {FieldType::kFloat32, "float32", 4}, {FieldType::kFloat64, "float64", 8}};

}  // namespace

FieldType fieldTypeFromName(const std::string& name) {
  for (const auto& t : kTypes)
    if (name == t.name) return t.type;
  throw std::invalid_argument("unknown field type '" + name +
                              "' (int8, uint8, int16, uint16, int32, uint32, float32, float64)");
}

std::string fieldTypeName(FieldType t) { return fieldTypeName(static_cast<std::uint8_t>(t)); }

std::string fieldTypeName(std::uint8_t datatype) {
  for (const auto& t : kTypes)
    if (static_cast<std::uint8_t>(t.type) == datatype) return t.name;
  return "unknown datatype " + std::to_string(datatype);
}

std::size_t fieldTypeSize(FieldType t) {
  for (const auto& k : kTypes)
    if (k.type == t) return k.size;
  return 0;
}

StampSource stampSourceFromName(const std::string& name) {
  if (name == "header") return StampSource::kHeader;
  if (name == "trigger") return StampSource::kTrigger;
  if (name == "bag_time") return StampSource::kBagTime;
  throw std::invalid_argument("'" + name + "' is not one of 'header', 'trigger', 'bag_time'");
}

std::string stampSourceName(StampSource s) {
  switch (s) {
    case StampSource::kHeader:
      return "header";
    case StampSource::kTrigger:
      return "trigger";
    case StampSource::kBagTime:
      return "bag_time";
  }
  return "?";
}

void validate(const BagImportConfig& c) {
  auto fail = [](const std::string& key, const std::string& why) {
    throw std::invalid_argument(key + ": " + why);
  };
  if (c.imu_topic.empty()) fail("imu_topic", "must not be empty");
  if (c.lidar_topic.empty()) fail("lidar_topic", "must not be empty");
  if (c.imu_topic == c.lidar_topic) fail("lidar_topic", "must differ from imu_topic");
  const CloudLayout& l = c.cloud;
  for (const auto& [key, spec] :
       {std::pair{"x_field", &l.x}, std::pair{"y_field", &l.y}, std::pair{"z_field", &l.z},
        std::pair{"doppler_field", &l.doppler}})
    if (spec->name.empty()) fail(key, "is required");
  if (!(l.time.scale > 0) || !std::isfinite(l.time.scale)) fail("time_scale", "must be > 0");
  if (!(l.time.frame_duration >= 0) || !std::isfinite(l.time.frame_duration))
    fail("frame_duration", "must be >= 0 and finite");
  if (!l.time.field.name.empty() && l.time.frame_duration != 0)
    fail("frame_duration",
         "is for clouds without a per-point time: with time_field = " + l.time.field.name +
             " the points carry their own times (set time_field = to spread them instead)");
  if (!l.time.relative && !l.time.field.name.empty() && l.time.field.type != FieldType::kFloat64)
    fail("time_relative",
         "false (absolute UNIX times) needs time_field_type = float64: a float32 cannot hold a "
         "UNIX time to better than 128 s");
  if (l.doppler_sign != 1.0 && l.doppler_sign != -1.0) fail("doppler_sign", "must be 1 or -1");
  if (!l.time.relative && c.stamp_source != StampSource::kHeader)
    fail("time_relative", "false (absolute point times) needs stamp_source = header");
  if (c.stamp_source == StampSource::kTrigger) {
    if (c.trigger_topic.empty()) fail("trigger_topic", "is required with stamp_source = trigger");
    if (c.trigger_topic == c.imu_topic || c.trigger_topic == c.lidar_topic)
      fail("trigger_topic", "must differ from imu_topic and lidar_topic");
  } else if (!c.trigger_topic.empty()) {
    fail("trigger_topic", "is only read with stamp_source = trigger (it is " +
                              stampSourceName(c.stamp_source) + ")");
  }
  if (!std::isfinite(c.lidar_time_offset)) fail("lidar_time_offset", "must be finite");
  if (!(c.reorder_window >= 0) || !std::isfinite(c.reorder_window))
    fail("reorder_window", "must be >= 0");
  if (!(c.gap_factor > 1)) fail("gap_factor", "must be > 1");
  if (c.unit_check_samples < 1) fail("unit_check_samples", "must be >= 1");
}

}  // namespace freeinit::bags
