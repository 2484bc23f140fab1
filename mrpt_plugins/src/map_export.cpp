#include <freeinit/mrpt/conversions.h>
#include <freeinit/mrpt/map_export.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace freeinit::mrpt_glue {

void writeStaticSimplemap(const std::string& path, const InitResult& result) {
  auto points = mrpt::maps::CSimplePointsMap::Create();
  points->reserve(result.static_map.size());
  for (const auto& p : result.static_map) points->insertPointFast(p.p_w.x(), p.p_w.y(), p.p_w.z());
  points->mark_as_modified();

  auto obs = mrpt::obs::CObservationPointCloud::Create();
  obs->sensorLabel = "FREEINIT_STATIC_MAP";
  obs->timestamp = fromUnix(result.state.timestamp);
  obs->pointcloud = points;  // in the world frame: sensorPose stays the identity

  auto sf = mrpt::obs::CSensoryFrame::Create();
  sf->insert(obs);
  mrpt::maps::CSimpleMap map;
  map.insert(mrpt::poses::CPose3DPDFGaussian::Create(), sf);
  saveSimplemapAtomically(path, map);
}

void saveSimplemapAtomically(const std::string& path, const mrpt::maps::CSimpleMap& map) {
  const std::string tmp = path + ".tmp";
  if (!map.saveToFile(tmp)) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot write the simple map");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error(path + ": " + ec.message());
}

void writeObservationRawlog(const std::string& path,
                            const std::vector<mrpt::obs::CObservation::Ptr>& observations) {
  const std::string tmp = path + ".tmp";
  {
    mrpt::io::CFileGZOutputStream f;
    if (!f.open(tmp)) throw std::runtime_error(path + ": cannot create " + tmp);
    auto arch = mrpt::serialization::archiveFrom(f);
    for (const auto& o : observations) arch << *o;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error(path + ": " + ec.message());
}

}  // namespace freeinit::mrpt_glue
