// A points map for Doppler (FMCW) LiDAR returns: XYZ plus, per point, the Doppler velocity
// (range rate), the measurement time offset w.r.t. the observation timestamp, the intensity and
// the scan line index. Carried inside a stock mrpt::obs::CObservationPointCloud.
//
// Serialized class name: "freeinit::mrpt_plugins::CPointsMapDoppler". Stock MRPT tools load it only
// with the plugin (`rawlog-edit -p libfreeinit_mrpt_plugins.so`, `RawLogViewer -l ...`).
#pragma once

#include <mrpt/maps/CPointsMap.h>
#include <mrpt/serialization/CSerializable.h>

#include <cstdint>

namespace freeinit::mrpt_plugins {

class CPointsMapDoppler : public mrpt::maps::CPointsMap {
  DEFINE_SERIALIZABLE(CPointsMapDoppler, freeinit::mrpt_plugins)

 public:
  /// Number of fields in getPointAllFields(): [x y z doppler time_offset intensity line].
  static constexpr std::size_t kFieldCount = 7;
  /// Most points a deserialized cloud may declare (2^26, 1.7 GB of fields; real frames hold up to
  /// a few 10^5): more is corrupt data. Fields are read as their bytes arrive, so a corrupt count
  /// below this takes no more memory than the file holds.
  static constexpr std::uint32_t kMaxPoints = std::uint32_t{1} << 26;

  CPointsMapDoppler() = default;
  CPointsMapDoppler(const CPointsMapDoppler& o) : CPointsMap() { impl_copyFrom(o); }
  CPointsMapDoppler& operator=(const CPointsMapDoppler& o) {
    impl_copyFrom(o);
    return *this;
  }
  CPointsMapDoppler& operator=(const CPointsMap& o) {
    impl_copyFrom(o);
    return *this;
  }

  /// Appends one return. x, y, z [m] in the sensor frame; doppler [m/s] range rate;
  /// time_offset [s] w.r.t. the observation timestamp; intensity [-]; line index.
  void insertPointDoppler(float x, float y, float z, float doppler, float time_offset,
                          float intensity, std::uint16_t line);

  float doppler(std::size_t i) const { return doppler_[i]; }
  float timeOffset(std::size_t i) const { return time_offset_[i]; }
  float intensity(std::size_t i) const { return intensity_[i]; }
  std::uint16_t line(std::size_t i) const { return line_[i]; }

  // CPointsMap's pure virtual interface.
  void reserve(size_t n) override;
  void resize(size_t n) override;
  void setSize(size_t n) override;
  void insertPointFast(float x, float y, float z = 0) override;
  void getPointAllFieldsFast(size_t index, std::vector<float>& point_data) const override;
  void setPointAllFieldsFast(size_t index, const std::vector<float>& point_data) override;
  void loadFromRangeScan(
      const mrpt::obs::CObservation2DRangeScan& scan,
      const std::optional<const mrpt::poses::CPose3D>& robotPose = std::nullopt) override;
  void loadFromRangeScan(
      const mrpt::obs::CObservation3DRangeScan& scan,
      const std::optional<const mrpt::poses::CPose3D>& robotPose = std::nullopt) override;

 protected:
  void impl_copyFrom(const mrpt::maps::CPointsMap& obj) override;
  void addFrom_classSpecific(const mrpt::maps::CPointsMap& other, size_t nPreviousPoints,
                             bool filterOutPointsAtZero) override;
  void internal_clear() override;
  void PLY_import_set_vertex_count(size_t n) override { setSize(n); }

 private:
  mrpt::aligned_std_vector<float> doppler_;      ///< [m/s]
  mrpt::aligned_std_vector<float> time_offset_;  ///< [s]
  mrpt::aligned_std_vector<float> intensity_;    ///< [-]
  std::vector<std::uint16_t> line_;
};

}  // namespace freeinit::mrpt_plugins
