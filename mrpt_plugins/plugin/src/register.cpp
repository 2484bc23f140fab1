#include <freeinit/mrpt_plugins/points_map_doppler.h>
#include <freeinit/mrpt_plugins/register.h>
#include <mrpt/core/initializer.h>
#include <mrpt/maps/registerAllClasses.h>
#include <mrpt/obs/registerAllClasses.h>
#include <mrpt/rtti/CObject.h>

namespace freeinit::mrpt_plugins {

void registerClasses() {
  mrpt::obs::registerAllClasses_mrpt_obs();
  mrpt::maps::registerAllClasses_mrpt_maps();
  mrpt::rtti::registerClass(CLASS_ID(CPointsMapDoppler));
  // Rawlogs name each object by its class with its namespace. Recordings made before the layer
  // took its folder's name (freeinit::mrpt_glue) keep reading.
  mrpt::rtti::registerClassCustomName(kLegacyPointsMapDopplerName, CLASS_ID(CPointsMapDoppler));
}

}  // namespace freeinit::mrpt_plugins

// Runs when the shared library is loaded, e.g. by `rawlog-edit -p libfreeinit_mrpt_plugins.so`.
MRPT_INITIALIZER(freeinit_mrpt_register_classes) { freeinit::mrpt_plugins::registerClasses(); }
