// The static map as an MRPT .simplemap made of stock classes only: a loader without our plugin
// must be able to open it (a plugin class in a simplemap crashes such loaders on use).
#pragma once

#include <freeinit/initial_state.h>

#include <string>

namespace freeinit::mrpt_glue {

/// One keyframe at the world origin holding a CObservationPointCloud with a CSimplePointsMap of
/// the static points (world frame), stamped with the state time. Written atomically.
void writeStaticSimplemap(const std::string& path, const InitResult& result);

}  // namespace freeinit::mrpt_glue
