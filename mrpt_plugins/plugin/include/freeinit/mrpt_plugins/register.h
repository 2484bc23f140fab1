// Registration of this library's classes with MRPT's run-time type information.
#pragma once

namespace freeinit::mrpt_plugins {

/// Registers CPointsMapDoppler and makes sure the stock MRPT classes our rawlogs use
/// (CObservationIMU, CObservationPointCloud, CSimplePointsMap, ...) are registered too: with
/// Debian's --as-needed linking a library nothing calls into is dropped and its classes vanish.
/// Idempotent; also run automatically when the library is loaded (MRPT plugin loading).
void registerClasses();

/// The name CPointsMapDoppler had in rawlogs written before the layer's namespace became
/// freeinit::mrpt_plugins; registerClasses() registers it as a second name for reading.
inline constexpr const char* kLegacyPointsMapDopplerName = "freeinit::mrpt_glue::CPointsMapDoppler";

}  // namespace freeinit::mrpt_plugins
