#include <freeinit/app_support/ingest_sources.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/stream_conversions.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CSensoryFrame.h>

#include <limits>
#include <utility>

namespace freeinit::app_support {
namespace {

bool labelMatches(const std::string& wanted, const std::string& label) {
  return wanted.empty() || wanted == label;
}

}  // namespace

ObservationDecoder::ObservationDecoder(const InputParams& input) : input_(input) {}

void ObservationDecoder::decode(std::size_t record,
                                const mrpt::serialization::CSerializable::Ptr& object,
                                std::vector<IngestItem>& out) {
  using namespace mrpt::obs;
  auto one = [&](const CObservation::Ptr& obs) {
    if (!obs) return;
    IngestItem it;
    it.record = record;
    it.t = mrpt_plugins::toUnix(obs->timestamp);
    try {
      it.stamp_ns = mrpt_plugins::toUnixNs(obs->timestamp);
    } catch (const std::invalid_argument&) {
      // Outside the wire's range: only the seconds are known exactly enough.
    }
    if (const auto* imu = dynamic_cast<const CObservationIMU*>(obs.get());
        imu != nullptr && labelMatches(input_.imu_label, obs->sensorLabel)) {
      it.kind = IngestItem::Kind::Imu;
      try {
        it.imu = mrpt_plugins::imuFromObservation(*imu, input_.imu_accel_in_g ? kGravity : 1.0);
        it.sensor_pose = mrpt_plugins::extrinsicsFromPose(imu->sensorPose);
      } catch (const std::exception& e) {
        it.problem = e.what();
      }
      it.imu.t = it.t;
    } else if (const auto* pc = dynamic_cast<const CObservationPointCloud*>(obs.get());
               pc != nullptr && labelMatches(input_.lidar_label, obs->sensorLabel)) {
      it.kind = IngestItem::Kind::Frame;
      try {
        it.frame = std::make_shared<LidarFrame>(mrpt_plugins::frameFromObservation(*pc));
      } catch (const std::exception& e) {
        it.problem = e.what();
      }
      it.sensor_pose = mrpt_plugins::extrinsicsFromPose(pc->sensorPose);
    } else {
      it.kind = IngestItem::Kind::Other;
      it.what = std::string(obs->GetRuntimeClass()->className) + " '" + obs->sensorLabel + "'";
    }
    out.push_back(std::move(it));
  };
  if (auto o = std::dynamic_pointer_cast<CObservation>(object)) {
    one(o);
  } else if (auto sf = std::dynamic_pointer_cast<CSensoryFrame>(object)) {
    for (const auto& so : *sf) one(so);
  } else if (!std::dynamic_pointer_cast<CActionCollection>(object)) {
    IngestItem it;
    it.record = record;
    it.t = std::numeric_limits<double>::quiet_NaN();
    it.problem = std::string("unexpected class ") +
                 (object ? object->GetRuntimeClass()->className : "(null)") + " in a rawlog";
    out.push_back(std::move(it));
  }
}

std::optional<IngestItem> itemFromStream(net::StreamEvent&& e, std::size_t record,
                                         double accel_scale) {
  using Kind = net::StreamEvent::Kind;
  IngestItem it;
  it.record = record;
  if (e.kind == Kind::Imu) {
    it.kind = IngestItem::Kind::Imu;
    it.stamp_ns = e.imu.stamp_ns;
    // Through MRPT's 100 ns clock, as the recording stores it: the same seconds offline.
    it.t = mrpt_plugins::toUnix(mrpt_plugins::fromUnixNs(e.imu.stamp_ns));
    it.imu.t = it.t;
    it.imu.gyro = e.imu.gyro;
    it.imu.accel = accel_scale * e.imu.accel;
    return it;
  }
  if (e.kind == Kind::Frame) {
    it.kind = IngestItem::Kind::Frame;
    it.stamp_ns = e.frame.stamp_ns;
    it.t = mrpt_plugins::toUnix(mrpt_plugins::fromUnixNs(e.frame.stamp_ns));
    auto f = std::make_shared<LidarFrame>();
    f->stamp = it.t;
    f->points = std::move(e.frame.points);
    input::sortByTime(*f);
    it.frame = std::move(f);
    it.frame_extrinsics = e.frame.extrinsics;
    return it;
  }
  return std::nullopt;
}

void checkRecord(ObservationDecoder& decoder, RecordChecker& checker,
                 mrpt_plugins::RawlogObject& rec, const std::function<void(CheckedItem&)>& take,
                 const std::function<bool(const IngestItem&)>& admit) {
  std::vector<IngestItem> items;
  decoder.decode(rec.index, rec.object, items);
  rec.object.reset();
  std::vector<CheckedItem> checked;
  for (auto& item : items) {
    if (admit && !admit(item)) continue;
    checked.clear();
    checker.push(std::move(item), checked);
    for (auto& c : checked) take(c);
  }
}

void forEachCheckedItem(mrpt_plugins::RawlogReader& reader, ObservationDecoder& decoder,
                        RecordChecker& checker, const std::function<void(CheckedItem&)>& take,
                        const std::function<void(const mrpt_plugins::RawlogObject&)>& on_record) {
  mrpt_plugins::RawlogObject rec;
  while (reader.next(rec)) {
    if (on_record) on_record(rec);
    checkRecord(decoder, checker, rec, take);
  }
  std::vector<CheckedItem> checked;
  checker.finish(checked);
  for (auto& c : checked) take(c);
}

}  // namespace freeinit::app_support
