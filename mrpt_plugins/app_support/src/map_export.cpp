#include <freeinit/app_support/map_export.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <mrpt/maps/CPointsMapXYZI.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/serialization/CArchive.h>

namespace freeinit::app_support {

void writeStaticSimplemap(const std::string& path, const InitResult& result) {
  // A stock class with intensity (MRPT has none with Doppler or time: those are in the PLY).
  auto points = mrpt::maps::CPointsMapXYZI::Create();
  points->reserve(result.static_map.size());
  for (const auto& p : result.static_map)
    points->insertPointRGB(p.p_w.x(), p.p_w.y(), p.p_w.z(), p.intensity, 0, 0);
  points->mark_as_modified();

  auto obs = mrpt::obs::CObservationPointCloud::Create();
  obs->sensorLabel = "FREEINIT_STATIC_MAP";
  obs->timestamp = mrpt_plugins::fromUnix(result.state.timestamp);
  obs->pointcloud = points;  // in the world frame: sensorPose stays the identity

  auto sf = mrpt::obs::CSensoryFrame::Create();
  sf->insert(obs);
  mrpt::maps::CSimpleMap map;
  map.insert(mrpt::poses::CPose3DPDFGaussian::Create(), sf);
  saveSimplemapAtomically(path, map);
}

// Through RawlogWriter's gzip stream rather than CSimpleMap::saveToFile / CFileGZOutputStream,
// which in MRPT 2.5.8 ignore a failed final flush (a full disk gives a cut file and success).
void saveSimplemapAtomically(const std::string& path, const mrpt::maps::CSimpleMap& map) {
  mrpt_plugins::RawlogWriter w(path);
  w.writeObject(map);
  w.commit();
}

void writeObservationRawlog(const std::string& path,
                            const std::vector<mrpt::obs::CObservation::Ptr>& observations) {
  mrpt_plugins::RawlogWriter w(path);
  for (const auto& o : observations) w.write(*o);
  w.commit();
}

}  // namespace freeinit::app_support
