// Registration of this library's classes with MRPT's run-time type information.
#pragma once

namespace freeinit::mrpt_glue {

/// Registers CPointsMapDoppler and makes sure the stock MRPT classes our rawlogs use
/// (CObservationIMU, CObservationPointCloud, CSimplePointsMap, ...) are registered too: with
/// Debian's --as-needed linking a library nothing calls into is dropped and its classes vanish.
/// Idempotent; also run automatically when the library is loaded (MRPT plugin loading).
void registerClasses();

}  // namespace freeinit::mrpt_glue
