#include <freeinit/mrpt/CPointsMapDoppler.h>
#include <freeinit/mrpt/register.h>
#include <mrpt/core/initializer.h>
#include <mrpt/maps/registerAllClasses.h>
#include <mrpt/obs/registerAllClasses.h>
#include <mrpt/rtti/CObject.h>

namespace freeinit::mrpt_glue {

void registerClasses() {
  mrpt::obs::registerAllClasses_mrpt_obs();
  mrpt::maps::registerAllClasses_mrpt_maps();
  mrpt::rtti::registerClass(CLASS_ID(CPointsMapDoppler));
}

}  // namespace freeinit::mrpt_glue

// Runs when the shared library is loaded, e.g. by `rawlog-edit -p libfreeinit_mrpt.so`.
MRPT_INITIALIZER(freeinit_mrpt_register_classes) { freeinit::mrpt_glue::registerClasses(); }
