// [bag_import]: how to read a ROS recording, as one INI section that freeinit-import-bag and the
// apps reading recordings straight in (freeinit, freeinit-eval-rawlog) share.
#pragma once

#include <freeinit/bags/import_config.h>
#include <freeinit/io/config_section.h>

#include <string>

namespace freeinit::bags {

/// What [bag_import] holds.
struct ImportSettings {
  BagImportConfig bag;
  std::string imu_label = "IMU";      ///< sensorLabel written on the IMU observations
  std::string lidar_label = "LIDAR";  ///< sensorLabel written on the point clouds
  /// The freeinit configuration made for this sensor, relative to the import INI's folder,
  /// suggested after an import ("": the defaults suit it).
  std::string freeinit_config;
};

/// The declaration of [bag_import] (keys, units, accepted values; BagImportConfig validated).
const config::Section<ImportSettings>& importSection();

}  // namespace freeinit::bags
