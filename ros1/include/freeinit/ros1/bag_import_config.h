// The importer's settings for ROS 1 bags: those of both ROS generations (bags/import_config.h),
// under the names the ROS 1 code has always used.
#pragma once

#include <freeinit/bags/import_config.h>

namespace freeinit::ros1 {

using bags::BagImportConfig;
using bags::CloudLayout;
using bags::DopplerMode;
using bags::FieldSpec;
using bags::FieldType;
using bags::fieldTypeFromName;
using bags::fieldTypeName;
using bags::fieldTypeSize;
using bags::StampSource;
using bags::stampSourceFromName;
using bags::stampSourceName;
using bags::TimeFieldSpec;
using bags::validate;

}  // namespace freeinit::ros1
