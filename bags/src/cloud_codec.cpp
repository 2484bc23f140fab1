#include <freeinit/bags/cloud_codec.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>

namespace freeinit::bags {
namespace {

constexpr bool kHostBigEndian = false;
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "little-endian host assumed");

template <class T>
T load(const std::uint8_t* p, bool swap) {
  std::array<std::uint8_t, sizeof(T)> b;
  std::memcpy(b.data(), p, sizeof(T));
  if (swap) std::reverse(b.begin(), b.end());
  T v;
  std::memcpy(&v, b.data(), sizeof(T));
  return v;
}

template <class T>
void store(T v, std::uint8_t* p, bool swap) {
  std::array<std::uint8_t, sizeof(T)> b;
  std::memcpy(b.data(), &v, sizeof(T));
  if (swap) std::reverse(b.begin(), b.end());
  std::memcpy(p, b.data(), sizeof(T));
}

double loadAs(const std::uint8_t* p, FieldType t, bool swap) {
  switch (t) {
    case FieldType::kInt8:
      return load<std::int8_t>(p, swap);
    case FieldType::kUint8:
      return load<std::uint8_t>(p, swap);
    case FieldType::kInt16:
      return load<std::int16_t>(p, swap);
    case FieldType::kUint16:
      return load<std::uint16_t>(p, swap);
    case FieldType::kInt32:
      return load<std::int32_t>(p, swap);
    case FieldType::kUint32:
      return load<std::uint32_t>(p, swap);
    case FieldType::kFloat32:
      return load<float>(p, swap);
    case FieldType::kFloat64:
      return load<double>(p, swap);
  }
  return 0;
}

// Integers are rounded to the nearest representable value (saturating); floats stored as they are.
void storeAs(double v, std::uint8_t* p, FieldType t, bool swap) {
  auto integer = [&](auto tag) {
    using I = decltype(tag);
    const double r = std::round(v);
    const double lo = static_cast<double>(std::numeric_limits<I>::min());
    const double hi = static_cast<double>(std::numeric_limits<I>::max());
    store<I>(static_cast<I>(std::clamp(r, lo, hi)), p, swap);
  };
  switch (t) {
    case FieldType::kInt8:
      return integer(std::int8_t{});
    case FieldType::kUint8:
      return integer(std::uint8_t{});
    case FieldType::kInt16:
      return integer(std::int16_t{});
    case FieldType::kUint16:
      return integer(std::uint16_t{});
    case FieldType::kInt32:
      return integer(std::int32_t{});
    case FieldType::kUint32:
      return integer(std::uint32_t{});
    case FieldType::kFloat32:
      return store<float>(static_cast<float>(v), p, swap);
    case FieldType::kFloat64:
      return store<double>(v, p, swap);
  }
}

std::string listFields(const std::vector<ros2::PointField>& fields) {
  std::ostringstream os;
  for (std::size_t i = 0; i < fields.size(); ++i)
    os << (i ? ", " : "") << fields[i].name << " " << fieldTypeName(fields[i].datatype);
  return fields.empty() ? std::string("none") : os.str();
}

// The byte offset of a configured field within a point, after checking it against the message.
struct BoundField {
  std::optional<std::uint32_t> offset;  ///< empty: not read
  FieldType type = FieldType::kFloat32;
};

BoundField bind(const PointCloudView& msg, const FieldSpec& spec, const char* role,
                const char* key) {
  BoundField b;
  b.type = spec.type;
  if (spec.name.empty()) return b;
  const std::vector<ros2::PointField>& fields = *msg.fields;
  const auto it = std::find_if(fields.begin(), fields.end(),
                               [&](const ros2::PointField& f) { return f.name == spec.name; });
  if (it == fields.end())
    throw LayoutError(std::string("no field '") + spec.name + "' (" + role + ", set " + key +
                      ") in the cloud; its fields: " + listFields(fields));
  if (it->datatype != static_cast<std::uint8_t>(spec.type))
    throw LayoutError(std::string("field '") + spec.name + "' (" + role + ") is " +
                      fieldTypeName(it->datatype) + ", the configuration says " +
                      fieldTypeName(spec.type) + " (set " + key + "_type if that is right)");
  if (it->count > 1)
    throw LayoutError(std::string("field '") + spec.name + "' (" + role + ") has count " +
                      std::to_string(it->count) + ", expected 1");
  if (static_cast<std::size_t>(it->offset) + fieldTypeSize(spec.type) > msg.point_step)
    throw LayoutError(std::string("field '") + spec.name + "' (" + role + ") at offset " +
                      std::to_string(it->offset) + " does not fit in point_step " +
                      std::to_string(msg.point_step));
  b.offset = it->offset;
  return b;
}

const std::vector<ros2::PointField> kNoFields;

}  // namespace

PointCloudView view(const ros2::PointCloud2& msg) {
  PointCloudView v;
  v.stamp_sec = msg.header.stamp.sec;
  v.stamp_nanosec = msg.header.stamp.nanosec;
  v.height = msg.height;
  v.width = msg.width;
  v.point_step = msg.point_step;
  v.row_step = msg.row_step;
  v.is_bigendian = msg.is_bigendian;
  v.fields = &msg.fields;
  v.data = msg.data.data();
  v.size = msg.data.size();
  return v;
}

LidarFrame decodeCloud(const PointCloudView& view_in, const CloudLayout& layout, bool drop_invalid,
                       DecodeStats* stats) {
  PointCloudView msg = view_in;
  if (msg.fields == nullptr) msg.fields = &kNoFields;
  const BoundField fx = bind(msg, layout.x, "x", "x_field");
  const BoundField fy = bind(msg, layout.y, "y", "y_field");
  const BoundField fz = bind(msg, layout.z, "z", "z_field");
  const BoundField fd = bind(msg, layout.doppler, "Doppler velocity", "doppler_field");
  const BoundField ft = bind(msg, layout.time.field, "point time", "time_field");
  const BoundField fi = bind(msg, layout.intensity, "intensity", "intensity_field");
  const BoundField fl = bind(msg, layout.line, "scan line", "line_field");

  // Sizes in 64 bits, checked whatever the width or height: a cloud of width 0 and height 4e9
  // has no point and must not run a row loop over data it does not have.
  const std::uint64_t width = msg.width, height = msg.height;
  const std::uint64_t n = width * height;
  LidarFrame frame;
  frame.stamp = msg.stamp();
  if (n == 0) return frame;
  const std::uint64_t row_bytes = width * msg.point_step;
  if (msg.row_step < row_bytes)
    throw LayoutError("row_step " + std::to_string(msg.row_step) + " < width " +
                      std::to_string(width) + " x point_step " + std::to_string(msg.point_step));
  if (msg.size < (height - 1) * msg.row_step + row_bytes)
    throw LayoutError("data holds " + std::to_string(msg.size) + " bytes, " +
                      std::to_string(height) + " rows of " + std::to_string(msg.row_step) +
                      " bytes need more (truncated message)");
  const bool swap = msg.is_bigendian != kHostBigEndian;
  const double stamp = frame.stamp;
  // Without a time field, point i of n sits in the middle of its share of the frame.
  const double spread = layout.time.frame_duration / static_cast<double>(n);

  frame.points.reserve(n);
  std::size_t invalid = 0;
  for (std::uint64_t r = 0; r < height; ++r) {
    const std::uint8_t* row = msg.data + r * msg.row_step;
    for (std::uint64_t c = 0; c < width; ++c) {
      const std::uint8_t* pt = row + c * msg.point_step;
      const std::uint64_t index = r * width + c;
      auto get = [&](const BoundField& f) {
        return f.offset ? loadAs(pt + *f.offset, f.type, swap) : 0.0;
      };
      double t = (static_cast<double>(index) + 0.5) * spread;
      if (ft.offset) {
        t = get(ft) * layout.time.scale;
        if (!layout.time.relative) t -= stamp;
      }
      DopplerPoint p;
      p.p_l = Eigen::Vector3f(static_cast<float>(get(fx)), static_cast<float>(get(fy)),
                              static_cast<float>(get(fz)));
      p.doppler = static_cast<float>(layout.doppler_sign * get(fd));
      p.time_offset = static_cast<float>(t);
      p.intensity = static_cast<float>(get(fi));
      const double line = get(fl);
      if (!(line >= 0 && line <= 65535))
        throw LayoutError("point " + std::to_string(index) + ": line index " +
                          std::to_string(line) + " is not in [0, 65535]");
      p.line = static_cast<std::uint16_t>(line);
      if (!p.p_l.allFinite() || !std::isfinite(p.doppler) || !std::isfinite(p.time_offset)) {
        if (!drop_invalid)
          throw LayoutError("point " + std::to_string(index) +
                            " has a NaN or infinite coordinate, Doppler or time (set "
                            "drop_invalid_points = true to drop such points)");
        ++invalid;
        continue;
      }
      frame.points.push_back(p);
    }
  }
  std::stable_sort(
      frame.points.begin(), frame.points.end(),
      [](const DopplerPoint& a, const DopplerPoint& b) { return a.time_offset < b.time_offset; });
  if (stats) stats->invalid_points += invalid;
  return frame;
}

void encodeCloud(const LidarFrame& frame, const CloudLayout& layout, bool reflectivity,
                 bool big_endian, ros2::PointCloud2& msg) {
  msg = ros2::PointCloud2();
  // As ros::Time(double) rounds: whole seconds, then the nanoseconds rounded.
  const double sec = std::floor(frame.stamp);
  auto nsec = static_cast<std::int64_t>(std::round((frame.stamp - sec) * 1e9));
  auto whole = static_cast<std::int64_t>(sec) + nsec / 1000000000;
  nsec %= 1000000000;
  msg.header.stamp.sec = static_cast<std::int32_t>(whole);
  msg.header.stamp.nanosec = static_cast<std::uint32_t>(nsec);
  msg.header.frame_id = "aeva";
  struct Slot {
    const FieldSpec* spec;
    std::uint32_t offset;
  };
  std::vector<Slot> slots;
  const FieldSpec refl{"reflectivity", FieldType::kFloat32};
  std::uint32_t offset = 0;
  for (const FieldSpec* s :
       {&layout.x, &layout.y, &layout.z, &layout.intensity, reflectivity ? &refl : nullptr,
        &layout.doppler, &layout.time.field, &layout.line}) {
    if (s == nullptr || s->name.empty()) continue;
    ros2::PointField f;
    f.name = s->name;
    f.offset = offset;
    f.datatype = static_cast<std::uint8_t>(s->type);
    f.count = 1;
    msg.fields.push_back(f);
    slots.push_back({s, offset});
    offset += static_cast<std::uint32_t>(fieldTypeSize(s->type));
  }
  msg.height = 1;
  msg.width = static_cast<std::uint32_t>(frame.points.size());
  msg.point_step = offset;
  msg.row_step = msg.width * msg.point_step;
  msg.is_bigendian = big_endian;
  msg.data.assign(msg.row_step, 0);
  bool dense = true;
  const bool swap = big_endian != kHostBigEndian;
  for (std::size_t i = 0; i < frame.points.size(); ++i) {
    const DopplerPoint& p = frame.points[i];
    std::uint8_t* pt = msg.data.data() + i * msg.point_step;
    dense = dense && p.p_l.allFinite() && std::isfinite(p.doppler) && std::isfinite(p.time_offset);
    for (const Slot& s : slots) {
      double v = 0;
      if (s.spec == &layout.x)
        v = p.p_l.x();
      else if (s.spec == &layout.y)
        v = p.p_l.y();
      else if (s.spec == &layout.z)
        v = p.p_l.z();
      else if (s.spec == &layout.intensity)
        v = p.intensity;
      else if (s.spec == &layout.doppler)
        v = p.doppler / layout.doppler_sign;
      else if (s.spec == &layout.line)
        v = p.line;
      else if (s.spec == &layout.time.field)
        v = (p.time_offset + (layout.time.relative ? 0.0 : frame.stamp)) / layout.time.scale;
      storeAs(v, pt + s.offset, s.spec->type, swap);
    }
  }
  msg.is_dense = dense;
}

}  // namespace freeinit::bags
