// Where IngestItems (ingest.h) come from: a rawlog record (an MRPT object, converted once, straight
// to core types) or a live stream event (already in core types: no MRPT on the way).
#pragma once

#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/ingest.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/net/stream_receiver.h>
#include <mrpt/serialization/CSerializable.h>

#include <functional>
#include <optional>
#include <vector>

namespace freeinit::app_support {

/// Turns the top-level records of a rawlog into items: sensory frames are flattened, actions
/// skipped, IMU samples and clouds with the configured labels converted (accelerations scaled by
/// [input] imu_accel_in_g), any other observation an Other item. Each item carries its
/// observation's sensorPose (the RecordChecker makes the extrinsics of them).
class ObservationDecoder {
 public:
  explicit ObservationDecoder(const InputParams& input);
  void decode(std::size_t record, const mrpt::serialization::CSerializable::Ptr& object,
              std::vector<IngestItem>& out);

 private:
  InputParams input_;
};

/// One record of a rawlog through the offline path: decoded, its items checked in order, each
/// checked item to `take` (a cloud the checker holds for the IMU around it comes out with a later
/// record, or at checker.finish()). `admit` (if given) sees each item before its checks and
/// refuses the items not needed: they pass by unchecked. The record's object is released.
void checkRecord(ObservationDecoder& decoder, RecordChecker& checker,
                 mrpt_plugins::RawlogObject& rec, const std::function<void(CheckedItem&)>& take,
                 const std::function<bool(const IngestItem&)>& admit = {});

/// The whole offline path over a rawlog: every record `reader` gives through checkRecord, in
/// order; `take` gets each checked item, the clouds held for the IMU around them at the end
/// included; `on_record` (if given) sees each record before it is decoded. Errors of the reader
/// propagate.
void forEachCheckedItem(
    mrpt_plugins::RawlogReader& reader, ObservationDecoder& decoder, RecordChecker& checker,
    const std::function<void(CheckedItem&)>& take,
    const std::function<void(const mrpt_plugins::RawlogObject&)>& on_record = {});

/// An Imu or Frame event of the live stream as an item (`record`: the observation number); its
/// points are moved out of the event and sorted by time if they are not; the accelerations are
/// multiplied by `accel_scale` as the rawlog decoder does. Other kinds: nullopt.
std::optional<IngestItem> itemFromStream(net::StreamEvent&& e, std::size_t record,
                                         double accel_scale = 1.0);

}  // namespace freeinit::app_support
