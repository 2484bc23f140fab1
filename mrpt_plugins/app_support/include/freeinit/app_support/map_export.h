// The static map as an MRPT .simplemap made of stock classes only: a loader without our plugin
// must be able to open it (a plugin class in a simplemap crashes such loaders on use).
#pragma once

#include <freeinit/initial_state.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CObservation.h>

#include <string>
#include <vector>

namespace freeinit::app_support {

/// One keyframe at the world origin holding a CObservationPointCloud with a CSimplePointsMap of
/// the static points (world frame), stamped with the state time. Written atomically.
void writeStaticSimplemap(const std::string& path, const InitResult& result);

/// Saves a simple map to "<path>.tmp" and renames it onto `path`; throws std::runtime_error.
void saveSimplemapAtomically(const std::string& path, const mrpt::maps::CSimpleMap& map);

/// Writes an observations-only rawlog (gz-compressed, MRPT's format) to "<path>.tmp" and renames
/// it onto `path`; throws std::runtime_error.
void writeObservationRawlog(const std::string& path,
                            const std::vector<mrpt::obs::CObservation::Ptr>& observations);

}  // namespace freeinit::app_support
